"""The language services' analysis is incremental and still exact: a file parsed from the
cached parses of its declarations is the file parsed whole, and after any edit the
diagnostics of a `LanguageProject` are those of `analyse` on the same texts."""

from __future__ import annotations

import functools
import random
import re
import threading
from pathlib import Path

import pytest

from backend.compiler.ast import SourceUnit
from backend.compiler.diagnostics import CompileError, Diagnostic
from backend.compiler.language import parse_cache
from backend.compiler.language.analysis import analyse
from backend.compiler.language.chunks import chunks
from backend.compiler.language.language_project import LanguageProject
from backend.compiler.language.parse_cache import parse_file
from backend.compiler.limits import MAX_FILE_BYTES
from backend.compiler.parse import parse_source
from backend.engineering.project import demo_project_path
from tests.support.corpus_paths import corpus_dir

DEMO = demo_project_path()


def demo_texts() -> dict[str, str]:
    return {path.name: path.read_text(encoding="utf-8") for path in sorted(DEMO.glob("*.st"))}


def oscat_text(chapter: str) -> str:
    return (corpus_dir("oscat/st") / chapter).read_text(encoding="utf-8", errors="replace")


def assert_parses_as_whole(name: str, text: str) -> None:
    assert "".join(chunk.text for chunk in chunks(text)) == text
    expected: tuple[SourceUnit | None, tuple[Diagnostic, ...]]
    try:
        whole = parse_source(name, text)
        expected = (whole, whole.warnings)
    except CompileError as exc:
        expected = (None, tuple(exc.diagnostics))
    incremental = parse_file(name, text)
    assert (incremental.unit, incremental.diagnostics) == expected


def test_the_demo_parsed_by_declarations_is_the_demo_parsed_whole() -> None:
    for name, text in demo_texts().items():
        assert len(chunks(text)) > 1
        assert_parses_as_whole(name, text)


def test_oscat_parsed_by_declarations_is_oscat_parsed_whole() -> None:
    folder = corpus_dir("oscat/st")
    for path in sorted(folder.glob("*.st")):
        text = path.read_text(encoding="utf-8", errors="replace")
        assert len(chunks(text)) > 5, path.name
        assert_parses_as_whole(path.name, text)


def test_keywords_in_comments_strings_and_blocks_cut_nothing() -> None:
    text = (
        "(* FUNCTION_BLOCK Hidden\nTYPE *)\n"
        "PROGRAM Main\nVAR_GLOBAL g : INT; END_VAR\nVAR s : STRING := '\nTYPE'; END_VAR\n"
        "// FUNCTION F\ns := 'x';\nEND_PROGRAM\n"
        "  TYPE T : INT; END_TYPE FUNCTION F : INT\nF := 1;\nEND_FUNCTION\n"
        "FUNCTION_BLOCK B\nEND_FUNCTION_BLOCK\nMETHOD M\nEND_METHOD\n"
    )
    starts = ["(*", "PROGRAM", "TYPE", "FUNCTION_BLOCK"]
    assert [c.text.split(None, 1)[0] for c in chunks(text)] == starts
    assert [c.line_offset for c in chunks(text)] == [0, 2, 9, 12]
    assert_parses_as_whole("main.st", text)


EDITS = ["x", ";", " ", "\n", "(*", "*)", "'", "END_IF;", "FUNCTION F2 : INT\n", "END_VAR\n"]


# edits that keep the text parsing: a name assigned changed (undeclared), a type changed
# in a declaration (the POUs that use it check anew), a line repeated (declared twice)
SEMANTIC = [
    (re.compile(r"^(\s*)(\w+)(\s*:=)", re.MULTILINE), r"\1\2x\3"),
    (re.compile(r"\bINT\b"), "REAL"),
    (re.compile(r"\bBOOL\b"), "INT"),
    (re.compile(r"^(.*;[ \t]*\n)", re.MULTILINE), r"\1\1"),
]


def random_edit(rng: random.Random, text: str) -> str:
    """Text typed in, or a stretch deleted, somewhere: most of these leave a syntax error;
    or an edit that keeps the text parsing."""
    if rng.random() < 0.5:
        pattern, replacement = rng.choice(SEMANTIC)
        found = list(pattern.finditer(text))
        if found:
            match = rng.choice(found)
            return text[: match.start()] + match.expand(replacement) + text[match.end() :]
    at = rng.randrange(len(text) + 1)
    if rng.random() < 0.3:
        return text[:at] + text[at + rng.randrange(1, 40) :]
    return text[:at] + rng.choice(EDITS) + text[at:]


