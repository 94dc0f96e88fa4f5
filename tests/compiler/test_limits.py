"""No source can kill or stall the compiler: pathological inputs, generated here, each end
in diagnostics, in a child process whose address space is capped at 1 GiB (so a compile
that needs more fails the test) and within the 10 s the hardening issue allows, counted as
the child's CPU time: what a pathological input costs, not how busy the shared machine is.
"""

from __future__ import annotations

import contextlib
import json
import os
import re
import select
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest

from backend.compiler import pipeline
from backend.compiler.source import SourceFile
from backend.engineering.project import ProjectError, load_project
from tests.conftest import REPO, padt

MEMORY_CAP = 1 << 30
SECONDS = 10

# The server imports the compiler once (0.4 s of CPU each child paid again) and forks a
# child for each request (a line of JSON on stdin: a list of projects, each a list of
# [name, text] files). The child caps its own address space, then compiles each project and
# prints one JSON line per project; the server then prints its exit code. A child starts
# with nothing compiled, as a child started afresh did.
SERVER = f"""
import json, os, resource, sys, time, traceback
from backend.compiler.pipeline import compile_sources
from backend.compiler.source import SourceFile
for request in sys.stdin:
    pid = os.fork()
    if pid == 0:
        code = 0
        try:
            resource.setrlimit(resource.RLIMIT_AS, ({MEMORY_CAP}, {MEMORY_CAP}))
            for files in json.loads(request):
                start = time.process_time()
                result = compile_sources([SourceFile(name, text) for name, text in files])
                seconds = time.process_time() - start
                diagnostics = [str(d) for d in result.diagnostics]
                print(json.dumps({{"seconds": seconds, "diagnostics": diagnostics}}))
        except BaseException:
            traceback.print_exc()
            code = 1
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(code)
    _, status = os.waitpid(pid, 0)
    # on a line of its own, whatever the child left unfinished
    print("\\n" + json.dumps({{"exit": os.waitstatus_to_exitcode(status)}}), flush=True)
"""


@dataclass(frozen=True)
class Outcome:
    seconds: float
    diagnostics: list[str]

    def codes(self) -> set[str]:
        return {d.rsplit("[", 1)[-1].rstrip("]") for d in self.diagnostics}


class CompileServer:
    """The server process, in a process group of its own with its children; its stderr (and
    theirs) goes to a file, read after each request for what that request's child wrote."""

    def __init__(self, stderr: Path) -> None:
        self.stderr_path = stderr
        self._stderr = stderr.open("wb")
        self._read = 0  # of the stderr file
        self.process: subprocess.Popen[bytes] | None = None

    def run(self, files: list[list[tuple[str, str]]], timeout: float) -> tuple[int, str, str]:
        """The child's exit code, stdout and stderr for one request."""
        if self.process is None:
            self.process = subprocess.Popen(
                [sys.executable, "-c", SERVER],
                stdin=subprocess.PIPE,
                stdout=subprocess.PIPE,
                stderr=self._stderr,
                cwd=REPO,
                start_new_session=True,
            )
        assert self.process.stdin is not None and self.process.stdout is not None
        self.process.stdin.write(json.dumps(files).encode() + b"\n")
        self.process.stdin.flush()
        lines: list[bytes] = []
        deadline = time.monotonic() + timeout
        descriptor = self.process.stdout.fileno()
        buffered = b""
        while not (lines and lines[-1].startswith(b'{"exit": ')):
            left = deadline - time.monotonic()
            if left <= 0:
                self.stop()  # the child too, as subprocess.run's timeout kills it
                raise subprocess.TimeoutExpired(SERVER, timeout)
            if not select.select([descriptor], [], [], left)[0]:
                continue
            chunk = os.read(descriptor, 1 << 16)
            if not chunk:
                self.stop()
                raise AssertionError(f"the compile server ended: {self._new_stderr()}")
            buffered += chunk
            *complete, buffered = buffered.split(b"\n")
            lines += complete
        assert not buffered
        code = json.loads(lines[-1])["exit"]
        stdout = b"".join(line + b"\n" for line in lines[:-1] if line).decode()
        return code, stdout, self._new_stderr()

    def _new_stderr(self) -> str:
        with self.stderr_path.open("rb") as written:
            written.seek(self._read)
            text = written.read()
        self._read += len(text)
        return text.decode(errors="replace")

    def stop(self) -> None:
        """The server and any child of it ended (the next request starts another)."""
        if self.process is None:
            return
        process, self.process = self.process, None
        for pipe in (process.stdin, process.stdout):
            if pipe is not None:
                pipe.close()
        with contextlib.suppress(ProcessLookupError):
            os.killpg(process.pid, signal.SIGKILL)
        process.wait()

    def close(self) -> None:
        self.stop()
        self._stderr.close()


