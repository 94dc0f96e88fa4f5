"""A block's in-outs of arrays, structures and blocks no block extends (issue 34:
layout.Bound, padt_memory.c, the image mode's C): a call binds the in-out to the caller's
very variable, in native memory as on the slots of objects. Every value equal to the
Python tier's after every cycle, written through the in-out's path as through the
variable's; the switch into the image and back keeps each in-out bound to its variable; a
context restores an in-out into storage of its own until the next call binds it, on
either side."""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import pytest

from runtime.code.native.tier import NativeTier
from runtime.image_switch import enter_image, leave_image
from runtime.restart import take_context, warm_start
from tests.runtime.native.test_image_switch import planned, twins
from tests.runtime.native.test_native_functions import in_memory
from tests.support.native_runs import compiled, side_by_side

IN_OUTS = """\
TYPE Pt : STRUCT x : INT; y : REAL; END_STRUCT; END_TYPE
VAR_GLOBAL shared : ARRAY[0..3] OF INT := [10, 20, 30, 40]; END_VAR
FUNCTION_BLOCK Sum
VAR_IN_OUT data : ARRAY[0..3] OF INT; p : Pt; END_VAR
VAR_OUTPUT s : INT; END_VAR
VAR i : INT; END_VAR
s := 0;
FOR i := 0 TO 3 DO s := s + data[i]; END_FOR;
data[0] := data[0] + 1;
p.x := p.x + s;
END_FUNCTION_BLOCK
FUNCTION_BLOCK Reset
VAR_IN_OUT data : ARRAY[0..3] OF INT; p : Pt; END_VAR
VAR_INPUT now : BOOL; END_VAR
VAR fives : ARRAY[0..3] OF INT := [5, 6, 7, 8]; origin : Pt; END_VAR
origin.y := origin.y + 1.5;
IF now THEN data := fives; p := origin; END_IF;  (* the caller's variables written whole *)
END_FUNCTION_BLOCK
FUNCTION_BLOCK Motor
VAR_INPUT on : BOOL; END_VAR
VAR_OUTPUT speed : INT; END_VAR
IF on THEN speed := speed + 1; END_IF;
END_FUNCTION_BLOCK
FUNCTION_BLOCK Drive  (* an in-out of a block: the caller's instance, called *)
VAR_IN_OUT m : Motor; END_VAR
VAR_OUTPUT seen : INT; END_VAR
m(on := TRUE);
seen := m.speed;
END_FUNCTION_BLOCK
FUNCTION_BLOCK Median  (* OSCAT's way: into an inner block's own in-out, read back *)
VAR_IN_OUT pt : ARRAY[0..3] OF INT; END_VAR
VAR inner : Sum; spare : Pt; END_VAR
inner.data := pt;
inner.p := spare;
inner();
pt := inner.data;
END_FUNCTION_BLOCK
PROGRAM Main
VAR
  arr : ARRAY[0..3] OF INT := [1, 2, 3, 4]; pts : ARRAY[1..3] OF Pt; total : INT;
  sum : Sum; other : Sum; reset : Reset; med : Median; idle : Sum; n : INT;
  sums : ARRAY[1..2] OF Sum; motors : ARRAY[1..2] OF Motor; drive : Drive;
END_VAR
n := n + 1;
sum(data := arr, p := pts[2]);
sums[2](data := arr, p := pts[1]);
total := sum.s;
other(data := shared, p := pts[2]);
reset(data := shared, p := pts[3], now := n MOD 3 = 0);
med(pt := arr);
drive(m := motors[2]);
END_PROGRAM
"""


