"""What the translator takes and what it leaves to Python, and why: one example of each
construct it knows, one of each it refuses (no C compiler needed: translation only)."""

from __future__ import annotations

import importlib
import re

import pytest

from runtime.code.native.kinds import Bool, Int, Outputs, Text, class_table, function_table
from runtime.code.native.translate import c_int, translate_unit
from tests.support.native_runs import compiled

FUNCTIONS = """
FUNCTION Twice : INT
VAR_INPUT v : INT; END_VAR
Twice := v * 2;
END_FUNCTION
FUNCTION Named : STRING
VAR_INPUT v : INT; END_VAR
Named := 'n';
END_FUNCTION
FUNCTION Split : BOOL
VAR_INPUT v : INT; END_VAR
VAR_OUTPUT q : INT; END_VAR
q := v;
END_FUNCTION
INTERFACE IGo
METHOD Go : INT
END_METHOD
END_INTERFACE
FUNCTION_BLOCK Runner IMPLEMENTS IGo
METHOD PUBLIC Go : INT
Go := 7;
END_METHOD
END_FUNCTION_BLOCK
"""


# a chart (SFC): its steps, its actions' control blocks
CHART = """INITIAL_STEP S1: END_STEP
TRANSITION FROM S1 TO S2 := b; END_TRANSITION
STEP S2: END_STEP
TRANSITION FROM S2 TO S1 := NOT b; END_TRANSITION"""


# a method called through an interface
INTERFACE_CALL = "g := rn; i := g.Go();"


def translated(body: str, declarations: str = "") -> tuple[bool, str]:
    """Whether PROGRAM Main's body translates, and the reason when it does not."""
    text = (
        f"{FUNCTIONS}PROGRAM Main\nVAR i, j : INT; d : DINT; l : LINT; u : UINT; b, c : BOOL; "
        "r : REAL; x : LREAL; s : STRING; t : TIME; a : ARRAY[1..4] OF INT; tn : TON; "
        "g : IGo; rn : Runner; "
        f"{declarations}END_VAR\n{body}\nEND_PROGRAM\n"
    )
    artifact = compiled(text)
    units = [*artifact.types, *artifact.pous]
    main = next(unit for unit in units if unit.name == "Main")
    forms = {unit.class_name: unit.unit for unit in units}
    result = translate_unit(
        main, forms[main.class_name], class_table(units, forms), None, function_table(units, forms)
    )
    return bool(result.bodies), result.left[0][1] if result.left else ""


@pytest.mark.parametrize(
    "body",
    [
        "i := i + j * 3 - 7;",
        "d := d / 3 + d MOD 7;",
        "l := l * l + d;",  # 128-bit intermediates, wrapped to 64 bits
        "u := SHL(u, 3) OR SHR(u, 2) XOR 16#F0F0;",
        "b := (i > j) AND NOT c OR i = 3;",
        "IF i > 3 THEN j := 1; ELSIF i < 0 THEN j := 2; ELSE j := 3; END_IF;",
        "CASE i OF 1: j := 2; 2..4, 7: j := 3; ELSE j := 0; END_CASE;",
        "FOR i := 10 TO 1 BY -2 DO a[1 + i MOD 4] := i; END_FOR;",
        "WHILE i < 10 DO i := i + 1; IF i = 5 THEN EXIT; END_IF; END_WHILE;",
        "REPEAT i := i - 1; UNTIL i < 0 END_REPEAT;",
        "tn(IN := b, PT := T#1s); c := tn.Q; t := tn.ET + T#5ms;",
        "r := r * 2.5 - INT_TO_REAL(i); x := x / 3.0 + ABS(x); b := r < 1.0;",
        "i := REAL_TO_INT(r); d := TRUNC(x);",
        "i := MAX(i, j, 3) - MIN(i, ABS(j)); r := MIN(r, 2.0, REAL#-1.5); d := ABS(d);",
        "i := Twice(i + 1) - Twice(v := j);",
        "x := SQRT(x) + LN(x) - EXP(x) * SIN(x) + EXPT(x, 2.0);",
        "s := CONCAT(s, 'x'); b := s < 'abc' OR Named(i) = 'n'; i := LEN(s);",
        "b := Split(v := i, q => j) OR Split(v := j, q => i);",
        "i := STRING_TO_INT(s); s := LEFT(s, i); i := FIND(s, 'a') + LEN(INT_TO_STRING(i));",
        "x := STRING_TO_LREAL(s);",
        "RETURN;",
        CHART,
        INTERFACE_CALL,
    ],
)
def test_bodies_of_these_constructs_are_translated(body: str) -> None:
    ok, reason = translated(body)
    assert ok, reason


WIDE = "ul, um : ULINT; lw : LWORD; arr : ARRAY[1..3] OF ULINT; "