_server: CompileServer | None = None


@pytest.fixture(autouse=True, scope="module")
def compile_server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[CompileServer]:
    global _server
    server = _server = CompileServer(tmp_path_factory.mktemp("limits") / "stderr")
    try:
        yield server
    finally:
        _server = None
        server.close()


Project = str | list[tuple[str, str]]  # one file, big.st, or named files


def compile_capped(*projects: Project, seconds: float = SECONDS) -> list[Outcome]:
    """Compile each project in a capped child; any traceback or crash fails the test, and
    so does a compile of `seconds` of CPU or more."""
    files = [[("big.st", p)] if isinstance(p, str) else p for p in projects]
    assert _server is not None
    returncode, stdout, stderr = _server.run(files, timeout=120)
    assert returncode == 0 and "Traceback" not in stderr, stderr[-2000:]
    outcomes = [Outcome(**json.loads(line)) for line in stdout.splitlines()]
    assert len(outcomes) == len(projects)
    for outcome in outcomes:
        assert outcome.seconds < seconds, outcome
    return outcomes


def refused_with(code: str, *projects: Project, seconds: float = SECONDS) -> None:
    """Each project compiles to an error with `code`, at a `file:line:col`."""
    for outcome in compile_capped(*projects, seconds=seconds):
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


def test_a_project_beyond_16_mib_2000_files_or_150000_tokens_is_refused() -> None:
    refused_with(
        "E0708",
        [(f"part{i}.st", comment(4 * MiB - 100)) for i in range(5)],
        [(f"pou{i}.st", f"FUNCTION F{i} : INT END_FUNCTION\n") for i in range(2_001)],
        program(";" * 1_000_000),
    )
    # what the refusal at the token limit costs is the parse up to the limit: the cost of
    # the largest project allowed, which grows with the CPU's load as the test below says
    statements = [(f"part{i}.st", program("x := x + 1;\n" * 20_000)) for i in range(3)]
    refused_with("E0708", statements, seconds=3 * SECONDS)


def test_a_project_just_within_its_token_limit_compiles_in_time() -> None:
    """The densest source the limits allow: close to 150,000 tokens of statements, in ten
    programs (in one, it would be more code than a unit may have). It takes about 6 s of
    CPU on the development machine, and CPU time grows when another process shares the
    core: so what is checked is that its cost grows linearly with its size (a fifth of it
    first, in the same child), under a cap three times the budget."""
    body = "x := x + 1;\n" * 2_460  # 6 tokens each

    def programs(count: int) -> str:
        return "".join(
            f"PROGRAM P{i}\nVAR x : DINT; END_VAR\n{body}END_PROGRAM\n" for i in range(count)
        )

    fifth, whole = compile_capped(programs(2), programs(10), seconds=3 * SECONDS)
    assert not whole.diagnostics, whole.diagnostics[:3]
    assert whole.seconds < 7.5 * fifth.seconds, (fifth, whole)  # linear: 5x


# ---- nesting ------------------------------------------------------------------------------

DEEP = 10_000  # far beyond every nesting limit, and beyond what recursion would survive


def right_deep(opening: str, innermost: str, closing: str, depth: int = DEEP) -> str:
    return opening * depth + innermost + closing * depth


