"""Implicit type conversions as IEC 61131-3 defines them (its table of implicit conversions):
what converts silently, what converts with the CODESYS/TwinCAT warning W0811, what is an
error (E0222, E0417, E0209), in every place a value is stored; the values the accepted
conversions give, traced through `padt sim`; and REAL to integer rounding
(docs/language.md, "Semantics choices")."""

from __future__ import annotations

from pathlib import Path

import pytest

from backend.compiler.pipeline import compile_sources
from backend.compiler.source import SourceFile
from runtime.code.intrinsics import _round
from tests.conftest import sim_trace
from tests.support.oracle.tree_walker import round_half_away


def diagnostics(source: str) -> list[str]:
    return [str(d) for d in compile_sources([SourceFile("t.st", source)]).diagnostics]


def one_assignment(target: str, source: str, value: str = "") -> str:
    initial = f" := {value}" if value else ""
    return f"PROGRAM Main\nVAR x : {target}; v : {source}{initial}; END_VAR\nx := v;\nEND_PROGRAM\n"


IEC_IMPLICIT = [
    ("DINT", "INT", "-5", -5),
    ("LINT", "SINT", "-128", -128),
    ("LINT", "DINT", "-2147483648", -2147483648),
    ("INT", "USINT", "200", 200),
    ("DINT", "UINT", "65535", 65535),
    ("LINT", "UDINT", "4294967295", 4294967295),
    ("ULINT", "USINT", "255", 255),
    ("REAL", "INT", "-7", -7.0),
    ("REAL", "UINT", "65535", 65535.0),
    ("LREAL", "DINT", "16777217", 16777217.0),  # exact in a double, not in a single
    ("LREAL", "UDINT", "4294967295", 4294967295.0),
    ("LREAL", "REAL", "0.5", 0.5),
    ("WORD", "BYTE", "16#12", 0x12),
    ("LWORD", "BOOL", "TRUE", 1),
    ("LTIME", "TIME", "T#1500ms", 1500),  # padt sim shows durations in ms
]


@pytest.mark.parametrize(("target", "source", "value", "expected"), IEC_IMPLICIT)
def test_the_iec_implicit_conversions_are_silent_and_exact(
    tmp_path: Path, target: str, source: str, value: str, expected: object
) -> None:
    program = one_assignment(target, source, value)
    assert diagnostics(program) == []
    trace = sim_trace(tmp_path, program, 1)
    assert trace["Main.x"] == [expected]
    assert type(trace["Main.x"][0]) is type(expected)  # an INT into a REAL gives a float


# converted as CODESYS and TwinCAT do, with W0811: (target, source, initial value, result)
DIALECT = [
    ("INT", "REAL", "2.5", 3),  # rounded, halves away from zero
    ("INT", "REAL", "-2.5", -3),
    ("REAL", "LREAL", "0.1", 0.10000000149011612),  # rounded to single precision
    ("INT", "DINT", "70000", 4464),  # wrapped into 16 bits
    ("INT", "UINT", "40000", -25536),
    ("UINT", "INT", "-1", 65535),
    ("INT", "WORD", "16#FFFF", -1),
    ("WORD", "INT", "-1", 65535),
    ("BYTE", "WORD", "16#1234", 0x34),
    ("REAL", "DINT", "16777217", 16777216.0),  # 24 bits of precision
    ("LREAL", "LINT", "9007199254740993", 9007199254740992.0),
    ("WORD", "REAL", "3.7", 4),
    ("UDINT", "LREAL", "-1.0", 4294967295),
]


@pytest.mark.parametrize(("target", "source", "value", "expected"), DIALECT)
def test_conversions_between_numbers_warn_and_convert_as_codesys(
    tmp_path: Path, target: str, source: str, value: str, expected: object
) -> None:
    program = one_assignment(target, source, value)
    assert diagnostics(program) == [
        f"t.st:3:6: warning: CODESYS and TwinCAT convert {source} to {target} implicitly, "
        f"IEC 61131-3 does not: use {source}_TO_{target}(...) or TO_{target}(...) [W0811]"
    ]
    assert sim_trace(tmp_path, program, 1)["Main.x"] == [expected]


