"""No source can kill or stall the compiler: pathological inputs, generated here, each end
in diagnostics, in a child process whose address space is capped at 1 GiB (so a compile
that needs more fails the test) and within the 10 s the hardening issue allows.
"""

from __future__ import annotations

import json
import re
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

from tests.conftest import REPO, padt

MEMORY_CAP = 1 << 30
SECONDS = 10

# The child caps its own address space before it imports the compiler, then compiles each
# project it reads (JSON on stdin: a list of projects, each a list of [name, text] files)
# and prints one JSON line per project.
CHILD = f"""
import json, resource, sys, time
resource.setrlimit(resource.RLIMIT_AS, ({MEMORY_CAP}, {MEMORY_CAP}))
from backend.compiler.pipeline import compile_sources
from backend.compiler.source import SourceFile
for files in json.load(sys.stdin):
    start = time.monotonic()
    result = compile_sources([SourceFile(name, text) for name, text in files])
    seconds = time.monotonic() - start
    print(json.dumps({{"seconds": seconds, "diagnostics": [str(d) for d in result.diagnostics]}}))
"""


@dataclass(frozen=True)
class Outcome:
    seconds: float
    diagnostics: list[str]

    def codes(self) -> set[str]:
        return {d.rsplit("[", 1)[-1].rstrip("]") for d in self.diagnostics}


Project = str | list[tuple[str, str]]  # one file, big.st, or named files


def compile_capped(*projects: Project) -> list[Outcome]:
    """Compile each project in a capped child; any traceback or crash fails the test, and
    so does a compile of 10 s or more."""
    files = [[("big.st", p)] if isinstance(p, str) else p for p in projects]
    run = subprocess.run(
        [sys.executable, "-c", CHILD],
        input=json.dumps(files),
        capture_output=True,
        text=True,
        cwd=REPO,
        timeout=120,
    )
    assert run.returncode == 0 and "Traceback" not in run.stderr, run.stderr[-2000:]
    outcomes = [Outcome(**json.loads(line)) for line in run.stdout.splitlines()]
    assert len(outcomes) == len(projects)
    for outcome in outcomes:
        assert outcome.seconds < SECONDS, outcome
    return outcomes


def refused_with(code: str, *projects: Project) -> None:
    """Each project compiles to an error with `code`, at a `file:line:col`."""
    for outcome in compile_capped(*projects):
        found = [d for d in outcome.diagnostics if d.endswith(f" [{code}]")]
        assert found and ": error: " in found[0], outcome.diagnostics[:5]
        assert re.match(r"[^:]+:[1-9][0-9]*:[1-9][0-9]*: ", found[0]), found[0]


def program(body: str, declarations: str = "x : DINT;") -> str:
    return f"PROGRAM P\nVAR {declarations} END_VAR\n{body}\nEND_PROGRAM\n"


# ---- source size --------------------------------------------------------------------------

MiB = 1 << 20