@pytest.mark.parametrize("memory", ["image", "slots"])
def test_in_outs_of_arrays_and_structures_are_the_callers_variables_on_both_tiers(
    native_tier: NativeTier, memory: str
) -> None:
    pair = in_memory(IN_OUTS, native_tier, memory, "n : INT;")
    c = ("Drive", "Main", "Median", "Motor", "Reset", "Sum")
    assert pair.report.bodies == c, pair.report.left
    # written through the in-out's path: the caller's variable is written
    pair.cycle_and_compare(6, writes={4: [("Main.sum.p.x", -5000)]})
    values = pair.native.variables.values()
    # arr[0] + 3 a cycle: two blocks' own, and Median's given back
    assert values["Main.arr"] == values["Main.sum.data"] == values["Main.sums[2].data"]
    assert values["Main.arr"] == [19, 2, 3, 4] and values["Main.sums[1].data"] == [0] * 4
    # written whole in Reset (cycles 3 and 6): the global and the structure it was given
    assert values["shared"] == values["Main.other.data"] == [5, 6, 7, 8]
    assert (values["Main.pts[3].y"], values["Main.reset.p.y"]) == (9.0, 9.0)
    assert values["Main.pts[2].x"] == values["Main.sum.p.x"] == values["Main.other.p.x"]
    assert values["Main.pts[2].x"] < 0
    assert values["Main.motors[2].speed"] == values["Main.drive.m.speed"] == 6
    # a block never called: its in-outs are its own, zeros
    assert values["Main.idle.data"] == [0, 0, 0, 0] and values["Main.idle.p.x"] == 0


def test_the_switch_keeps_each_in_out_bound_to_its_variable(native_tier: NativeTier) -> None:
    pair = twins(compiled(IN_OUTS))
    pair.cycle_and_compare(2)
    switched = pair.native.variables
    plan = planned(pair.native, native_tier)
    enter_image(switched, plan)
    main: Any = switched.programs[0].instance
    # packed bound to its variable (before any call binds it again): the in-out's view
    # sees a write through the variable's
    main.arr[1] = 77
    assert main.sum.data[1] == main.sums[1].data[1] == 77 and main.med.inner.data[1] != 77
    assert switched.globals is not None and main.other.data == switched.globals.shared
    switched.globals.shared[3] = -1
    assert main.other.data[3] == main.reset.data[3] == -1
    python: Any = pair.python.variables.programs[0].instance
    python.arr[1] = 77
    pair.python.variables.globals.shared[3] = -1
    pair.cycle_and_compare(2)
    main.idle.data = [9, 9, 9, 9]  # no variable of the image: into its own storage
    assert main.idle.data == [9, 9, 9, 9] and main.arr[2] == 3
    python.idle.data = [9, 9, 9, 9]
    for twin in (pair.python.variables, switched):  # a path through an in-out, then its own
        twin.store(twin.lookup("Main.sum.p.x"), -5000)
        twin.store(twin.lookup("Main.idle.p.x"), 5)
    pair.cycle_and_compare(2)
    assert switched.values()["Main.pts[2].x"] < 0
    leave_image(switched)
    main = switched.programs[0].instance
    # back on objects, each in-out holds the very object it was bound to
    assert main.sum.data is main.arr and main.sum.p is main.pts[1]
    assert main.sums[1].data is main.arr and main.sums[1].p is main.pts[0]
    assert main.drive.m is main.motors[1]
    assert main.other.data is switched.globals.shared and main.reset.p is main.pts[2]
    assert main.med.inner.data is not main.med.pt  # the copy Median gave it, of its own
    assert main.idle.data is not main.arr and main.idle.data == [9, 9, 9, 9]
    assert main.idle.p.x == 5
    pair.cycle_and_compare(3)


@pytest.mark.parametrize("into_image", [True, False])
def test_a_context_restores_an_in_out_into_its_own_storage_on_either_side(
    native_tier: NativeTier, into_image: bool
) -> None:
    """A context taken in the image warm-starts objects, and the other way round: each
    in-out holds the values it referred to, its own until the next call binds it."""
    artifact = compiled(IN_OUTS)
    pair = twins(artifact)
    source = pair.native if into_image else pair.python
    enter_image(pair.native.variables, planned(pair.native, native_tier))
    pair.cycle_and_compare(4)
    context = take_context(source)
    assert context is not None
    restarted = twins(artifact)
    if into_image:
        enter_image(restarted.native.variables, planned(restarted.native, native_tier))
    for twin in (restarted.python, restarted.native):
        twin.stop()
        warm_start(twin, context)
    values = restarted.native.variables.values()
    assert values == restarted.python.variables.values()
    assert values["Main.sum.data"] == values["Main.arr"]  # the values it referred to
    assert values["Main.idle.data"] == [0, 0, 0, 0]
    for twin in (restarted.python, restarted.native):
        twin.start()
    restarted.cycle_and_compare(3)


