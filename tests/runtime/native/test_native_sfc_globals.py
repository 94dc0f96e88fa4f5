"""An SFC step's action on a BOOL global sets the global on both tiers, whatever the way to
it (VAR_EXTERNAL, the global named directly, a located output), with every qualifier, when
each program runs on its own view of the globals (more than one program, or a sliced one:
runtime/code/instances.py). A step's time (L, D, SD, DS, SL) read from a global another program
writes is the value that program wrote (docs/language.md, SFC). The same set of the globals a
program writes holds those it passes to an in-out. An action's own body runs as C."""

from __future__ import annotations

import pytest

from runtime.code.native.tier import NativeTier
from runtime.contract.artifact import ProgramConfig
from runtime.resource import Resource
from tests.runtime.native.test_native_functions import in_memory
from tests.support.native_runs import advance, side_by_side

GLOBALS = """
VAR_GLOBAL
  go, stop : BOOL;
  eN, eS, eL, eD, eP, eSD, eDS, eSL, eP0, eP1 : BOOL;
  gN, gS : BOOL;
  valve AT %QX0.0 : BOOL;
  hold : TIME := T#1s;
END_VAR
"""

# Run becomes active at the end of cycle 2 and is left at the end of cycle 6 (as the local
# flags of tests/compiler/test_sfc.py, which Q keeps here for comparison)
CHART = """
PROGRAM Q
VAR_EXTERNAL go, stop : BOOL; eN, eS, eL, eD, eP, eSD, eDS, eSL, eP0, eP1 : BOOL;
  valve : BOOL; hold : TIME; END_VAR
VAR qN, qL : BOOL; END_VAR
INITIAL_STEP Idle: eS(R); eSD(R); eDS(R); eSL(R); gS(R); END_STEP
TRANSITION FROM Idle TO Run := go; END_TRANSITION
STEP Run: qN(N); qL(L, hold); eN(N); eS(S); eL(L, hold); eD(D, hold); eP(P);
  eSD(SD, hold); eDS(DS, hold); eSL(SL, T#300ms); eP0(P0); eP1(P1);
  gN(N); gS(S); valve(N);
END_STEP
TRANSITION FROM Run TO Idle := stop; END_TRANSITION
END_PROGRAM
"""

# the second program drives the chart through globals and sets the time of its steps
OPERATOR = """
PROGRAM Operator
VAR_EXTERNAL go, stop : BOOL; hold : TIME; END_VAR
VAR cycle : INT; END_VAR
cycle := cycle + 1;
hold := T#200ms;
go := cycle = 1;  (* the chart sees it in its next cycle *)
stop := cycle = 5;
END_PROGRAM
"""

PROGRAMS = [ProgramConfig("Operator", "Operator", 1, priority=0), ProgramConfig("Q", "Q", 2, 1)]


def flags(text: str) -> list[bool]:
    return [c == "T" for c in text.split()]


def history(resource: Resource, names: list[str], cycles: int) -> dict[str, list[object]]:
    seen: dict[str, list[object]] = {name: [] for name in names}
    for _ in range(cycles):
        advance(resource)
        values = {**resource.variables.values(), "image valve": resource.io.outputs.get("valve")}
        for name in names:
            seen[name].append(values[name])
    return seen


def test_a_steps_actions_on_globals_set_them_on_both_tiers(native_tier: NativeTier) -> None:
    pair = side_by_side(GLOBALS + CHART + OPERATOR, native_tier, PROGRAMS)
    assert pair.report.bodies == ("Operator", "Q")  # the chart as C too
    names = ["Q.Run.X", "Q.qN", "Q.qL", "eN", "eS", "eL", "eD", "eP", "eSD", "eDS", "eSL"]
    names += ["eP0", "eP1", "gN", "gS", "valve", "image valve"]
    python = history(pair.python, names, 8)
    assert python["Q.Run.X"] == flags("F T T T T F F F")
    assert python["Q.qN"] == python["eN"] == flags("F F T T T T F F")
    assert python["gN"] == python["valve"] == flags("F F T T T T F F")
    assert python["image valve"] == python["valve"]  # what the field gets, %QX0.0
    assert python["eS"] == python["gS"] == flags("F F T T T T F F")  # stored until R in Idle
    assert python["Q.qL"] == python["eL"] == flags("F F T T F F F F")  # 200 ms, not 1 s
    assert python["eD"] == flags("F F F F T T F F")
    assert python["eP"] == python["eP1"] == flags("F F T F F F F F")
    assert python["eSD"] == python["eDS"] == flags("F F F F T T F F")
    assert python["eSL"] == flags("F F T T T F F F")
    assert python["eP0"] == flags("F F F F F F T F")
    assert history(pair.native, names, 8) == python


SLICED = """
VAR_GLOBAL eN, gN : BOOL; valve AT %QX0.0 : BOOL; END_VAR
PROGRAM Alone
VAR_EXTERNAL eN, valve : BOOL; END_VAR
VAR go : BOOL := TRUE; END_VAR
INITIAL_STEP Idle: END_STEP
TRANSITION FROM Idle TO Run := go; END_TRANSITION
STEP Run: eN(N); gN(N); valve(N); END_STEP
END_PROGRAM
"""