def test_expressions_of_every_kind_nested_too_deep_are_refused() -> None:
    left_deep = " + ".join(["1"] * DEEP)
    refused_with(
        "E0706",
        program("x := " + right_deep("- ", "1", "") + ";"),
        program("b := " + right_deep("NOT ", "TRUE", "") + ";", "b : BOOL;"),
        program(f"x := {left_deep};"),
        program("x := " + right_deep("1 + (", "1", ")") + ";"),
        program("x := " + " * ".join(["1"] * DEEP) + " MOD 2 ** 1;"),
        program("b := " + " AND ".join(["b"] * DEEP) + " OR b XOR b;", "b : BOOL;"),
        program("b := " + " < ".join(["x"] * DEEP) + ";", "b : BOOL; x : DINT;"),
        program("x := " + right_deep("ABS(", "1", ")") + ";"),
        program("x := " + right_deep("MAX(1, ", "1", ")") + ";"),
        program("x := " + right_deep("a[", "0", "]") + ";", "a : ARRAY[0..1] OF DINT; x : DINT;"),
        program("x := s" + ".m" * DEEP + ";"),
        program("x := x" + ".0" * DEEP + ";"),
        program("x := p" + "^" * DEEP + ";", "p, x : DINT;"),
        program("", "a : ARRAY[0..1] OF INT := " + right_deep("[", "1", "]") + ";"),
        program("", "s : S := " + right_deep("(m := ", "1", ")") + ";"),
        program("", f"a : ARRAY[0..{left_deep}] OF INT;"),
        program("", f"s : STRING[{left_deep}];"),
        f"TYPE E : (A := {left_deep}); END_TYPE\n" + program(""),
        program(f"CASE x OF {left_deep}: x := 1; END_CASE;"),
        program(f"FOR x := 1 TO {left_deep} DO END_FOR;"),
        "PROGRAM P\nVAR b : BOOL; END_VAR\nINITIAL_STEP S0: END_STEP\nSTEP S1: END_STEP\n"
        f"TRANSITION FROM S0 TO S1 := {' AND '.join(['b'] * DEEP)}; END_TRANSITION\n"
        "END_PROGRAM\n",
        # through the names of constants, which the compiler folds
        "VAR_GLOBAL CONSTANT c0 : DINT := 1;"
        + "".join(f"c{i + 1} : DINT := c{i} + 1;" for i in range(10_000))
        + " END_VAR\n"
        + program("", "a : ARRAY[0..c10000] OF INT;"),
    )


def test_parentheses_cost_no_nesting() -> None:
    (outcome,) = compile_capped(program("x := " + right_deep("(", "1", ")", 60_000) + ";"))
    assert not outcome.diagnostics, outcome.diagnostics


def test_statements_of_every_kind_nested_too_deep_are_refused() -> None:
    depth = DEEP // 2
    refused_with(
        "E0705",
        program(right_deep("IF b THEN ", "x := 1;", " END_IF;", depth), "b : BOOL; x : DINT;"),
        program(right_deep("IF b THEN ELSE ", "x := 1;", " END_IF;", depth), "b : BOOL; x : DINT;"),
        program(right_deep("CASE x OF 1: ", "x := 1;", " END_CASE;", depth)),
        program(right_deep("WHILE b DO ", "x := 1;", " END_WHILE;", depth), "b : BOOL; x : DINT;"),
        program(
            right_deep("REPEAT ", "x := 1;", " UNTIL b END_REPEAT;", depth), "b : BOOL; x : DINT;"
        ),
        program(right_deep("FOR x := 1 TO 2 DO ", "x := 1;", " END_FOR;", depth)),
        "PROGRAM P\nVAR b : BOOL; x : DINT; END_VAR\nINITIAL_STEP S0: A(N); END_STEP\n"
        "ACTION A: " + right_deep("IF b THEN ", "x := 1;", " END_IF;", depth) + " END_ACTION\n"
        "END_PROGRAM\n",
        # Python nests 20 loops at most, and each ELSIF and CASE branch in the one before
        program(right_deep("WHILE x < 1 DO ", "x := 1;", " END_WHILE;", 21)),
        program(
            "IF x = 0 THEN "
            + "".join(f"ELSIF x = {i} THEN x := {i};" for i in range(5_000))
            + " END_IF;"
        ),
        program("CASE x OF " + "".join(f"{i}: x := {i};" for i in range(5_000)) + " END_CASE;"),
        program(
            right_deep(
                "CASE x OF " + "".join(f"{i}: x := {i};" for i in range(30)) + " 99: ",
                "x := 1;",
                " END_CASE;",
                35,
            )
        ),
    )


def test_deep_elsif_that_calls_functions_with_outputs_is_refused() -> None:
    """Each such ELSIF nests its branch in the generated code: 120 would be 100 blocks deep."""
    function = (
        "FUNCTION F : BOOL\nVAR_INPUT a : INT; END_VAR\nVAR_OUTPUT o : INT; END_VAR\n"
        "F := a > 1;\nEND_FUNCTION\n"
    )
    branches = "".join(f"ELSIF F(a := x, o => y) THEN x := {i}; " for i in range(120))
    refused_with(
        "E0705", function + program(f"IF x = 0 THEN x := 1; {branches} END_IF;", "x, y : INT;")
    )