def test_the_named_conversion_function_gives_the_same_value_without_a_warning(
    tmp_path: Path,
) -> None:
    program = """PROGRAM Main
VAR r : REAL := -2.5; d : DINT := 70000; a, b, c, e : INT; END_VAR
a := r;
b := REAL_TO_INT(r);
c := d;
e := TO_INT(d);
END_PROGRAM
"""
    assert [line.split(": ")[0] for line in diagnostics(program)] == ["t.st:3:6", "t.st:5:6"]
    trace = sim_trace(tmp_path, program, 1)
    assert (trace["Main.a"], trace["Main.b"]) == ([-3], [-3])
    assert (trace["Main.c"], trace["Main.e"]) == ([4464], [4464])


EXPLICIT_ONLY = [
    ("DATE", "DT", "DT#2020-01-02-03:04:05", "DT_TO_DATE"),  # would keep the time of day
    ("DT", "DATE", "D#2020-01-02", "DATE_TO_DT"),
    ("DT", "TOD", "TOD#03:04:05", "TOD_TO_DT"),
    ("TIME", "LTIME", "LT#1s", "LTIME_TO_TIME"),
    ("WSTRING", "STRING", "'a'", "STRING_TO_WSTRING"),
    ("STRING", "WSTRING", '"a"', "WSTRING_TO_STRING"),
    ("CHAR", "STRING", "'ab'", "STRING_TO_CHAR"),
]


@pytest.mark.parametrize(("target", "source", "value", "function"), EXPLICIT_ONLY)
def test_other_kind_changes_need_the_conversion_function(
    target: str, source: str, value: str, function: str
) -> None:
    assert diagnostics(one_assignment(target, source, value)) == [
        f"t.st:3:6: error: cannot assign {source} to {target} implicitly: "
        f"use {function}(...) or TO_{target}(...) [E0222]"
    ]
    fixed = one_assignment(target, source, value).replace("x := v;", f"x := {function}(v);")
    assert diagnostics(fixed) == []


def test_a_real_literal_is_no_integer() -> None:
    program = """PROGRAM Main
VAR x : INT; w : WORD; r : REAL; END_VAR
x := 1.5;
w := -2.0;
r := 1.5 * 2;
x := 2.5 * 3;
END_PROGRAM
"""
    assert diagnostics(program) == [
        "t.st:3:6: error: cannot assign a REAL literal to INT implicitly: "
        "write an integer literal or use TO_INT(...) [E0222]",
        "t.st:4:6: error: cannot assign a REAL literal to WORD implicitly: "
        "write an integer literal or use TO_WORD(...) [E0222]",
        "t.st:5:10: warning: CODESYS and TwinCAT convert LREAL to REAL implicitly, "
        "IEC 61131-3 does not: use LREAL_TO_REAL(...) or TO_REAL(...) [W0811]",
        "t.st:6:10: warning: CODESYS and TwinCAT convert LREAL to INT implicitly, "
        "IEC 61131-3 does not: use LREAL_TO_INT(...) or TO_INT(...) [W0811]",
    ]


def test_bool_time_and_numbers_stay_type_mismatches() -> None:
    program = """PROGRAM Main
VAR i : INT; d : DINT; b : BOOL; t : TIME; END_VAR
i := b;
d := t;
END_PROGRAM
"""
    assert diagnostics(program) == [
        "t.st:3:6: error: type mismatch: cannot assign BOOL to INT [E0209]",
        "t.st:4:6: error: type mismatch: cannot assign TIME to DINT [E0209]",
    ]


