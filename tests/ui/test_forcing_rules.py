"""The rules behind the Forcing tab and the value edit, without a browser: the level of a
variable, the time limit as typed, the remaining time as shown, the banner, and how the
fields of the value edit are read."""

from __future__ import annotations

from frontend.forcing_feed import ForcingSnapshot
from frontend.screens.forcing import GLOBAL, duration, level_of, render_banner, time_limit
from frontend.screens.value_edit import read_edit
from runtime.contract import protocol as p
from runtime.contract.artifact import ProgramConfig, ResourceConfig

STATS = p.CycleStatistics(0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0, 0)
PROGRAM = p.ProgramStatus("TankControl", 1, 0, p.ProgramState.RUN, "", 0, 0, None)


def status(forcing: bool) -> p.Status:
    return p.Status(
        "Tank1", p.ResourceState.RUN, "92A62FF5", None, None, 1, 100.0, STATS, forcing,
        "users", None, [PROGRAM],
    )  # fmt: skip


def test_a_variable_of_a_program_is_forced_locally_the_others_globally() -> None:
    assert level_of("TankControl.pump", status(False)) == "TankControl"
    assert level_of("tankcontrol.refillDelay.Q", status(False)) == "TankControl"
    assert level_of("SYS.FORCE_DEACTIVATION", status(False)) == GLOBAL
    assert level_of("TankControl", status(False)) == GLOBAL  # a global of that name


def test_the_time_limit_is_a_time_literal_and_empty_means_none() -> None:
    assert time_limit("T#5m") == (300_000, "")
    assert time_limit("t#1h30m") == (5_400_000, "")
    assert time_limit("  ") == (None, "")
    assert time_limit("5 minutes")[1] == "5 minutes is no time: write it as T#5m, T#90s or T#1h30m"
    assert time_limit("T#2d")[1] == "the time limit is from T#1ms to T#24h"


def test_the_remaining_time_reads_as_a_person_says_it() -> None:
    assert duration(252.0) == "4 min 12 s"
    assert duration(299.2) == "5 min 0 s"  # counts 0 s only when it is over
    assert duration(3900) == "1 h 05 min"
    assert duration(0) == "0 s"


def test_the_banner_shows_while_forcing_runs_with_its_values_and_time_left() -> None:
    state = p.ForcingState(
        started=["", "TankControl"],
        remaining_ms={"global": 252_000.0, "TankControl": None},
        entries=[
            p.ForceInfo("TankControl.pump", "TankControl", False, True, True),
            p.ForceInfo("TankControl.level", "TankControl", 5, False, False),
        ],
    )
    parameters = p.ParametersReply(
        ResourceConfig("Tank1"), [ProgramConfig("TankControl", "TankControl", 1)]
    )
    snapshot = ForcingSnapshot("Tank1", state, fetched=100.0, parameters=parameters)
    shown = render_banner(status(True), snapshot, now=100.0)
    assert "FORCING ACTIVE — 1 value forced · global, 4 min 12 s left; local TankControl, " \
        "no time limit" in shown  # fmt: skip
    assert render_banner(status(True), snapshot, now=110.0).count("4 min 2 s left") == 1
    assert render_banner(status(False), snapshot, now=100.0) == ""
    assert "FORCING ACTIVE</div>" in render_banner(status(True), None, now=100.0)


def test_the_value_edit_reads_the_variable_case_insensitively_and_checks_the_literal() -> None:
    types = {"TankControl.level": "INT", "TankControl.pump": "BOOL", "TankControl.lowLevel": "INT"}
    assert read_edit("tankcontrol.PUMP", "false", types).value is False
    assert read_edit("TankControl.level", "16#10", types).value == 16
    assert read_edit("TankControl.level", "ten", types).value_problem == (
        "ten is not an ST literal of type INT"
    )
    assert read_edit("TankControl.level", "", types).value_problem == "type the new value"
    unknown = read_edit("level", "1", types)
    assert unknown.path is None and unknown.variable_problem == "no variable level"
    assert unknown.matches == ("TankControl.level", "TankControl.lowLevel")