def test_nesting_up_to_the_limits_compiles() -> None:
    outcomes = compile_capped(
        program(right_deep("IF b THEN ", "x := 1;", " END_IF;", 39), "b : BOOL; x : DINT;"),
        program(right_deep("WHILE x < 1 DO ", "x := 1;", " END_WHILE;", 20)),
        program("x := " + " + ".join(["1"] * 60) + ";"),
        program(
            "IF x = 0 THEN "
            + "".join(f"ELSIF x = {i} THEN x := {i};" for i in range(999))
            + " END_IF;"
        ),
    )
    for outcome in outcomes:
        assert not outcome.diagnostics, outcome.diagnostics


# ---- generated code -----------------------------------------------------------------------


def test_generated_code_beyond_its_size_is_refused() -> None:
    transitions = "".join("TRANSITION FROM S0 TO S1 := b; END_TRANSITION\n" for _ in range(2_000))
    functions = "".join(
        f"FUNCTION F{i} : INT\nVAR a : ARRAY[1..300000] OF LREAL := [300000(1.5)]; END_VAR\n"
        f"F{i} := 1;\nEND_FUNCTION\n"
        for i in range(12)
    )
    refused_with(
        "E0713",
        program("", "a : ARRAY[1..900000] OF LREAL := [900000(1.5)];"),
        program("", "a : ARRAY[1..1000] OF ARRAY[1..1000] OF INT := [1000([1000(12345)])];"),
        "PROGRAM P\nVAR b : BOOL; END_VAR\nINITIAL_STEP S0: END_STEP\nSTEP S1: END_STEP\n"
        + transitions
        + "END_PROGRAM\n",
        functions + program("x := F0();"),
    )


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
        program("", "a : " + "ARRAY[0..1] OF " * 10_000 + "BOOL;"),
        chain("blocks", 10_000),
        chain("structures", 10_000),
        chain("names", 10_000),
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


def test_a_repetition_beyond_its_array_is_refused_before_it_is_written_out() -> None:
    """A structure member's initial value was not checked, and `[10^12(0)]` was expanded."""
    refused_with(
        "E0121",
        "TYPE S : STRUCT a : ARRAY[1..10] OF INT := [1000000000000(0)]; END_STRUCT; END_TYPE\n"
        + program("", "s : S;"),
        program("", "a : ARRAY[1..10] OF INT := [1000000000000(0)];"),
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


# ---- should a limit be missing -------------------------------------------------------------


@pytest.mark.parametrize("error", [RecursionError, MemoryError])
def test_the_compiler_never_lets_recursion_or_memory_errors_out(
    error: type[Exception], monkeypatch: pytest.MonkeyPatch
) -> None:
    def exhausted(resolved: object) -> None:
        raise error()

    monkeypatch.setattr(pipeline, "check", exhausted)
    result = pipeline.compile_sources([SourceFile("main.st", program("x := 1;"))])
    assert result.artifact is None
    assert [str(d) for d in result.diagnostics] == [
        "main.st:1:1: error: the compiler ran out of "
        + ("stack" if error is RecursionError else "memory")
        + " on this project [E0708]"
    ]


def test_a_padt_toml_nested_too_deep_is_a_project_error(tmp_path: Path) -> None:
    (tmp_path / "padt.toml").write_text(
        '[resource]\nname = "R"\n[project]\nx = ' + "[" * 100_000 + "]" * 100_000 + "\n"
    )
    (tmp_path / "main.st").write_text(program("x := 1;"))
    with pytest.raises(ProjectError, match="nested too deep"):
        load_project([tmp_path])
    run = padt("compile", str(tmp_path))
    assert run.returncode == 2 and "Traceback" not in run.stderr, run.stderr


def test_a_very_long_name_is_quoted_cut_in_its_diagnostic() -> None:
    """A name of 5,000 parts made a diagnostic of 58 KB; it is quoted by its start and end."""
    name = ".".join(f"N{i}" for i in range(5_000))
    source = SourceFile("p.st", program("x := 1;", f"x : DINT; y : {name};"))
    result = pipeline.compile_sources([source])
    (diagnostic,) = result.diagnostics
    assert str(diagnostic).startswith("p.st:2:") and len(str(diagnostic)) < 500
    assert "'N0.N1.N2." in diagnostic.message and ".N4998.N4999'" in diagnostic.message
    assert "[...]" in diagnostic.message
