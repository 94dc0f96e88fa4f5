"""Function block instances called through an expression, as IEC 61131-3 ed. 3 and CODESYS
allow: an array element `fbs[i](...)`, a structure member `s.fb(...)`, an element's member
`axes[1].t(...)`; their outputs read back as `fbs[i].Q`. Traced through `padt sim` (100 ms
cycles)."""

from __future__ import annotations

from pathlib import Path

from tests.compiler.test_checks import diagnostics
from tests.compiler.test_limits import compile_server as compile_server  # refused_with needs it
from tests.compiler.test_limits import program, refused_with, right_deep
from tests.conftest import sim_trace

TIMERS = """
TYPE Axis : STRUCT
  t : TON;
  done : BOOL;
END_STRUCT
END_TYPE
PROGRAM Main
VAR
  fbs : ARRAY[1..3] OF TON;
  ax : Axis;
  axes : ARRAY[0..1] OF Axis;
  i : INT := 2;
  q2, q1 : BOOL;
  run : BOOL;
END_VAR
fbs[1](IN := run, PT := T#200ms);
q1 := fbs[1].Q;
fbs[i](IN := run, PT := T#300ms, Q => q2);
ax.t(IN := run, PT := T#100ms);
ax.done := ax.t.Q;
axes[1].t(IN := fbs[1].Q, PT := T#100ms);
END_PROGRAM
"""


def test_array_elements_and_members_are_called_each_on_their_own_instance(
    tmp_path: Path,
) -> None:
    t = sim_trace(tmp_path, TIMERS, 6, "Main.run=TRUE@2")
    # run rises in the cycle at 100 ms: each timer measures from there with its own PT
    assert t["Main.fbs[1].Q"] == [False, False, False, True, True, True]
    assert t["Main.q1"] == t["Main.fbs[1].Q"]
    assert t["Main.fbs[2].PT"] == [300] * 6  # fbs[i] with i = 2
    assert t["Main.q2"] == [False, False, False, False, True, True]
    assert t["Main.fbs[3].IN"] == [False] * 6  # never called
    assert t["Main.ax.done"] == [False, False, True, True, True, True]
    # started by fbs[1].Q at 300 ms, elapsed 100 ms later
    assert t["Main.axes[1].t.Q"] == [False, False, False, False, True, True]
    assert t["Main.axes[0].t.PT"] == [0] * 6


def test_a_counter_array_indexed_by_a_loop(tmp_path: Path) -> None:
    source = """
FUNCTION_BLOCK Acc
VAR_INPUT add : INT; END_VAR
VAR_OUTPUT sum : INT; END_VAR
sum := sum + add;
END_FUNCTION_BLOCK
PROGRAM Main
VAR accs : ARRAY[1..3] OF Acc; k : INT; total : INT; END_VAR
total := 0;
FOR k := 1 TO 3 DO
  accs[k](add := k * 10);
  total := total + accs[k].sum;
END_FOR;
END_PROGRAM
"""
    t = sim_trace(tmp_path, source, 3)
    assert t["Main.accs[1].sum"] == [10, 20, 30]
    assert t["Main.accs[3].sum"] == [30, 60, 90]
    assert t["Main.total"] == [60, 120, 180]


def test_called_instances_are_checked_like_named_ones() -> None:
    found = diagnostics(
        """
PROGRAM Main
VAR fbs : ARRAY[1..3] OF TON; ints : ARRAY[1..3] OF INT; b : BOOL; END_VAR
b := fbs[1](IN := TRUE);
ints[1](IN := TRUE);
fbs[5](IN := TRUE);
fbs[1](nope := 1);
nothing[1](IN := TRUE);
END_PROGRAM
"""
    )
    assert found == [
        "t.st:4:6: error: function block instance 'fbs[...]' has no value [E0409]",
        "t.st:5:1: error: 'ints[...]' is not a function [E0411]",
        "t.st:6:5: error: index 5 is outside the bounds 1..3 [E0215]",
        "t.st:7:8: error: 'TON' has no parameter 'nope' [E0403]",
        "t.st:8:1: error: 'nothing' is not declared [E0201]",
    ]


TON_THROUGH_A_REFERENCE = """
PROGRAM Main
VAR t : TON; p : REF_TO TON; q : BOOL; END_VAR
p := REF(t);
p^(IN := TRUE, PT := T#100ms);
q := p^.Q;
END_PROGRAM
"""


def test_an_instance_called_through_a_reference(tmp_path: Path) -> None:
    t = sim_trace(tmp_path, TON_THROUGH_A_REFERENCE, 3)
    assert t["Main.t.Q"] == [False, True, True]
    assert t["Main.q"] == [False, True, True]


def test_a_global_written_in_an_element_is_seen_by_the_other_programs(tmp_path: Path) -> None:
    source = """
VAR_GLOBAL g : INT; END_VAR
FUNCTION_BLOCK Bump
VAR_EXTERNAL g : INT; END_VAR
g := g + 1;
END_FUNCTION_BLOCK
TYPE Holder : STRUCT b : Bump; END_STRUCT; END_TYPE
PROGRAM Main
VAR fbs : ARRAY[1..2] OF Bump; h : Holder; END_VAR
fbs[2]();
h.b();
END_PROGRAM
PROGRAM Reader
VAR_EXTERNAL g : INT; END_VAR
VAR seen : INT; END_VAR
seen := g;
END_PROGRAM
CONFIGURATION C
  RESOURCE R ON PLC
    TASK T1 (INTERVAL := T#100ms, PRIORITY := 1);
    PROGRAM Main WITH T1 : Main;
    PROGRAM Reader WITH T1 : Reader;
  END_RESOURCE
END_CONFIGURATION
"""
    t = sim_trace(tmp_path, source, 3)
    # Reader runs after Main in a cycle and sees Main's writes from the next cycle on
    assert t["g"] == [2, 4, 6]
    assert t["Reader.seen"] == [0, 2, 4]


def test_instance_calls_nested_too_deep_are_refused_not_crashed() -> None:
    refused_with(
        "E0706",
        program(right_deep("a[0](IN := ", "TRUE", ")") + ";", "a : ARRAY[0..1] OF TON;"),
        program(right_deep("- ", "1", "") + ";"),  # an expression statement (W0807)
    )