def test_a_sliced_program_sets_the_globals_of_its_steps(native_tier: NativeTier) -> None:
    """One program alone, but sliced: its own view of the globals too."""
    sliced = [ProgramConfig("Alone", "Alone", 1, max_duration_us=1_000_000, max_cycles=2)]
    pair = side_by_side(SLICED, native_tier, sliced)
    assert pair.report.bodies == ("Alone",)
    names = ["Alone.Run.X", "eN", "gN", "valve"]
    python = history(pair.python, names, 3)
    assert python == {
        "Alone.Run.X": flags("T T T"),
        "eN": flags("F T T"),
        "gN": flags("F T T"),
        "valve": flags("F T T"),
    }
    assert history(pair.native, names, 3) == python


BLOCK = """
VAR_GLOBAL inlet : BOOL; seen : INT; END_VAR
FUNCTION_BLOCK Filler
VAR_EXTERNAL inlet : BOOL; END_VAR
VAR_INPUT go : BOOL; END_VAR
INITIAL_STEP Idle: END_STEP
TRANSITION FROM Idle TO Fill := go; END_TRANSITION
STEP Fill: inlet(N); END_STEP
END_FUNCTION_BLOCK
PROGRAM Batch
VAR filler : Filler; END_VAR
filler(go := TRUE);
END_PROGRAM
PROGRAM Counter
VAR_EXTERNAL inlet : BOOL; seen : INT; END_VAR
IF inlet THEN seen := seen + 1; END_IF;
END_PROGRAM
"""


def test_a_blocks_chart_sets_a_global_another_program_reads(native_tier: NativeTier) -> None:
    programs = [ProgramConfig("Batch", "Batch", 1), ProgramConfig("Counter", "Counter", 2, 1)]
    pair = side_by_side(BLOCK, native_tier, programs)
    assert pair.report.bodies == ("Batch", "Counter", "Filler")  # the block's chart too
    python = history(pair.python, ["Batch.filler.Fill.X", "inlet", "seen"], 4)
    assert python == {
        "Batch.filler.Fill.X": flags("T T T T"),
        "inlet": flags("F T T T"),
        "seen": [0, 0, 1, 2],  # Counter sees inlet a cycle later
    }
    assert history(pair.native, ["Batch.filler.Fill.X", "inlet", "seen"], 4) == python


IN_OUTS = """
VAR_GLOBAL total, count, other : INT; END_VAR
FUNCTION_BLOCK Bump
VAR_IN_OUT x : INT; END_VAR
x := x + 1;
END_FUNCTION_BLOCK
FUNCTION Add : INT
VAR_IN_OUT acc : INT; END_VAR
VAR_INPUT n : INT; END_VAR
acc := acc + n;
Add := acc;
END_FUNCTION
PROGRAM A
VAR bumper : Bump; y : INT; END_VAR
bumper(x := total);
y := Add(count, 2);
END_PROGRAM
PROGRAM B
VAR_EXTERNAL other : INT; END_VAR
other := other + 1;
END_PROGRAM
"""


def test_a_global_bound_to_an_in_out_is_written_beside_another_program(
    native_tier: NativeTier,
) -> None:
    """The same write set: what a call binds to an in-out (named or by position) is written."""
    programs = [ProgramConfig("A", "A", 1), ProgramConfig("B", "B", 2, 1)]
    pair = side_by_side(IN_OUTS, native_tier, programs)
    python = history(pair.python, ["total", "count", "other"], 3)
    assert python == {"total": [1, 2, 3], "count": [2, 4, 6], "other": [1, 2, 3]}
    assert history(pair.native, ["total", "count", "other"], 3) == python


ACTIONS = """
FUNCTION_BLOCK Dosing
VAR_INPUT go : BOOL; END_VAR
VAR n : INT; total : REAL; label : STRING[12]; END_VAR
INITIAL_STEP Idle: END_STEP
TRANSITION FROM Idle TO Dose := go; END_TRANSITION
STEP Dose: Count(N); Stamp(P); END_STEP
TRANSITION FROM Dose TO Idle := n MOD 4 = 0; END_TRANSITION
ACTION Count:
  n := n + 1;
  total := total + 0.5 * INT_TO_REAL(n);
END_ACTION
ACTION Stamp:
  label := CONCAT('dose ', INT_TO_STRING(n));
END_ACTION
END_FUNCTION_BLOCK
PROGRAM Main
VAR d : Dosing; cycle : INT; END_VAR
cycle := cycle + 1;
d(go := cycle MOD 3 <> 0);
END_PROGRAM
"""


@pytest.mark.parametrize("memory", ["image", "slots"])
def test_the_actions_bodies_run_as_c(native_tier: NativeTier, memory: str) -> None:
    """An action's body is a method of its block (`_action_<NAME>`), C as the block's other
    methods are: with its Python replaced by one that fails, the chart runs on with the
    Python tier's values."""
    pair = in_memory(ACTIONS, native_tier, memory, "cycle : INT;")
    assert pair.report.bodies == ("Dosing", "Main"), pair.report.left

    def python_action(_: object) -> None:
        raise AssertionError("the Python of an action whose C is in place")

    image = pair.native.variables.image
    code = pair.native.variables.code
    assert code is not None
    for cls in (code.classes()["POU_DOSING"], *([image.views["POU_DOSING"]] if image else [])):
        cls._action_COUNT = cls._action_STAMP = python_action  # type: ignore[attr-defined]
    pair.cycle_and_compare(12)
    values = pair.native.variables.values()
    assert values["Main.d.n"] > 4 and values["Main.d.label"].startswith("dose ")