def comment(size: int, opening: str = "(*", closing: str = "*)") -> str:
    """A comment of exactly `size` bytes, in lines of 64."""
    inner = size - len(opening) - len(closing)
    return opening + ("x" * 63 + "\n") * (inner // 64) + "x" * (inner % 64) + closing


def test_comments_cost_only_their_bytes() -> None:
    """The largest project of comments: four files of 4 MiB, each kind of comment."""
    files = [
        (f"part{i}.st", comment(4 * MiB - 100, opening, closing))
        for i, (opening, closing) in enumerate((("(*", "*)"), ("/*", "*/"), ("{{", "}}")))
    ]
    (outcome,) = compile_capped([*files, ("main.st", program("x := 1;"))])
    assert not [d for d in outcome.diagnostics if ": error: " in d], outcome.diagnostics


def test_a_file_larger_than_4_mib_is_refused() -> None:
    refused_with("E0707", comment(4 * MiB + 1) + program("x := 1;"), comment(50 * MiB))


def test_a_project_beyond_16_mib_2000_files_or_200000_tokens_is_refused() -> None:
    refused_with(
        "E0708",
        [(f"part{i}.st", comment(4 * MiB - 100)) for i in range(5)],
        [(f"pou{i}.st", f"FUNCTION F{i} : INT END_FUNCTION\n") for i in range(2_001)],
        program("x := x + 1;\n" * 40_000),
        program(";" * 1_000_000),
        [(f"part{i}.st", program("x := x + 1;\n" * 20_000)) for i in range(3)],
    )


def test_a_project_just_within_its_token_limit_compiles_in_time() -> None:
    """The densest source the limits allow, close to 200,000 tokens."""
    body = "x := x + 1;\n" * 33_000  # 6 tokens each
    (outcome,) = compile_capped(program(body))
    assert not outcome.diagnostics, outcome.diagnostics[:3]


# ---- literals ------------------------------------------------------------------------------


def test_literals_beyond_their_length_are_refused() -> None:
    refused_with(
        "E0709",
        program("s := '" + "$$" * 1_000_000 + "';", "s : STRING;"),  # lexed in little memory
        program('s := "' + "x" * 65_536 + '";', "s : WSTRING;"),
        program("s := STRING#'" + "x" * 65_536 + "';", "s : STRING;"),
        program("x := " + "9" * 100_000 + ";", "x : LINT;"),
        program("x := 16#" + "F" * 5_000 + ";", "x : LWORD;"),
        program("x := 1." + "9" * 1_000_000 + ";", "x : LREAL;"),
        program("x := T#" + "9" * 100_000 + "ms;", "x : TIME;"),
        program("x := D#" + "1" * 2_000 + "-1-1;", "x : DATE;"),
    )


def test_literals_within_their_length_compile() -> None:
    (outcome,) = compile_capped(
        program(
            "s := '" + "x" * 65_535 + "'; x := " + "1" * 300 + " + 0.5;", "s : STRING; x : LREAL;"
        )
    )
    assert not outcome.diagnostics, outcome.diagnostics


def test_an_integer_beyond_lreal_is_an_invalid_literal() -> None:
    refused_with(
        "E0003",
        program("x := 1" + "0" * 400 + " + 1.0;", "x : LREAL;"),
        program("x := REAL#1" + "0" * 400 + ";", "x : REAL;"),
        program("x := 16#1" + "0" * 256 + ";", "x : LREAL;"),
    )


# ---- data ----------------------------------------------------------------------------------


def chain(kind: str, length: int) -> str:
    """Function blocks, structures or type names, each holding or naming the next."""
    if kind == "blocks":
        return (
            "".join(
                f"FUNCTION_BLOCK F{i}\nVAR inner : F{i + 1}; END_VAR\nEND_FUNCTION_BLOCK\n"
                for i in range(length)
            )
            + f"FUNCTION_BLOCK F{length} END_FUNCTION_BLOCK\n"
            + program("f();", "f : F0;")
        )
    if kind == "structures":
        members = "".join(f"S{i} : STRUCT m : S{i + 1}; END_STRUCT;\n" for i in range(length))
        return f"TYPE\n{members}S{length} : STRUCT m : INT; END_STRUCT;\nEND_TYPE\n" + program(
            "s.m.m.m := s.m.m.m;", "s : S0;"
        )
    names = "".join(f"A{i} : A{i + 1};\n" for i in range(length))
    return f"TYPE\n{names}A{length} : INT;\nEND_TYPE\n" + program("a := 1;", "a : A0;")


def test_data_nested_beyond_32_levels_is_refused() -> None:
    refused_with(
        "E0711",
        program("", "a : " + "ARRAY[0..1] OF " * 25_000 + "BOOL;"),
        chain("blocks", 15_000),
        chain("structures", 20_000),
        chain("names", 40_000),
        "TYPE A : " + "ARRAY[0..1] OF " * 20 + "BOOL; END_TYPE\n"
        "TYPE B : " + "ARRAY[0..1] OF " * 20 + "A; END_TYPE\n" + program("", "b : B;"),
    )


def test_data_nested_32_levels_deep_compiles() -> None:
    # the program is a level too
    outcomes = compile_capped(chain("blocks", 30), chain("structures", 30), chain("names", 31))
    for outcome in outcomes:
        assert not [d for d in outcome.diagnostics if ": error: " in d], outcome.diagnostics


def test_a_block_holding_itself_through_a_structure_is_still_refused() -> None:
    refused_with(
        "E0109",
        "TYPE S : STRUCT f : F; END_STRUCT; END_TYPE\n"
        "FUNCTION_BLOCK F\nVAR s : S; END_VAR\nEND_FUNCTION_BLOCK\n" + program("", "f : F;"),
    )


def test_arrays_beyond_a_million_values_are_refused() -> None:
    refused_with(
        "E0710",
        program("", "a : ARRAY[0..999999999] OF LREAL;"),
        program("", "a : ARRAY[1..1000, 1..1001] OF BOOL;"),
        program("", "a : ARRAY[1..1000] OF ARRAY[1..1001] OF BOOL;"),
        program("", "a : ARRAY[1..100] OF STRING[1000000];"),
        "TYPE S : STRUCT a, b : ARRAY[1..1000] OF INT; END_STRUCT; END_TYPE\n"
        + program("", "a : ARRAY[1..501] OF S;"),
    )


def test_a_resource_or_a_call_beyond_a_million_values_is_refused() -> None:
    blocks = (
        "FUNCTION_BLOCK A\nVAR x : ARRAY[1..1000] OF LREAL; END_VAR\nEND_FUNCTION_BLOCK\n"
        "FUNCTION_BLOCK B\nVAR a : ARRAY[1..1000] OF A; END_VAR\nEND_FUNCTION_BLOCK\n"
    )
    refused_with(
        "E0712",
        blocks + program("", "b : ARRAY[1..1000] OF B;"),
        program("", "a, b : ARRAY[1..600000] OF LREAL;"),
        "VAR_GLOBAL g : ARRAY[1..400000] OF LREAL; END_VAR\n"
        "PROGRAM P1\ng[1] := 1.0;\nEND_PROGRAM\nPROGRAM P2\nEND_PROGRAM\n",
        "FUNCTION F : INT\nVAR a, b : ARRAY[1..600000] OF LREAL; END_VAR\nF := 1;\nEND_FUNCTION\n"
        + program("x := F();"),
    )


def test_a_million_values_compile() -> None:
    (outcome,) = compile_capped(program("a[1] := 1.0;", "a : ARRAY[1..999999] OF LREAL;"))
    assert not outcome.diagnostics, outcome.diagnostics


def test_padt_sim_refuses_an_array_of_a_billion_values(tmp_path: Path) -> None:
    source = tmp_path / "huge.st"
    source.write_text(program("a[0] := 1.0;", "a : ARRAY[0..999999999] OF LREAL;"))
    run = padt("sim", str(source), "--cycles", "1")
    assert run.returncode == 1 and "Traceback" not in run.stderr, run.stderr
    assert "[E0710]" in run.stdout + run.stderr
