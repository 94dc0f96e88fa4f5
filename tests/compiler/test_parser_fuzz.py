"""Fuzzing the compiler's front door: bad input gives diagnostics, never an exception.

`compile_sources` promises to return every problem as a `file:line:col` diagnostic. These
property tests feed it random text, random bytes, soups of ST tokens and mutations of a
valid program, and check that it returns a CompileResult whose diagnostics all point into
the file at line >= 1 and column >= 1, and that whatever it accepts loads on a resource.

Every crash these tests once found is pinned by a test at the end with its minimal input
(literals without a value, deep nesting, a block containing itself, non-constant initial
values, arithmetic on BOOL and STRING, typed literals of the wrong kind).
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, note, settings
from hypothesis import strategies as st

from backend.compiler.pipeline import CompileResult, compile_sources
from backend.compiler.source import SourceFile
from runtime.clock import VirtualClock
from runtime.resource import Resource
from tests.conftest import padt

FILE = "fuzz.st"

FUZZ = settings(
    max_examples=150,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)

# ---- a valid program that exercises most of the language --------------------------------------

VALID = """\
TYPE
  Point : STRUCT
    x : INT;
    y : INT := 16#0F;
  END_STRUCT;
END_TYPE

FUNCTION Clamp : INT
VAR_INPUT v, lo, hi : INT; END_VAR
IF v < lo THEN Clamp := lo; ELSIF v > hi THEN Clamp := hi; ELSE Clamp := v; END_IF;
END_FUNCTION

