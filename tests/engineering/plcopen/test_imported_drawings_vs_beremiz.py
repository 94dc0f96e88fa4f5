"""Imported drawings against the ST another tool made of them: each OSCAT chapter's FBD test
program, imported from its PLCopen XML, runs through `padt sim` beside the ST that Beremiz
generated from the same drawing (`oscat/st`, the chapter's `build/plc.st`), over the same
inputs, and every variable of the drawing must equal Beremiz's in every cycle. The four
chapters are the four different drawings among the 24."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from tests.conftest import padt
from tests.support.corpus_paths import corpus_dir

CHAPTERS = (
    "BASIC_3.33-5_Mathematics",
    "BASIC_3.33-9_Arithmetic_Functions",
    "BASIC_3.33-10_Geometric_Functions",
    "BASIC_3.33-12_Time_and_Date",
)
# the values the drawings' inputs take, one per cycle (a REAL input gets them as REALs)
INPUTS = ("7", "-3", "2147483000", "41", "0")
CYCLES = len(INPUTS) + 1


def _beremiz_program(chapter: str) -> str:
    """Beremiz's ST of the chapter's program0, renamed so both can run side by side."""
    text = (corpus_dir("oscat/st") / f"{chapter}.st").read_text()
    found = re.search(r"^PROGRAM program0\b.*?^END_PROGRAM", text, re.M | re.S)
    assert found is not None, chapter
    return found.group(0).replace("PROGRAM program0", "PROGRAM program0_beremiz", 1)


def _inputs(drawn: str) -> dict[str, str]:
    """The variables the drawing reads and nothing writes, with their types."""
    declared = dict(re.findall(r"^\s+(LocalVar\d+) : (\w+);", drawn, re.M))
    read = set(re.findall(r": IN (LocalVar\d+)", drawn))
    written = set(re.findall(r": OUT (LocalVar\d+)", drawn))
    return {name: declared[name] for name in sorted(read - written)}


@pytest.mark.parametrize("chapter", CHAPTERS)
def test_an_imported_drawing_runs_as_the_st_beremiz_made_of_it(
    tmp_path: Path, chapter: str
) -> None:
    folder = tmp_path / "project"
    xml = corpus_dir("oscat/plcopen") / f"{chapter}.xml"
    imported = padt("import", str(xml), "-o", str(folder))
    assert imported.returncode == 0, imported.stderr
    drawn = (folder / "program0.st").read_text()
    assert "\nFBD\n" in drawn
    (folder / "program0_beremiz.st").write_text(_beremiz_program(chapter))
    toml = (folder / "padt.toml").read_text()
    toml += '\n[[resource.program]]\nname = "beremiz"\npou = "program0_beremiz"\nid = 2\n'
    (folder / "padt.toml").write_text(toml)
    settings = []
    for cycle, value in enumerate(INPUTS, start=1):
        for name, type_name in _inputs(drawn).items():
            literal = f"{value}.5" if type_name in ("REAL", "LREAL") else value
            for program in ("instance0", "beremiz"):
                settings += ["--set", f"{program}.{name}={literal}@{cycle}"]
    run = padt("sim", str(folder), "--cycles", str(CYCLES), "--cycle-ms", "20", *settings)
    assert run.returncode == 0, run.stderr
    cycles = [json.loads(line)["values"] for line in run.stdout.splitlines()]
    assert len(cycles) == CYCLES
    compared = 0
    for cycle, values in enumerate(cycles, start=1):
        for path, value in values.items():
            if not path.startswith("instance0.LocalVar"):
                continue
            theirs = values[path.replace("instance0.", "beremiz.", 1)]
            assert value == theirs, f"{chapter}, cycle {cycle}: {path} {value} != {theirs}"
            compared += 1
    assert compared >= 3 * CYCLES
