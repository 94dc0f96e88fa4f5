"""SFC semantics traced cycle by cycle through `padt sim` (docs/language.md, section SFC).

Cycles are 100 ms; a value printed for cycle k is the value after cycle k ran."""

from __future__ import annotations

from pathlib import Path

from tests.compiler.test_checks import diagnostics
from tests.conftest import sim_trace

QUALIFIERS = """
PROGRAM Q
VAR go, stop : BOOL; qN, qS, qL, qD, qP, qSD, qDS, qSL, qP0, qP1 : BOOL; runs, pulses : INT;
END_VAR
INITIAL_STEP Idle: qS(R); qSD(R); qDS(R); qSL(R); END_STEP
TRANSITION FROM Idle TO Run := go; END_TRANSITION
STEP Run: qN(N); qS(S); qL(L, T#200ms); qD(D, T#200ms); qP(P); qSD(SD, T#200ms);
  qDS(DS, T#200ms); qSL(SL, T#300ms); qP0(P0); qP1(P1); Count(N); Once(P); END_STEP
TRANSITION FROM Run TO Idle := stop; END_TRANSITION
ACTION Count: runs := runs + 1; END_ACTION
ACTION Once: pulses := pulses + 1; END_ACTION
END_PROGRAM
"""


def trace(tmp_path: Path, source: str, cycles: int, *sets: str) -> dict[str, list[object]]:
    return sim_trace(tmp_path, source, cycles, *sets)


def flags(text: str) -> list[bool]:
    return [c == "T" for c in text.split()]


def test_every_qualifier_cycle_by_cycle(tmp_path: Path) -> None:
    # Run becomes active at the end of cycle 2 and is left at the end of cycle 6.
    t = trace(
        tmp_path, QUALIFIERS, 8, "Q.go=TRUE@2", "Q.go=FALSE@3", "Q.stop=TRUE@6", "Q.stop=FALSE@7"
    )
    assert t["Q.Run.X"] == flags("F T T T T F F F")
    assert t["Q.Run.T"] == [0, 0, 0, 100, 200, 300, 300, 300]  # 0 in its first active cycle
    assert t["Q.Idle.X"] == flags("T F F F F T T T")
    assert t["Q.qN"] == flags("F F T T T T F F")  # while the step is active
    assert t["Q.qS"] == flags("F F T T T T F F")  # stored until R (in Idle)
    assert t["Q.qL"] == flags("F F T T F F F F")  # at most 200 ms
    assert t["Q.qD"] == flags("F F F F T T F F")  # after 200 ms
    assert t["Q.qP"] == flags("F F T F F F F F")  # one cycle on activation
    assert t["Q.qSD"] == flags("F F F F T T F F")  # stored, then delayed
    assert t["Q.qDS"] == flags("F F F F T T F F")  # delayed, then stored
    assert t["Q.qSL"] == flags("F F T T T F F F")  # stored, at most 300 ms
    assert t["Q.qP0"] == flags("F F F F F F T F")  # one cycle after deactivation
    assert t["Q.qP1"] == flags("F F T F F F F F")  # one cycle on activation
    assert t["Q.runs"] == [0, 0, 1, 2, 3, 4, 5, 5]  # 4 active cycles and the final scan
    assert t["Q.pulses"] == [0, 0, 1, 1, 1, 1, 1, 1]  # P runs once, without a final scan


def test_stored_actions_outlive_their_step(tmp_path: Path) -> None:
    source = """
    PROGRAM K
    VAR go : BOOL; s, sd : BOOL; END_VAR
    INITIAL_STEP A: END_STEP
    TRANSITION FROM A TO B := go; END_TRANSITION
    STEP B: s(S); sd(SD, T#300ms); END_STEP
    TRANSITION FROM B TO C := TRUE; END_TRANSITION
    STEP C: END_STEP
    END_PROGRAM
    """
    t = trace(tmp_path, source, 7, "K.go=TRUE@1")
    assert t["K.B.X"] == flags("T F F F F F F")  # entered after cycle 1, acts in cycle 2 only
    assert t["K.s"] == flags("F T T T T T T")  # S holds with nothing to reset it
    assert t["K.sd"] == flags("F F F F T T T")  # SD fires 300 ms after B, though B is gone


def test_divergence_convergence_and_priority(tmp_path: Path) -> None:
    source = """
    PROGRAM D
    VAR go, done : BOOL; END_VAR
    INITIAL_STEP S0: END_STEP
    TRANSITION FROM S0 TO (A, B) := go; END_TRANSITION
    STEP A: END_STEP
    STEP B: END_STEP
    TRANSITION FROM (A, B) TO S0 := done; END_TRANSITION
    INITIAL_STEP C0: END_STEP
    TRANSITION (PRIORITY := 2) FROM C0 TO C1 := TRUE; END_TRANSITION
    TRANSITION (PRIORITY := 1) FROM C0 TO C2 := TRUE; END_TRANSITION
    STEP C1: END_STEP
    STEP C2: END_STEP
    END_PROGRAM
    """
    t = trace(tmp_path, source, 4, "D.go=TRUE@1", "D.go=FALSE@2", "D.done=TRUE@3")
    assert t["D.A.X"] == flags("T T F F") and t["D.B.X"] == flags("T T F F")
    assert t["D.S0.X"] == flags("F F T T")
    # both transitions from C0 are TRUE; only the one with priority 1 fires
    assert t["D.C2.X"] == flags("T T T T") and t["D.C1.X"] == flags("F F F F")


def test_a_steps_action_sets_a_global_beside_another_program(tmp_path: Path) -> None:
    # with two programs each runs on its own view of the globals: what a step's action
    # sets must be published like an assignment (the template's vessel, split in two)
    source = """
    VAR_GLOBAL inlet, outlet : BOOL; level : INT; END_VAR
    PROGRAM Batch
    VAR_EXTERNAL inlet : BOOL; level : INT; END_VAR
    VAR go : BOOL; END_VAR
    INITIAL_STEP Idle: END_STEP
    TRANSITION FROM Idle TO Fill := go; END_TRANSITION
    STEP Fill: inlet(N); outlet(R); END_STEP
    TRANSITION FROM Fill TO Drain := level >= 2; END_TRANSITION
    STEP Drain: outlet(S); END_STEP
    END_PROGRAM
    PROGRAM Vessel
    VAR_EXTERNAL inlet, outlet : BOOL; level : INT; END_VAR
    IF inlet THEN level := level + 1; END_IF;
    IF outlet THEN level := level - 1; END_IF;
    END_PROGRAM
    """
    t = trace(tmp_path, source, 8, "Batch.go=TRUE@1")
    assert t["Batch.Fill.X"] == flags("T T T T F F F F")
    assert t["inlet"] == flags("F T T T T F F F")  # from the cycle after Fill is entered
    assert t["outlet"] == flags("F F F F F T T T")
    assert t["level"] == [0, 0, 1, 2, 3, 4, 3, 2]  # Vessel sees each a cycle later


def test_a_global_set_by_steps_of_two_programs_has_two_writers() -> None:
    source = """VAR_GLOBAL lamp : BOOL; END_VAR
PROGRAM A
INITIAL_STEP S: lamp(N); END_STEP
END_PROGRAM
PROGRAM B
VAR_EXTERNAL lamp : BOOL; END_VAR
INITIAL_STEP S: lamp(S); END_STEP
END_PROGRAM
"""
    assert (
        "t.st:3:17: error: global 'lamp' is written by the user programs A, B; "
        "global data must have one writer [E0606]"
    ) in diagnostics(source)