def assert_edits_keep_diagnostics_exact(texts: dict[str, str], edits: int, seed: int) -> None:
    rng = random.Random(seed)
    project = LanguageProject(texts)
    current = dict(texts)
    for _ in range(edits):
        file = rng.choice(sorted(current))
        # an edit kept, or undone as one does after a typo
        edited = random_edit(rng, current[file])
        project.set_text(file, edited)
        if rng.random() < 0.5:
            current[file] = edited
        else:
            project.diagnostics(file)
            project.set_text(file, current[file])
        expected = analyse({**current})
        got = project.analysis()
        assert got.diagnostics == expected.diagnostics
        assert got.units == expected.units
        for name in current:
            assert project.diagnostics(name) == sorted(
                d for d in expected.diagnostics if d.file == name
            )


def test_random_edits_of_the_demo_give_the_diagnostics_of_a_full_analysis() -> None:
    texts = demo_texts()
    texts["more.st"] = (
        "FUNCTION Scale : INT\nVAR_INPUT a : INT; END_VAR\nScale := a * 2;\nEND_FUNCTION\n"
        "TYPE Point : STRUCT x : INT; y : BOOL; END_STRUCT; END_TYPE\n"
        "VAR_GLOBAL origin : Point; END_VAR\n"
        "FUNCTION_BLOCK Extra\nVAR_INPUT a : INT; END_VAR\nVAR b : BOOL; END_VAR\n"
        "VAR_OUTPUT p : Point; END_VAR\nb := Scale(a) > 3;\nEND_FUNCTION_BLOCK\n"
    )
    # a chain of declarations: User reads a member of a type through Extra and a global
    texts["uses.st"] = (
        "PROGRAM User\nVAR e : Extra; n : INT; END_VAR\ne(a := n);\nn := Scale(n);\n"
        "n := e.p.x + origin.x;\ne.b := e.p.y;\nEND_PROGRAM\n"
    )
    # CODESYS's qualified names and enumeration values, which resolve rewrites
    texts["codesys.st"] = (
        "TYPE Color : (Red, Green); END_TYPE\n"
        "PROGRAM Paint\nVAR c : Color; t : Tc2_Standard.TON; END_VAR\n"
        "c := Color.Red;\nt(IN := c = Color.Green, PT := T#1s);\nEND_PROGRAM\n"
    )
    assert_edits_keep_diagnostics_exact(texts, edits=60, seed=31)


CHAIN = {
    "types.st": "TYPE Point : STRUCT x : INT; y : BOOL; END_STRUCT; END_TYPE\n"
    "TYPE Mode : (Off, Auto); END_TYPE\n",
    "globals.st": "VAR_GLOBAL origin : Point; END_VAR\n",
    "block.st": "FUNCTION_BLOCK Extra\nVAR_OUTPUT p : Point; END_VAR\np.x := 1;\n"
    "END_FUNCTION_BLOCK\n",
    "user.st": "PROGRAM User\nVAR e : Extra; n : INT; b : BOOL; END_VAR\ne();\n"
    "n := e.p.x + origin.x;\nb := e.p.y;\nb := Auto <> Off;\nEND_PROGRAM\n",
}


@pytest.mark.parametrize(
    ("file", "old", "new"),
    [
        ("types.st", "x : INT", "x : BOOL"),  # a member, used through a block and a global
        ("types.st", "y : BOOL", "z : BOOL"),
        ("types.st", "(Off, Auto)", "(Off, Manual)"),  # a value, used without its type
        ("globals.st", "origin : Point", "origin : INT"),
        ("block.st", "p : Point", "p : INT"),
        ("block.st", "FUNCTION_BLOCK Extra", "FUNCTION_BLOCK Other"),
    ],
)
def test_a_declaration_changed_checks_again_what_uses_it(file: str, old: str, new: str) -> None:
    project = LanguageProject(CHAIN)
    assert project.analysis().diagnostics == analyse(CHAIN).diagnostics == ()
    changed = {**CHAIN, file: CHAIN[file].replace(old, new)}
    project.set_text(file, changed[file])
    expected = analyse(changed).diagnostics
    assert [d for d in expected if d.file == "user.st"], "the edit makes an error in user.st"
    assert project.analysis().diagnostics == expected
    project.set_text(file, CHAIN[file])
    assert project.analysis().diagnostics == ()


@pytest.mark.parametrize(
    "chapter", ["BASIC_3.33-16_Logic_Modules.st", "BASIC_3.33-12_Time_and_Date.st"]
)
def test_random_edits_of_oscat_give_the_diagnostics_of_a_full_analysis(chapter: str) -> None:
    assert_edits_keep_diagnostics_exact({chapter: oscat_text(chapter)}, edits=16, seed=7)