def test_string_literals_take_the_string_type_they_are_stored_in() -> None:
    program = """PROGRAM Main
VAR c : CHAR := 'a'; w : WSTRING := 'abc'; s : STRING[3] := 'abcdef'; END_VAR
w := 'xyz';
END_PROGRAM
"""
    assert diagnostics(program) == []


def test_an_untyped_integer_literal_takes_the_type_it_meets() -> None:
    # The compiler computes `i + 1` in DINT (as CODESYS), IEC in INT: no narrowing here.
    program = """PROGRAM Main
VAR i, j : INT; u : UINT; b : BOOL; d : DINT; r : REAL; a : ARRAY[1..4] OF INT; END_VAR
i := i + 1;
i := -(i * 2) + 1;
i := LIMIT(0, i, 9);
i := MAX(j, i - 1);
u := SEL(b, u, 0);
i := SHL(21, 2);
i := TRUNC(r);
i := j + UPPER_BOUND(a, 1);
i := i + d;
END_PROGRAM
"""
    assert diagnostics(program) == [
        "t.st:11:8: warning: CODESYS and TwinCAT convert DINT to INT implicitly, "
        "IEC 61131-3 does not: use DINT_TO_INT(...) or TO_INT(...) [W0811]"
    ]


EVERY_PLACE = """TYPE Pair : STRUCT a : INT; b : REAL; END_STRUCT; END_TYPE
FUNCTION Half : INT
VAR_INPUT v : INT; END_VAR
VAR_OUTPUT rest : REAL; END_VAR
Half := v / 2.0;
rest := v;
END_FUNCTION
FUNCTION_BLOCK Scale
VAR_INPUT v : INT; END_VAR
VAR_OUTPUT out : REAL; END_VAR
out := v * 1.5;
END_FUNCTION_BLOCK
PROGRAM Main
VAR CONSTANT big : DINT := 9; END_VAR
VAR
  i : INT := big;
  arr : ARRAY[1..2] OF INT := [big, 2];
  p : Pair := (a := big);
  r : REAL := 7.5;
  n : INT;
  s : Scale;
END_VAR
n := Half(v := r, rest => i);
s(v := r, out => n);
arr[2] := r;
p.a := r;
END_PROGRAM
"""


def test_every_place_a_value_is_stored_is_checked(tmp_path: Path) -> None:
    warned = [line.split(": warning: ")[0] for line in diagnostics(EVERY_PLACE)]
    # (an operation is found at its operator)
    assert warned == [
        "t.st:5:11",  # the return value: Half := v / 2.0 (a REAL)
        "t.st:16:14",  # an initial value
        "t.st:17:32",  # an array element's initial value
        "t.st:18:21",  # a struct member's initial value
        "t.st:23:16",  # a function's input
        "t.st:23:27",  # a function's output into a variable
        "t.st:24:8",  # a function block's input
        "t.st:24:18",  # a function block's output into a variable
        "t.st:25:11",  # an array element
        "t.st:26:8",  # a struct member
    ]
    trace = sim_trace(tmp_path, EVERY_PLACE, 1)
    assert trace["Main.s.v"] == [8]  # 7.5 rounded, halves away from zero
    assert trace["Main.i"] == [8]  # the output rest: 8.0 stored in an INT
    assert trace["Main.n"] == [12]  # 8 * 1.5, after Half gave 4
    assert trace["Main.arr"] == [[9, 8]]
    assert trace["Main.p.a"] == [8]


