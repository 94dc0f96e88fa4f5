"""The flat offset of an element of a two-dimensional array indexed by a FOR counter, on
both tiers. The offset of the counter's dimension was once generated as `i - 1 * 4`
where a counted loop knew the counter within the bounds (no check needed): `i - 4`, a
negative list index that read and wrote other elements, silently and consistently, so
that only a read outside the loop showed it."""

from __future__ import annotations

from runtime.code.native.tier import NativeTier
from tests.support.native_runs import side_by_side

TEXT = """
PROGRAM P
VAR a : ARRAY[1..3, 1..4] OF INT; i : INT; total : INT; middle : INT; corner : INT; END_VAR
total := 0;
FOR i := 1 TO 3 DO a[i, 2] := i * 10; END_FOR
FOR i := 1 TO 3 DO total := total + a[i, 2]; END_FOR
middle := a[2, 2];
corner := a[1, 1];
END_PROGRAM
CONFIGURATION C RESOURCE R ON PLC
  TASK T(INTERVAL := T#100ms); PROGRAM p WITH T : P;
END_RESOURCE END_CONFIGURATION
"""


def test_a_counter_indexes_its_own_dimension_on_both_tiers(native_tier: NativeTier) -> None:
    pair = side_by_side(TEXT, native_tier)
    pair.cycle_and_compare(2)
    values = pair.python.variables.values()
    assert values["p.middle"] == 20  # written by the loop at [2, 2], read outside it
    assert values["p.corner"] == 0  # never written
    assert values["p.total"] == 60
    assert values["p.a"] == [0, 10, 0, 0, 0, 20, 0, 0, 0, 30, 0, 0]