FUNCTION_BLOCK Counter
VAR_INPUT up : BOOL; limit : INT := 10; END_VAR
VAR_OUTPUT count : INT; full : BOOL; END_VAR
VAR delay : TON; END_VAR
delay(IN := up, PT := T#200ms);
IF delay.Q AND count < limit THEN
  count := count + 1;
END_IF;
full := count >= limit;
END_FUNCTION_BLOCK

PROGRAM Main
VAR
  ctr : Counter;
  values : ARRAY[1..5] OF INT := [1, 2, 3, 4, 5];
  p : Point;
  i, total : INT;
  level : REAL := 2.5;
  mode : BYTE := 2#0000_0011;
  running : BOOL := TRUE;
  name : STRING[8] := 'pump$N';
END_VAR
ctr(up := running, limit := 3);
total := 0;
FOR i := 1 TO 5 BY 1 DO
  total := total + values[i] * 2;
END_FOR;
WHILE total > 100 DO
  total := total - 7;
  IF total = 50 THEN EXIT; END_IF;
END_WHILE;
CASE mode OF
  0: p.x := Clamp(total, 0, 50);
  1, 2..3: p.y := -total MOD 3;
ELSE
  level := level * 1.5E0 / 2.0;
END_CASE;
REPEAT
  i := i - 1;
UNTIL i <= 0 END_REPEAT;
{attribute 'hide'}
running := NOT ctr.full OR (p.x = p.y) XOR FALSE; (* keep counting *)
END_PROGRAM
"""

# ---- the vocabulary of token soups ----------------------------------------------------------

KEYWORDS = (
    "PROGRAM", "END_PROGRAM", "FUNCTION", "END_FUNCTION", "FUNCTION_BLOCK", "END_FUNCTION_BLOCK",
    "VAR", "VAR_INPUT", "VAR_OUTPUT", "VAR_IN_OUT", "VAR_TEMP", "VAR_GLOBAL", "VAR_EXTERNAL",
    "END_VAR", "CONSTANT", "RETAIN", "AT", "TYPE", "END_TYPE", "STRUCT", "END_STRUCT", "ARRAY",
    "OF", "STRING", "WSTRING", "IF", "THEN", "ELSIF", "ELSE", "END_IF", "CASE", "END_CASE", "FOR",
    "TO", "BY", "DO", "END_FOR", "WHILE", "END_WHILE", "REPEAT", "UNTIL", "END_REPEAT", "EXIT",
    "CONTINUE", "RETURN", "AND", "OR", "XOR", "NOT", "MOD", "TRUE", "FALSE", "BOOL", "SINT",
    "INT", "DINT", "LINT", "UINT", "UDINT", "BYTE", "WORD", "DWORD", "REAL", "LREAL", "TIME",
    "DATE", "TOD", "DT", "TON", "TOF", "TP", "CTU", "R_TRIG", "CONFIGURATION",
    "END_CONFIGURATION", "RESOURCE", "END_RESOURCE", "ON", "TASK", "WITH", "INTERVAL", "PRIORITY",
    "ABS", "SQRT", "INT_TO_REAL", "LEN", "CONCAT", "MUX", "SEL", "LIMIT", "MAX", "printf",
    "__CURRENT_TIME",
)  # fmt: skip
NAMES = ("x", "y", "i", "t", "fb", "P", "Main", "Counter", "Clamp", "Point", "total", "ctr")
OPERATORS = (
    ":=", "=>", ";", ":", ",", ".", "..", "...", "(", ")", "[", "]", "+", "-", "*", "/", "**",
    "=", "<>", "<", ">", "<=", ">=", "&", "^", "#", "%", "'", '"', "$", "{", "}", "@", "!", "?",
    "|", "~", "\\",
)  # fmt: skip
LITERALS = (
    "0", "1", "42", "32767", "32768", "-1", "1_000", "99999999999999999999", "16#FF", "16#ff_ff",
    "2#1010", "8#777", "1.5", "0.1", "1.0E10", "1e-3", "3.4E38", "INT#5", "INT#-5", "UINT#16#FFFF",
    "REAL#1.5", "BOOL#TRUE", "BOOL#1", "T#1s", "T#1h2m3s4ms", "TIME#-5ms", "LT#1.5us",
    "T#1d_2h", "D#2024-01-15", "DATE#1970-01-01", "TOD#12:30:05.25", "DT#2024-01-15-08:00:00",
    "'text'", "'$N$T$$$''", "'$41'", '"wide$0041"', "''", "%IX0.0", "%QW12", "%MD3.1",
    "Color#Red",
)  # fmt: skip
COMMENTS = (
    "(* comment *)",
    "(* nested (* comment *) *)",
    "// line comment\n",
    "/* C comment */",
    "(* unterminated",
    "{attribute 'x'}",
    "{{ C code }}",
    "{",
    "}",
)
SEPARATORS = (" ", " ", " ", "\n", "\t", "\r\n", "")

token = st.one_of(
    st.sampled_from(KEYWORDS),
    st.sampled_from(KEYWORDS).map(str.lower),
    st.sampled_from(NAMES),
    st.from_regex(r"[A-Za-z_][A-Za-z0-9_]{0,10}", fullmatch=True),
    st.sampled_from(OPERATORS),
    st.sampled_from(LITERALS),
    st.integers().map(str),
    st.sampled_from(COMMENTS),
)


@st.composite
def token_soup(draw: st.DrawFn) -> str:
    """Tokens in random order, sometimes framed by a POU header so that the parser gets
    past the first token into declarations and statements."""
    parts = draw(st.lists(st.tuples(token, st.sampled_from(SEPARATORS)), max_size=60))
    soup = "".join(t + sep for t, sep in parts)
    frame = draw(st.sampled_from(["", "program", "declarations", "fb"]))
    if frame == "program":
        return f"PROGRAM P\nVAR x : INT; b : BOOL; t : TON; END_VAR\n{soup}\nEND_PROGRAM\n"
    if frame == "declarations":
        return f"PROGRAM P\nVAR\n{soup}\nEND_VAR\nx := 1;\nEND_PROGRAM\n"
    if frame == "fb":
        return f"FUNCTION_BLOCK F\nVAR_INPUT a : INT; END_VAR\n{soup}\nEND_FUNCTION_BLOCK\n"
    return soup


random_text = st.one_of(
    st.text(max_size=300),
    st.binary(max_size=300).map(lambda raw: raw.decode("utf-8", errors="replace")),
    st.binary(max_size=300).map(lambda raw: raw.decode("latin-1")),
    token_soup(),
)

# ---- mutations of the valid program --------------------------------------------------------------

# names, numbers and typed literals, the two-character operators, then any one character
_TOKEN = re.compile(
    r"\(\*.*?\*\)|//[^\n]*|\s+|[A-Za-z_][A-Za-z0-9_]*#[A-Za-z0-9_.:\-]+|"
    r"[A-Za-z_][A-Za-z0-9_]*|[0-9][0-9_.#A-Fa-f]*(?:[Ee][+-]?[0-9]+)?|'(?:[^'$]|\$.)*'|"
    r":=|=>|<>|<=|>=|\.\.|\*\*|.",
    re.DOTALL,
)
OPERATIONS = (
    "delete_token",
    "duplicate_token",
    "swap_tokens",
    "replace_token",
    "insert_token",
    "delete_char",
    "duplicate_char",
    "swap_chars",
)
Mutation = tuple[str, int, int, str]


def tokens_of(text: str) -> list[str]:
    return _TOKEN.findall(text)


def mutate(text: str, mutations: list[Mutation]) -> str:
    """Apply each mutation in turn; positions count modulo the current length, so that any
    drawn numbers make a valid mutation and shrink toward the start of the program."""
    for operation, first, second, word in mutations:
        if operation.endswith("_char"):
            if not text:
                continue
            i = first % len(text)
            if operation == "delete_char":
                text = text[:i] + text[i + 1 :]
            elif operation == "duplicate_char":
                text = text[:i] + text[i] + text[i:]
            elif i + 1 < len(text):
                text = text[:i] + text[i + 1] + text[i] + text[i + 2 :]
            continue
        tokens = tokens_of(text)
        # only tokens that are not white space are mutated, so every mutation matters
        solid = [n for n, t in enumerate(tokens) if not t.isspace()]
        if not solid:
            continue
        i, j = solid[first % len(solid)], solid[second % len(solid)]
        if operation == "delete_token":
            del tokens[i]
        elif operation == "duplicate_token":
            tokens.insert(i, tokens[i])
        elif operation == "swap_tokens":
            tokens[i], tokens[j] = tokens[j], tokens[i]
        elif operation == "replace_token":
            tokens[i] = word
        else:
            tokens.insert(i, word + " ")
        text = "".join(tokens)
    return text


mutations = st.lists(
    st.tuples(
        st.sampled_from(OPERATIONS),
        st.integers(0, 1 << 16),
        st.integers(0, 1 << 16),
        token,
    ),
    min_size=1,
    max_size=4,
)

# ---- the property -----------------------------------------------------------------------------


def assert_reported_as_diagnostics(text: str) -> CompileResult:
    note(repr(text))
    result = compile_sources([SourceFile(FILE, text)])  # any exception is a bug
    assert isinstance(result, CompileResult)
    for diagnostic in result.diagnostics:
        where = f"{diagnostic.file}:{diagnostic.line}:{diagnostic.col}"
        assert diagnostic.file == FILE and diagnostic.line >= 1 and diagnostic.col >= 1, where
        assert str(diagnostic) == (
            f"{where}: {diagnostic.severity}: {diagnostic.message} [{diagnostic.code}]"
        )
    errors = [d for d in result.diagnostics if d.severity == "error"]
    assert result.ok == (not errors), [str(d) for d in result.diagnostics]
    return result


def assert_loads(result: CompileResult) -> None:
    """Accepted code must load: the generated Python compiles and the cold-start values are
    set. (It is not run: a mutation may well have made a loop endless.)"""
    assert result.artifact is not None
    Resource("R", VirtualClock()).load(result.artifact)


@FUZZ
@given(random_text)
def test_random_text_gives_diagnostics_not_exceptions(text: str) -> None:
    assert_reported_as_diagnostics(text)


@FUZZ
@given(token_soup())
def test_token_soup_gives_diagnostics_not_exceptions(text: str) -> None:
    result = assert_reported_as_diagnostics(text)
    if result.ok:
        assert_loads(result)


def test_the_valid_program_compiles_loads_and_runs() -> None:
    result = compile_sources([SourceFile(FILE, VALID)])
    assert result.ok, [str(d) for d in result.diagnostics]
    pragma_line = VALID.splitlines().index("{attribute 'hide'}") + 1
    assert [str(d) for d in result.diagnostics] == [
        f"{FILE}:{pragma_line}:1: note: pragma 'attribute' ignored: CODESYS/TwinCAT, "
        "not IEC 61131-3 [N0801]"
    ]
    assert result.artifact is not None
    clock = VirtualClock()
    resource = Resource("R", clock)
    resource.load(result.artifact)
    resource.start()
    for _ in range(5):
        resource.cycle()
        clock.advance(100_000_000)
    assert resource.status().programs[0].state == "RUN"
    assert (
        resource.variables.values()["Main.ctr.count"] == 3
    )  # the TON let the counter run to its limit


def test_mutation_keeps_the_text_when_it_cannot_apply() -> None:
    assert mutate("", [("delete_char", 3, 0, "x")]) == ""
    assert mutate("   ", [("delete_token", 3, 0, "x")]) == "   "
    assert mutate("a := b;", [("swap_tokens", 0, 2, "x")]) == "b := a;"
    assert "".join(tokens_of(VALID)) == VALID  # the tokens cover the text


@FUZZ
@given(mutations)
def test_mutated_program_gives_diagnostics_not_exceptions(changes: list[Mutation]) -> None:
    text = mutate(VALID, changes)
    result = assert_reported_as_diagnostics(text)
    if result.ok:
        assert_loads(result)


def test_cli_compile_of_garbage_exits_1_without_traceback(tmp_path: Path) -> None:
    garbage = tmp_path / "garbage.st"
    garbage.write_bytes(b"\x00\xff\xfePROGRAM ((( := ;; END_IF 16#FF#FF 'open\n\x1b[31m END_")
    run = padt("compile", str(garbage))
    assert run.returncode == 1, run.stderr
    assert "Traceback" not in run.stderr
    assert re.search(rf"^{re.escape(str(garbage))}:\d+:\d+: error: .* \[E0001\]$", run.stdout, re.M)


# ---- crashes and gaps found by fuzzing, pinned until they are fixed ------------------------------


def diagnostics_of(text: str) -> list[str]:
    """The rendered diagnostics; fails (rather than raises) on a crash."""
    try:
        result = compile_sources([SourceFile(FILE, text)])
    except Exception as exc:  # the bug under test: report it as a plain failure
        pytest.fail(f"compile_sources raised {type(exc).__name__}: {exc}")
    return [str(d) for d in result.diagnostics]


def program(body: str, declarations: str = "x : INT;") -> str:
    return f"PROGRAM P\nVAR {declarations} END_VAR\n{body}\nEND_PROGRAM\n"


@pytest.mark.parametrize("literal", ["16#_", "2#_", "INT#16#_"])
def test_based_literal_without_digits_is_a_diagnostic(literal: str) -> None:
    found = diagnostics_of(program(f"x := {literal};"))
    assert found and found[0].startswith(f"{FILE}:3:6: error: invalid literal: ")
    assert found[0].endswith(" [E0003]")


@pytest.mark.parametrize("literal", ["D#2024-13-01", "D#2024-02-30", "D#0-1-1"])
def test_impossible_date_is_a_diagnostic(literal: str) -> None:
    found = diagnostics_of(program(f"d := {literal};", "d : DATE;"))
    assert found and found[0].startswith(f"{FILE}:3:6: error: invalid literal: ")
    assert found[0].endswith(" [E0003]")


def test_huge_duration_is_a_diagnostic() -> None:
    found = diagnostics_of(program(f"t := T#{'9' * 400}s;", "t : TIME;"))
    assert found and found[0].startswith(f"{FILE}:3:6: error: invalid literal: ")
    assert found[0].endswith(" [E0003]")


@pytest.mark.parametrize("depth", [600])
def test_deeply_nested_code_compiles_or_is_a_diagnostic(depth: int) -> None:
    chain = program(f"x := {'+'.join(['1'] * depth)};", "x : DINT;")
    nested = program("IF TRUE THEN " * (depth // 2) + "x := 1;" + " END_IF;" * (depth // 2))
    for text in (chain, nested):
        diagnostics_of(text)


def test_function_block_containing_itself_is_rejected() -> None:
    text = "FUNCTION_BLOCK A\nVAR inner : A; END_VAR\nEND_FUNCTION_BLOCK\n" + program(";", "a : A;")
    assert any(": error: " in d and d.endswith(" [E0109]") for d in diagnostics_of(text))


def test_initial_value_reading_a_later_variable_is_rejected() -> None:
    text = program(";", "a : INT := b; b : INT := 5;")
    assert any(": error: " in d and d.endswith(" [E0117]") for d in diagnostics_of(text))


@pytest.mark.parametrize(
    "body, declarations",
    [("b := b + b;", "b : BOOL;"), ("b := b / b;", "b : BOOL;"), ("s := s - s;", "s : STRING;")],
)
def test_arithmetic_on_bool_and_string_is_rejected(body: str, declarations: str) -> None:
    found = diagnostics_of(program(body, declarations))
    assert any(": error: " in d and d.endswith(" [E0211]") for d in found)


@pytest.mark.parametrize("literal", ["INT#1.5", "INT#TRUE", "INT#'a'"])
def test_typed_literal_of_the_wrong_kind_is_rejected(literal: str) -> None:
    found = diagnostics_of(program(f"x := {literal};"))
    assert any(": error: " in d and d.endswith(" [E0208]") for d in found)


def test_configuration_errors_point_into_the_source() -> None:
    text = (
        "PROGRAM P\nEND_PROGRAM\n"
        "CONFIGURATION C\nRESOURCE R ON PLC\nPROGRAM main : Missing;\n"
        "END_RESOURCE\nEND_CONFIGURATION\n"
    )
    found = diagnostics_of(text)
    assert found and all(d.startswith(f"{FILE}:") for d in found), found


def test_cli_compile_of_a_crashing_literal_has_no_traceback(tmp_path: Path) -> None:
    source = tmp_path / "crash.st"
    source.write_text(program("x := 16#_;"))
    run = padt("compile", str(source))
    assert run.returncode == 1 and "Traceback" not in run.stderr, run.stderr
