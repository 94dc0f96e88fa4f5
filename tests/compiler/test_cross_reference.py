"""The cross-reference the compiler gives the documentation: every variable with the
lines that declare, read and write it, as the resolved AST means the names."""

from __future__ import annotations

from backend.compiler.cross_reference import DECLARED, READ, WRITTEN, cross_reference
from backend.compiler.source import SourceFile

SOURCE = """\
VAR_GLOBAL
  level : INT;
  alarm : BOOL;
END_VAR
FUNCTION Clip : INT
VAR_INPUT x : INT; END_VAR
VAR_IN_OUT hit : BOOL; END_VAR
hit := x > 9;
Clip := x;
END_FUNCTION
PROGRAM P
VAR_EXTERNAL level : INT; END_VAR
VAR
  alarm : BOOL;
  i : INT;
  t : TON;
  a : ARRAY[1..3] OF INT;
  hit : BOOL;
END_VAR
FOR i := 1 TO 3 DO
  a[i] := Clip(x := level, hit := hit);
END_FOR;
t(IN := alarm, PT := T#1s);
alarm := t.Q OR SYS.COLDSTART;
CASE level OF
  1: level := 2;
END_CASE;
END_PROGRAM
"""


def uses() -> dict[str, dict[str, list[int]]]:
    table = cross_reference([SourceFile("p.st", SOURCE)])
    return {
        v.qualified: {how: [u.pos.line for u in v.where(how)] for how in (DECLARED, READ, WRITTEN)}
        for v in table
    }


def test_every_variable_declared_read_and_written_where_the_compiler_means_it() -> None:
    found = uses()
    # a VAR_EXTERNAL is the global: both declarations, its reads and writes in P
    assert found["level"] == {DECLARED: [2, 12], READ: [21, 25], WRITTEN: [26]}
    # the global `alarm` is hidden in P by its own `alarm`: never used
    assert found["alarm"] == {DECLARED: [3], READ: [], WRITTEN: []}
    assert found["P.alarm"] == {DECLARED: [14], READ: [23], WRITTEN: [24]}
    # a FOR variable is written, an index read, an element write writes the array
    assert found["P.i"] == {DECLARED: [15], READ: [21], WRITTEN: [20]}
    assert found["P.a"] == {DECLARED: [17], READ: [], WRITTEN: [21]}
    # calling an FB instance writes it; its output read through a member reads it
    assert found["P.t"] == {DECLARED: [16], READ: [24], WRITTEN: [23]}
    # an in-out argument is read and written
    assert found["P.hit"] == {DECLARED: [18], READ: [21], WRITTEN: [21]}
    assert found["Clip.hit"] == {DECLARED: [7], READ: [], WRITTEN: [8]}
    assert found["Clip.Clip"] == {DECLARED: [5], READ: [], WRITTEN: [9]}
    assert found["SYS.COLDSTART"] == {DECLARED: [], READ: [24], WRITTEN: []}


def test_the_standard_library_stays_out_and_the_order_is_fixed() -> None:
    names = [v.qualified for v in cross_reference([SourceFile("p.st", SOURCE)])]
    assert not any(name.startswith("TON.") for name in names)
    assert names == ["alarm", "level", "SYS.COLDSTART", *sorted(names[3:], key=str.upper)]


def test_an_instance_given_by_an_expression_is_written_and_its_in_outs_too() -> None:
    source = """\
FUNCTION_BLOCK Acc
VAR_IN_OUT total : INT; END_VAR
total := total + 1;
END_FUNCTION_BLOCK
PROGRAM P
VAR accs : ARRAY[1..2] OF Acc; k : INT := 1; sum : INT; END_VAR
accs[k](total := sum);
END_PROGRAM
"""
    table = cross_reference([SourceFile("p.st", source)])
    found = {
        v.qualified: {how: [u.pos.line for u in v.where(how)] for how in (READ, WRITTEN)}
        for v in table
    }
    assert found["P.accs"] == {READ: [], WRITTEN: [7]}
    assert found["P.k"] == {READ: [7], WRITTEN: []}
    assert found["P.sum"] == {READ: [7], WRITTEN: [7]}


def test_a_charts_bool_actions_are_written_and_its_step_times_read() -> None:
    source = """\
VAR_GLOBAL inlet : BOOL; hold : TIME; END_VAR
PROGRAM B
VAR_EXTERNAL inlet : BOOL; hold : TIME; END_VAR
VAR lamp : BOOL; END_VAR
INITIAL_STEP S:
  inlet(N); lamp(L, hold);
END_STEP
END_PROGRAM
"""
    table = cross_reference([SourceFile("b.st", source)])
    found = {
        v.qualified: {how: [u.pos.line for u in v.where(how)] for how in (READ, WRITTEN)}
        for v in table
    }
    assert found["inlet"] == {READ: [], WRITTEN: [6]}
    assert found["B.lamp"] == {READ: [], WRITTEN: [6]}
    assert found["hold"] == {READ: [6], WRITTEN: []}