def test_a_second_project_on_the_same_texts_shares_the_first_ones_parses() -> None:
    texts = demo_texts()
    first = LanguageProject(texts).analysis()
    second = LanguageProject(texts).analysis()
    user_units = len(texts)
    for one, other in zip(first.units[:user_units], second.units[:user_units], strict=True):
        assert all(a is b for a, b in zip(one.pous, other.pous, strict=True))


def test_a_keystroke_reparses_only_the_declaration_it_changed() -> None:
    text = oscat_text("BASIC_3.33-16_Logic_Modules.st")
    project = LanguageProject({"logic.st": text})
    before = project.analysis().units[0].pous
    at = text.index("END_FUNCTION", len(text) // 2)
    project.set_text("logic.st", text[:at] + " " + text[at:])
    after = project.analysis().units[0].pous
    changed = [a.name for a, b in zip(before, after, strict=True) if a is not b]
    assert len(changed) == 1
    # a line more above a declaration moves it down, with the parse it had
    project.set_text("logic.st", "\n" + text)
    moved = project.analysis().units[0].pous
    assert [p.pos.line for p in moved] == [p.pos.line + 1 for p in before]


def test_threads_editing_at_once_leave_the_analysis_of_the_last_texts() -> None:
    texts = demo_texts()
    project = LanguageProject(texts)
    (name,) = texts

    def type_in(mark: str) -> None:
        for n in range(5):
            project.set_text(name, texts[name] + f"\n(* {mark} {n} *)\n")
            project.diagnostics(name)

    workers = [threading.Thread(target=type_in, args=(str(i),)) for i in range(4)]
    for worker in workers:
        worker.start()
    for worker in workers:
        worker.join(timeout=300)
    assert not any(worker.is_alive() for worker in workers)
    final = project.texts()
    assert project.analysis().diagnostics == analyse(final).diagnostics


def test_a_file_removed_is_gone_from_the_analysis(tmp_path: Path) -> None:
    texts = demo_texts()
    texts["broken.st"] = "PROGRAM Broken\nx := ;\nEND_PROGRAM\n"
    project = LanguageProject(texts)
    assert [d.code for d in project.diagnostics("broken.st")] == ["E0001"]
    project.remove("broken.st")
    assert project.diagnostics("broken.st") == []
    assert "broken.st" not in project.analysis().texts


@pytest.mark.parametrize(
    "hostile",
    [
        "(*" * 100_000,  # comments never closed: the cut reads the text once
        "PROGRAM P\n" + "{" * 100_000,
        "PROGRAM P\nVAR s : STRING := '" + "$'" * 100_000,
        "FUNCTION_BLOCK B\n" * 20_000,  # declarations never ended
        "PROGRAM P\n" + "x := 1;\n" * 10 + "\x00\udcff" + "END_PROGRAM\n",
    ],
    ids=["comments", "pragmas", "string", "unended", "bytes"],
)
def test_hostile_texts_get_the_diagnostics_of_a_full_analysis(hostile: str) -> None:
    project = LanguageProject({"hostile.st": hostile})
    assert project.analysis().diagnostics == analyse({"hostile.st": hostile}).diagnostics
    assert project.diagnostics("hostile.st")


def test_a_file_beyond_the_size_limit_is_refused_as_the_compiler_refuses_it() -> None:
    huge = "PROGRAM P\n" + "(* filler *)\n" * (MAX_FILE_BYTES // 13 + 1) + "END_PROGRAM\n"
    project = LanguageProject({"huge.st": huge, **demo_texts()})
    expected = analyse({"huge.st": huge, **demo_texts()}).diagnostics
    assert project.analysis().diagnostics == expected
    assert [d.code for d in project.diagnostics("huge.st")] == ["E0707"]


def test_the_shared_parses_are_bounded_least_recently_used_first_out() -> None:
    cache: parse_cache._SizedCache[str, str] = parse_cache._SizedCache(10)
    made: list[str] = []

    def make(text: str) -> str:
        made.append(text)
        return text.upper()

    for text in ("aaaa", "bbbb", "aaaa", "cccc", "aaaa", "bbbb"):
        assert cache.get(text, len(text), functools.partial(make, text)) == text.upper()
    # "bbbb" was the least recently used when "cccc" came, so it was made again
    assert made == ["aaaa", "bbbb", "cccc", "bbbb"]
    # a text larger than the whole cache is parsed, and kept by nobody
    for _ in range(2):
        assert cache.get("x" * 11, 11, functools.partial(make, "x" * 11)) == "X" * 11
    assert made[-2:] == ["x" * 11] * 2
    assert cache.get("bbbb", 4, functools.partial(make, "bbbb")) == "BBBB"
    assert made[-1] == "x" * 11
