"""Timers and counters traced through `padt sim` (100 ms cycles; IN set per cycle)."""

from __future__ import annotations

from pathlib import Path

from tests.conftest import sim_trace

SOURCE = """
PROGRAM T
VAR in : BOOL; on : TON; off : TOF; pulse : TP; END_VAR
on(IN := in, PT := T#200ms);
off(IN := in, PT := T#200ms);
pulse(IN := in, PT := T#200ms);
END_PROGRAM
"""


def run(tmp_path: Path, *sets: str, cycles: int = 8) -> dict[str, list[object]]:
    return sim_trace(tmp_path, SOURCE, cycles, *sets)


def bits(values: list[object]) -> str:
    return "".join("1" if v else "0" for v in values)


def test_ton_tof_tp(tmp_path: Path) -> None:
    # IN is TRUE in cycles 2..5 (t = 100..400 ms)
    t = run(tmp_path, "T.in=TRUE@2", "T.in=FALSE@6")
    assert bits(t["T.on.Q"]) == "00011000"  # TRUE once ET reaches PT (cycles 4, 5)
    assert t["T.on.ET"] == [0, 0, 100, 200, 200, 0, 0, 0]
    assert bits(t["T.off.Q"]) == "01111110"  # stays TRUE for 200 ms after IN falls
    assert t["T.off.ET"] == [0, 0, 0, 0, 0, 0, 100, 200]
    assert bits(t["T.pulse.Q"]) == "01100000"  # exactly PT long
    assert t["T.pulse.ET"] == [0, 0, 100, 200, 200, 0, 0, 0]


def test_tp_cannot_be_restarted_while_running(tmp_path: Path) -> None:
    t = run(tmp_path, "T.in=TRUE@2", "T.in=FALSE@3", "T.in=TRUE@4", "T.in=FALSE@5", cycles=6)
    assert bits(t["T.pulse.Q"]) == "011000"  # the second rising edge falls inside the pulse


CHANGING_PT = """
PROGRAM T
VAR in, fall : BOOL; pt : TIME := T#200ms; on : TON; off : TOF; pulse : TP; END_VAR
on(IN := in, PT := pt);
off(IN := fall, PT := pt);
pulse(IN := in, PT := pt);
END_PROGRAM
"""


def test_a_larger_pt_after_the_time_elapsed_changes_no_output(tmp_path: Path) -> None:
    """PT grows from 200 to 500 ms in cycle 6, after each timer's time has elapsed: TON's Q
    stays TRUE until IN falls (as matiec and CODESYS), TOF's and TP's Q stay FALSE, and ET
    keeps the PT it reached."""
    t = sim_trace(
        tmp_path,
        CHANGING_PT,
        10,
        "T.in=TRUE@2",  # cycles 2..8
        "T.in=FALSE@9",
        "T.fall=TRUE@2",  # cycle 2 only
        "T.fall=FALSE@3",
        "T.pt=T#500ms@6",
    )
    assert bits(t["T.on.Q"]) == "0001111100"
    assert t["T.on.ET"] == [0, 0, 100, 200, 200, 200, 200, 200, 0, 0]
    assert bits(t["T.off.Q"]) == "0111000000"
    assert t["T.off.ET"] == [0, 0, 0, 100, 200, 200, 200, 200, 200, 200]
    assert bits(t["T.pulse.Q"]) == "0110000000"
    assert t["T.pulse.ET"] == [0, 0, 100, 200, 200, 200, 200, 200, 0, 0]


def test_pt_changed_while_timing_counts_against_the_new_pt(tmp_path: Path) -> None:
    """PT grows from 200 to 400 ms in cycle 3, while every timer is still timing: each runs
    to the new PT."""
    t = sim_trace(
        tmp_path,
        CHANGING_PT,
        10,
        "T.in=TRUE@2",
        "T.in=FALSE@9",
        "T.fall=TRUE@2",
        "T.fall=FALSE@3",
        "T.pt=T#400ms@3",
    )
    assert bits(t["T.on.Q"]) == "0000011100"
    assert t["T.on.ET"] == [0, 0, 100, 200, 300, 400, 400, 400, 0, 0]
    assert bits(t["T.off.Q"]) == "0111110000"
    assert t["T.off.ET"] == [0, 0, 0, 100, 200, 300, 400, 400, 400, 400]
    assert bits(t["T.pulse.Q"]) == "0111100000"
    assert t["T.pulse.ET"] == [0, 0, 100, 200, 300, 400, 400, 400, 0, 0]