@pytest.mark.parametrize(
    "body",
    [
        "ul := ul + um * 3 - 1; b := ul > um; um := ul / um + ul MOD 7;",
        "ul := ul * um * ul;",  # beyond 128 bits: modulo 2**64, all the wrap keeps
        "lw := SHL(lw, i) OR SHR(lw, d) OR ROL(lw, 3) XOR NOT lw;",
        "l := ULINT_TO_LINT(ul); ul := LINT_TO_ULINT(l); lw := DWORD_TO_LWORD(16#FFFF);",
        "FOR i := 1 TO 3 DO arr[i] := arr[i] + ul; END_FOR; x := ULINT_TO_LREAL(ul);",
        "x := ULINT_TO_LREAL(ul MOD um) + ULINT_TO_LREAL(ul - um); i := ul MOD 7;",
    ],
)
def test_bodies_with_ulint_and_lword_are_translated(body: str) -> None:
    ok, reason = translated(body, WIDE)
    assert ok, reason


@pytest.mark.parametrize(
    ("body", "reason"),
    [
        ("FOR ul := 1 TO 3 DO i := i + 1; END_FOR;", "a range over values beyond 64 bits"),
        ("i := a[ul];", "an integer beyond 64 bits where 64 are needed"),
    ],
)
def test_ulint_where_64_bits_are_needed_stays_python(body: str, reason: str) -> None:
    ok, why = translated(body, WIDE)
    assert not ok and reason in why


def test_a_body_left_to_python_names_the_st_line_of_the_statement_refused() -> None:
    body_line = FUNCTIONS.count("\n") + 3  # PROGRAM Main, then VAR, then the body
    ok, why = translated("FOR ul := 1 TO 3 DO i := i + 1; END_FOR;", WIDE)
    assert not ok and why.endswith(f"(ST line {body_line})")


def test_the_c_names_the_printed_line_of_each_statement_it_runs() -> None:
    """`padt_line` is the line of the printed Python a statement's header is on (what a
    fault's traceback names, and fault_location maps to the ST line): in the order
    printed, every line of the body but an `else:`."""
    text = (
        "PROGRAM Main\nVAR i, j : INT; a : ARRAY[1..4] OF INT; END_VAR\n"
        "IF i > 3 THEN j := 1; ELSIF i < 0 THEN j := 2; ELSIF i = 1 THEN j := 5; "
        "ELSE IF j = 2 THEN i := 1; ELSE i := 2; END_IF; END_IF;\n"
        "FOR i := 1 TO 4 DO a[i] := j; IF j > 9 THEN EXIT; END_IF; END_FOR;\n"
        "WHILE j < 10 DO j := j + 1; END_WHILE;\nEND_PROGRAM\n"
    )
    units = [*compiled(text).pous]
    main = units[-1]
    forms = {unit.class_name: unit.unit for unit in units}
    result = translate_unit(main, forms[main.class_name], class_table(units, forms), None)
    assert result.bodies == ("POU_MAIN.__call__",)
    lines = main.source.splitlines()
    first = lines.index("    def __call__(s):") + 1
    body = range(first + 1, len(lines) + 1)
    assert f"f->line = {first};" in result.source
    assert [int(n) for n in re.findall(r"padt_line = (\d+);", result.source)] == [
        n for n in body if lines[n - 1].strip() != "else:"
    ]


def test_the_native_tier_parses_no_python() -> None:
    """The C is made from the typed form (issue 34, step 4), not from printed Python."""
    for name in ("build", "kinds", "tier", "translate", "worker"):
        assert "ast" not in vars(importlib.import_module(f"runtime.code.native.{name}"))


def test_the_artifact_names_a_function_result_and_the_tier_reads_outputs_off_the_code() -> None:
    units = [*compiled(FUNCTIONS + "PROGRAM Main\nEND_PROGRAM\n").pous]
    assert {unit.name: unit.returns for unit in units} == {
        "Twice": "INT", "Named": "STRING[80]", "Split": "BOOL", "Runner": "", "Main": ""
    }  # fmt: skip
    table = function_table(units, {unit.class_name: unit.unit for unit in units})
    assert not table["FN_TWICE"].outputs
    assert table["FN_SPLIT"].outputs == Outputs((Bool(), Int(-32768, 32767)))
    assert table["FN_NAMED"].result == Text()


def test_the_same_unit_gives_the_same_c_and_module_name() -> None:
    text = "PROGRAM Main\nVAR i : INT; END_VAR\ni := i + 1;\nEND_PROGRAM\n"
    first, second = compiled(text), compiled(text)
    results = []
    for artifact in (first, second):
        units = [*artifact.types, *artifact.pous]
        forms = {unit.class_name: unit.unit for unit in units}
        results.append(translate_unit(units[-1], units[-1].unit, class_table(units, forms), None))
    assert results[0].source == results[1].source and results[0].module == results[1].module


def _read_c_int(text: str) -> int:
    """What a C compiler makes of `c_int`'s forms."""
    halves = re.fullmatch(
        r"\(\(padt_i128\)\(\(\(unsigned __int128\)(\d+)ULL << 64\) \| (\d+)ULL\)\)", text
    )
    if halves is not None:
        bits = int(halves.group(1)) << 64 | int(halves.group(2))
        return bits - (1 << 128) if bits >> 127 else bits
    if text == "(-9223372036854775807LL - 1)":
        return -(2**63)
    return int(text.removesuffix("LL"))


@pytest.mark.parametrize(
    "value", [0, 7, -7, 2**31, -(2**63), 2**63 - 1, 2**63, 2**64 - 1, -(2**64), 2**100]
)
def test_integer_constants_are_written_exactly(value: int) -> None:
    assert _read_c_int(c_int(value)) == value
