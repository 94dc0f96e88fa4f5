"""The random programs of the compiler's differential test (tests/compiler/
test_differential.py: INT, UINT, DINT, BOOL and REAL, wrapping arithmetic, IF, CASE, FOR,
WHILE, REPEAT, EXIT, CONTINUE, a function block and a TON) run on the native tier and on
the Python tier: every variable identical after every cycle (REAL bit for bit), the same
faults in the same cycle."""

from __future__ import annotations

from collections import Counter

from hypothesis import HealthCheck, given, settings

from runtime.code.native.tier import NativeTier
from tests.compiler.test_differential import CYCLES, programs
from tests.support.native_runs import side_by_side

LEFT: Counter[str] = Counter()  # why bodies stayed Python, over the examples


@settings(
    max_examples=12,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
@given(programs())
def test_random_programs_run_alike_on_both_tiers(native_tier: NativeTier, program: str) -> None:
    pair = side_by_side(program, native_tier)
    for pou, reason in pair.report.left:
        LEFT[f"{pou}: {reason.split(' (')[0]}"] += 1
    assert "Acc" in pair.report.bodies  # the function block of every program
    pair.cycle_and_compare(CYCLES)
