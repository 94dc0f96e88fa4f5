"""Declarations of edition 3 and CODESYS on the native tier (the runtime's default) and
the Python tier (`padt sim`), side by side: references that start as NULL or as REF(x) of
their own instance, and FB_INIT, run once when an instance is made. Every variable
identical after every cycle, no fault, and the values the language gives."""

from __future__ import annotations

from runtime.code.native.tier import NativeTier
from tests.runtime.native.test_native_oop import run_alike, values

INITIAL_REFERENCES = """
VAR_GLOBAL g : INT := 5; gr : REF_TO INT := REF(g); END_VAR
FUNCTION_BLOCK Counter
VAR mine : REF_TO INT := REF(n); none : REF_TO INT := NULL; n : INT; END_VAR
mine^ := mine^ + 1;
END_FUNCTION_BLOCK
PROGRAM Main
VAR
  level : INT := 3; r : REF_TO INT := REF(level); c : Counter; cs : ARRAY[1..2] OF Counter;
  seen : INT;
END_VAR
r^ := r^ + 1;
c(); cs[2]();
seen := gr^ + c.n + cs[2].n;
IF c.none = NULL THEN seen := seen + 100; END_IF;
END_PROGRAM
"""


def test_references_start_as_null_or_as_ref_of_their_own_instance_on_both_tiers(
    native_tier: NativeTier,
) -> None:
    pair = run_alike(INITIAL_REFERENCES, native_tier, 3)
    found = values(pair)
    assert found["Main.r"] == "Main.level" and found["Main.level"] == 6
    assert found["Main.c.mine"] == "Main.c.n" and found["Main.c.none"] is None
    assert found["gr"] == "g" and found["Main.seen"] == 5 + 3 + 3 + 100


def test_a_variable_named_like_the_tiers_own_attributes_stays_a_variable(
    native_tier: NativeTier,
) -> None:
    text = """
FUNCTION_BLOCK F
VAR_OUTPUT _native_namespace, python_call : INT; END_VAR
_native_namespace := _native_namespace + 1;
python_call := _native_namespace * 2;
END_FUNCTION_BLOCK
PROGRAM Main
VAR f : F; x : INT; END_VAR
f();
x := f._native_namespace + f.python_call;
END_PROGRAM
"""
    pair = run_alike(text, native_tier, 3)
    assert "F" in pair.report.bodies
    assert values(pair)["Main.x"] == 3 + 6


def test_a_function_with_an_open_array_leaves_only_its_caller_to_python(
    native_tier: NativeTier,
) -> None:
    """A FUNCTION whose in-out is an open array (`ARRAY[*] OF INT`) once made the whole
    artifact's translation fail, every body staying Python; now only the body that passes
    the array is left to Python, with its reason, beside the FUNCTION's own body (an
    open array is no parameter a FUNCTION's C takes)."""
    text = """
FUNCTION First : INT
VAR_IN_OUT a : ARRAY[*] OF INT; END_VAR
First := a[LOWER_BOUND(a, 1)];
a[LOWER_BOUND(a, 1)] := First + 1;
END_FUNCTION
FUNCTION_BLOCK Tick
VAR_OUTPUT n : INT; END_VAR
n := n + 1;
END_FUNCTION_BLOCK
PROGRAM Main
VAR q : ARRAY[1..3] OF INT; r : INT; t : Tick; END_VAR
r := First(q) + q[2];
q[2] := q[2] + 10;
t();
END_PROGRAM
"""
    pair = run_alike(text, native_tier, 3)
    assert "Tick" in pair.report.bodies
    assert [pou for pou, _ in pair.report.left] == ["First", "Main"]
    assert "arrays of fixed bounds" in dict(pair.report.left)["First"]
    found = values(pair)
    assert (found["Main.q"], found["Main.r"], found["Main.t.n"]) == ([3, 30, 0], 2 + 20, 3)
