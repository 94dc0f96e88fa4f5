"""The programs of the edition-3 tests (methods, EXTENDS with SUPER^ and THIS^, interfaces,
properties, `?=`, references) run on the Python tier (`padt sim`) and on the native tier
(`padt runtime`, docs/native-code.md) side by side: every variable, every program's state
and error identical after every cycle. The programs are those the tests of
tests/compiler/test_oop.py, test_references.py, test_dialect_names.py and
test_instance_calls.py trace through `padt sim`; what each one must give is asserted there."""

from __future__ import annotations

import pytest

from runtime.code.native.tier import NativeTier
from runtime.contract.protocol import ProgramState
from tests.compiler import test_dialect_names as dialect_names
from tests.compiler import test_instance_calls as instance_calls
from tests.compiler import test_oop as oop
from tests.compiler import test_references as references
from tests.support.native_runs import Pair, Writes, program_error, side_by_side

CYCLES = 10

PROGRAMS: dict[str, str] = {
    "oop.COUNTER_CALLS": oop.COUNTER_CALLS,
    "oop.PUMP_AND_MAIN": oop.PUMP_AND_MAIN,
    "oop.WALKER": oop.WALKER,
    "oop.DRIVES_CALLS": oop.DRIVES_CALLS,
    "oop.QUIET_DRIVE": oop.QUIET_DRIVE,
    "oop.MACHINES_THROUGH_AN_INTERFACE": oop.MACHINES_THROUGH_AN_INTERFACE,
    "oop.MACHINES_THROUGH_A_REFERENCE": oop.MACHINES_THROUGH_A_REFERENCE,
    "oop.MACHINES_ATTEMPTED": oop.MACHINES_ATTEMPTED,
    "oop.MACHINES_UNASSIGNED": oop.MACHINES_UNASSIGNED,
    "oop.MOTOR_CALLS": oop.MOTOR_CALLS,
    "oop.BOX": oop.BOX,
    "oop.TANKS": oop.TANKS,
    "oop.TEMPORARIES_AND_METHODS": oop.TEMPORARIES_AND_METHODS,
    "oop.HALF_TON": oop.HALF_TON,
    "oop.PRIMED_PUMP": oop.PRIMED_PUMP,
    "oop.TWINCAT_ORDER": oop.TWINCAT_ORDER,
    "oop.LISTENER": oop.LISTENER,
    "oop.ACCUMULATOR": oop.ACCUMULATOR,
    "oop.GENERATIONS": oop.GENERATIONS,
    "oop.VARIABLE_LENGTH_ARRAY": oop.VARIABLE_LENGTH_ARRAY,
    "oop.CALLED_THROUGH_A_REFERENCE": oop.CALLED_THROUGH_A_REFERENCE,
    "oop.CALLED_THROUGH_A_REFERENCE_TO": oop.CALLED_THROUGH_A_REFERENCE_TO,
    "oop.INTERFACE_OUTPUTS": oop.INTERFACE_OUTPUTS,
    "references.READ_AND_WRITTEN": references.READ_AND_WRITTEN,
    "references.PASSED_TO_A_BLOCK": references.PASSED_TO_A_BLOCK,
    "references.BELOW_AN_ASSIGNED_ROOT": references.BELOW_AN_ASSIGNED_ROOT,
    "references.COMPARED": references.COMPARED,
    "references.NULL_DEREFERENCED": references.NULL_DEREFERENCED,
    "references.POINTERS": references.POINTERS,
    "references.REFERENCE_TO_BOUND": references.REFERENCE_TO_BOUND,
    "references.UNBOUND_REFERENCE_TO": references.UNBOUND_REFERENCE_TO,
    "references.REFERENCE_TO_INPUTS": references.REFERENCE_TO_INPUTS,
    "references.UNBOUND_REFERENCE_TO_INPUT": references.UNBOUND_REFERENCE_TO_INPUT,
    "references.GLOBAL_KEEPER": references.GLOBAL_KEEPER,
    "references.LAMP_COMMAND": references.LAMP_COMMAND,
    "dialect_names.ACCESS": dialect_names.ACCESS,
    "dialect_names.QUALIFIED": dialect_names.QUALIFIED,
    "dialect_names.SYSTEM_INTERFACE": dialect_names.SYSTEM_INTERFACE,
    "instance_calls.TON_THROUGH_A_REFERENCE": instance_calls.TON_THROUGH_A_REFERENCE,
}

# program errors by design: a call through an interface never assigned, a dereference of
# NULL, a REFERENCE TO never bound
FAULTING = {
    "oop.MACHINES_UNASSIGNED",
    "references.NULL_DEREFERENCED",
    "references.UNBOUND_REFERENCE_TO",
    "references.UNBOUND_REFERENCE_TO_INPUT",
}

# as the test's `padt sim --set`
WRITES: dict[str, Writes] = {"oop.ACCUMULATOR": {2: [("Main.go", True)]}}


def both(native_tier: NativeTier, text: str) -> Pair:
    """A Pair of its own tier object, sharing the session's cache of compiled modules."""
    return side_by_side(text, NativeTier(native_tier.cache, native_tier.toolchain))


@pytest.mark.parametrize("name", sorted(PROGRAMS))
def test_an_edition_3_program_runs_alike_on_both_tiers(native_tier: NativeTier, name: str) -> None:
    pair = both(native_tier, PROGRAMS[name])
    pair.cycle_and_compare(CYCLES, WRITES.get(name))
    assert not pair.report.failed, pair.report.failed
    if name in FAULTING:
        assert "dereference of NULL" in program_error(pair.native), program_error(pair.native)
    else:
        assert not program_error(pair.native), program_error(pair.native)


def test_super_in_a_block_called_by_a_program_in_c_runs_without_fault(
    native_tier: NativeTier,
) -> None:
    """Issue 33: HalfTon's body calls SUPER^() (TON's body, as C); Main, as C, calls HalfTon.
    Before f5b7957 the native tier faulted in the first cycle: "descriptor '__call__' for
    'POU_TON' objects doesn't apply to a 'POU_HALFTON' object"."""
    pair = both(native_tier, oop.HALF_TON)
    pair.cycle_and_compare(CYCLES)
    assert {"Main", "TON"} <= set(pair.report.bodies), pair.report.left
    assert [(p.name, p.state) for p in pair.native.programs] == [("Main", ProgramState.RUN)]


def test_super_of_a_user_block_in_c_runs_without_fault(native_tier: NativeTier) -> None:
    """The same with a base of the user's: Drive's body is C, Servo's SUPER^() runs it on a
    Servo (before f5b7957: a TypeError in the first cycle)."""
    pair = both(native_tier, oop.DRIVES_CALLS)
    pair.cycle_and_compare(CYCLES)
    assert "Drive" in pair.report.bodies, pair.report.left
    assert [(p.name, p.state) for p in pair.native.programs] == [("Main", ProgramState.RUN)]
