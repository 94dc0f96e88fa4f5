"""A text cut again only where an edit changed it is cut as the whole text would be: after
random edits (names typed, lines broken, comments, strings and pragmas opened and closed,
declarations begun and ended) on the demo and on OSCAT, `cut` equals `chunks` every time."""

from __future__ import annotations

import random

from backend.compiler.language.chunks import chunks
from backend.compiler.language.cuts import cut
from backend.engineering.project import demo_project_path
from tests.support.corpus_paths import corpus_dir

TYPED = ("x", "\n", "(*", "*)", "'", '"', "//", "{", "}", "$", ";", "  ", ":= 1;", "END_IF;")
DECLARATIONS = ("\nEND_PROGRAM\n", "\nPROGRAM Z\n", "END_FUNCTION_BLOCK", "\nFUNCTION_BLOCK F\n")


def edit_randomly(text: str, seed: int, edits: int) -> None:
    rng = random.Random(seed)
    cut(text)
    for number in range(edits):
        at = rng.randrange(len(text) + 1)
        if rng.random() < 0.3 and at < len(text):
            edited = text[:at] + text[at + rng.randrange(1, 4) :]
        else:
            edited = text[:at] + rng.choice(TYPED + DECLARATIONS) + text[at:]
        assert cut(edited) == tuple(chunks(edited)), f"edit {number} at {at}"
        if rng.random() < 0.7:  # mostly a text goes on from the edited one
            text = edited


def test_the_demo_after_random_edits_is_cut_as_a_whole() -> None:
    edit_randomly((demo_project_path() / "tank.st").read_text(encoding="utf-8"), 1, 300)


def test_oscat_after_random_edits_is_cut_as_a_whole() -> None:
    folder = corpus_dir("oscat/st")
    for seed, name in enumerate(("BASIC_3.33-12_Time_and_Date.st", "BUILDING_1.0.st")):
        edit_randomly((folder / name).read_text(encoding="utf-8", errors="replace"), seed, 150)