def test_a_value_forced_through_an_in_out_is_forced_in_its_variable(
    native_tier: NativeTier,
) -> None:
    """Forcing writes a path through an in-out where the in-out is bound at each cycle, in
    native memory as on objects: the caller's variable holds the forced value."""
    pair = in_memory(IN_OUTS, native_tier, "image", "n : INT;")
    pair.cycle_and_compare(1)  # Sum's in-out bound to pts[2]
    for twin in (pair.python, pair.native):
        twin.params = replace(twin.params, safety_operation=False)
        program = twin.variables.program("Main")
        program.config = replace(program.config, local_forcing_allowed=True)
        twin.forcing.force("Main.sum.p.x", 1000)
        twin.forcing.start("Main")
    pair.cycle_and_compare(3)
    values = pair.native.variables.values()
    assert values["Main.pts[2].x"] == values["Main.sum.p.x"] == 1000


REBOUND = """\
FUNCTION_BLOCK Sum
VAR_IN_OUT data : ARRAY[0..3] OF INT; END_VAR
VAR_OUTPUT s : INT; END_VAR
s := data[0] + data[1] + data[2] + data[3];
END_FUNCTION_BLOCK
PROGRAM Main
VAR
  arr : ARRAY[0..3] OF INT := [1, 2, 3, 4]; zeros : ARRAY[0..3] OF INT; f : Sum;
  a, b, n : INT;
END_VAR
n := n + 1;
IF n = 1 THEN f(data := arr); END_IF;  (* bound once *)
a := f.s;
arr := zeros;  (* written whole: the in-out still holds arr *)
arr[0] := n;
f();  (* called again without binding it anew *)
b := f.s;
END_PROGRAM
"""


@pytest.mark.parametrize("memory", ["image", "slots"])
def test_a_variable_written_whole_stays_the_one_an_in_out_holds(
    native_tier: NativeTier, memory: str
) -> None:
    """`arr := zeros` writes zeros' values into arr, in place on both tiers (`_fill`): an
    in-out bound to arr sees them. (The Python tier gave arr a new list, and the in-out
    kept the old one; native memory wrote the bytes in place: the tiers differed.)"""
    pair = in_memory(REBOUND, native_tier, memory, "a, b, n : INT;")
    pair.cycle_and_compare(4)
    values = pair.native.variables.values()
    assert (values["Main.a"], values["Main.b"], values["Main.f.data"]) == (3, 4, [4, 0, 0, 0])


def test_a_variable_written_whole_through_a_reference_stays_the_one_an_in_out_holds(
    native_tier: NativeTier,
) -> None:
    """`r^ := zeros` writes zeros' values into what r refers to, in place as `arr := zeros`
    does (a reference keeps the configuration on slots: both tiers call the runtime's
    `_deref_set`). It gave the place a new list, which the in-out did not hold."""
    text = REBOUND.replace("a, b, n : INT;", "a, b, n : INT; r : REF_TO ARRAY[0..3] OF INT;")
    text = text.replace("f(data := arr); END_IF;", "f(data := arr); r := REF(arr); END_IF;")
    pair = side_by_side(text.replace("arr := zeros;", "r^ := zeros;"), native_tier)
    pair.cycle_and_compare(4)
    values = pair.native.variables.values()
    assert (values["Main.a"], values["Main.b"], values["Main.f.data"]) == (3, 4, [4, 0, 0, 0])