def test_an_in_out_argument_must_have_the_parameter_type() -> None:
    # an in-out is the caller's variable: a REAL passed for a DINT once crashed the program
    program = """FUNCTION_BLOCK Count
VAR_IN_OUT total : DINT; END_VAR
total := total + 1;
END_FUNCTION_BLOCK
FUNCTION Bump : BOOL
VAR_IN_OUT total : DINT; text : STRING; END_VAR
total := total + 1;
END_FUNCTION
PROGRAM Main
VAR n : INT; r : REAL; d : DINT; c : Count; ok : BOOL; s : STRING[10]; END_VAR
c(total := n);
c(total := r);
ok := Bump(total := n, text := s);
c(total := d);
ok := Bump(total := d, text := s);
END_PROGRAM
"""
    needs = "error: an in-out parameter of type DINT needs a variable of that type, not"
    assert diagnostics(program) == [
        f"t.st:11:12: {needs} INT [E0417]",
        f"t.st:12:12: {needs} REAL [E0417]",
        f"t.st:13:21: {needs} INT [E0417]",
    ]


ROUNDING = [
    ("0.49999999999999994", 0),  # adding 0.5 first gave 1
    ("0.5", 1),
    ("1.5", 2),
    ("2.5", 3),
    ("-0.5", -1),
    ("-1.5", -2),
    ("-2.5", -3),
    ("2.4999999999999996", 2),
    ("4503599627370497.0", 4503599627370497),  # 2**52 + 1: adding 0.5 first gave 2**52 + 2
    ("-4503599627370497.0", -4503599627370497),
    ("9007199254740993.0", 9007199254740992),  # the literal itself is 2**53 in a double
    ("1.0E18", 10**18),
]


def test_real_to_integer_rounds_to_the_nearest_halves_away_from_zero(tmp_path: Path) -> None:
    lines = [f"  x{k} := LREAL_TO_LINT(LREAL#{text});" for k, (text, _) in enumerate(ROUNDING)]
    names = ", ".join(f"x{k}" for k in range(len(ROUNDING)))
    program = f"PROGRAM Main\nVAR {names} : LINT; END_VAR\n" + "\n".join(lines) + "\nEND_PROGRAM\n"
    trace = sim_trace(tmp_path, program, 1)
    assert [trace[f"Main.x{k}"][0] for k in range(len(ROUNDING))] == [v for _, v in ROUNDING]
    # the runtime's helper and the differential tests' oracle agree, also beyond LINT
    for text, expected in ROUNDING:
        assert _round(float(text)) == round_half_away(float(text)) == expected
    for value in (1e300, -1e300, 2.0**63 + 2048.0, 0.5 + 2.0**-53):
        assert _round(value) == round_half_away(value) == round(value)


def test_an_in_out_array_must_have_the_element_type() -> None:
    program = """FUNCTION Sum : DINT
VAR_IN_OUT values : ARRAY[1..3] OF DINT; END_VAR
Sum := values[1] + values[2] + values[3];
END_FUNCTION
PROGRAM Main
VAR a : ARRAY[0..2] OF INT; b : ARRAY[0..2] OF DINT; total : DINT; END_VAR
total := Sum(values := a);
total := Sum(values := b);
END_PROGRAM
"""
    assert diagnostics(program) == [
        "t.st:7:24: error: an in-out parameter of type ARRAY[1..3] OF DINT needs a variable "
        "of that type, not ARRAY[0..2] OF INT [E0417]"
    ]


def test_a_typed_real_literal_is_the_single_a_real_holds(tmp_path: Path) -> None:
    """REAL#7.3 is the IEEE single nearest 7.3 (7.300000190734863), as a REAL variable
    initialised with 7.3 holds it; found by the OSCAT tests of `padt test` (STAIR)."""
    source = """
PROGRAM Main
VAR v : REAL := 7.3; typed, untyped, stored : BOOL; w : REAL; d : LREAL; END_VAR
typed := v = REAL#7.3;
untyped := v = 7.3;
w := REAL#7.3;
stored := w = v;
d := LREAL#7.3;
END_PROGRAM
"""
    t = sim_trace(tmp_path, source, 1)
    assert t["Main.typed"] == t["Main.untyped"] == t["Main.stored"] == [True]
    assert t["Main.w"] == [7.300000190734863]
    assert t["Main.d"] == [7.3]  # an LREAL literal keeps its double
