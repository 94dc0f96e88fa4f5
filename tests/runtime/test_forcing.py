"""Forcing (spec section 11): global and local levels, force switches, time limits and
their reactions, the automatic end on start / stop, Force Deactivation; every force is an
event with the old and new value."""

from __future__ import annotations

from tests.support.resource_harness import harness

PLANT = """
VAR_GLOBAL
  pump AT %QX0.0 : BOOL;
  level AT %IW0 : INT;
  alarm : BOOL;
  kill : BOOL;
END_VAR
PROGRAM Control
VAR_EXTERNAL pump : BOOL; level : INT; alarm : BOOL; END_VAR
VAR setpoint : INT := 50; n : DINT; END_VAR
n := n + 1;
pump := level < setpoint;
alarm := level > 90;
END_PROGRAM
PROGRAM Safety
VAR_EXTERNAL kill : BOOL; END_VAR
SYS.FORCE_DEACTIVATION := kill;
END_PROGRAM
"""
PROGRAMS = [{"name": "Control", "local_forcing_allowed": True}, {"name": "Safety"}]


def test_a_forced_input_replaces_what_the_io_delivers() -> None:
    h = harness(PLANT, PROGRAMS)
    h.ok("force", variable="level", value=95)
    h.resource.io.set_inputs({"level": 10})
    h.cycle()
    assert h.value("Control.n") == 1 and h.value("pump") is True  # prepared, not started
    h.ok("start_forcing")
    h.resource.io.set_inputs({"level": 10})
    h.cycle()
    assert (h.value("level"), h.value("alarm"), h.value("pump")) == (95, True, False)
    assert h.resource.io.outputs["pump"] is False
    forcing = h.ok("forcing")["forcing"]
    assert forcing["started"] == [""] and forcing["entries"][0]["active"] is True


def test_a_forced_output_wins_over_the_program() -> None:
    h = harness(PLANT, PROGRAMS)
    h.ok("start_forcing")
    h.ok("force", variable="pump", value=True)
    h.resource.io.set_inputs({"level": 80})  # the program says: pump off
    h.cycle(2)
    assert h.resource.io.outputs["pump"] is True
    h.ok("force", variable="pump", value=True, switch=False)  # switch OFF: not forced
    h.cycle()
    assert h.resource.io.outputs["pump"] is False


def test_local_forcing_needs_its_program_allowed_and_started() -> None:
    h = harness(PLANT, PROGRAMS)
    h.ok("force", variable="Control.setpoint", value=70)
    h.ok("start_forcing")  # global forcing does not force a local variable
    h.cycle()
    assert h.value("Control.setpoint") == 50
    h.ok("start_forcing", program="Control")
    h.cycle()
    assert h.value("Control.setpoint") == 70
    h.ok("stop_program", program="Control")  # a program stop ends its local forcing
    assert h.ok("forcing")["forcing"]["started"] == [""]
    other = harness(PLANT, [{"name": "Control"}, {"name": "Safety"}])
    assert other.refused("force", variable="Control.setpoint", value=1) == "not_allowed"


def test_forcing_is_refused_when_not_allowed() -> None:
    assert (
        harness(PLANT, PROGRAMS, global_forcing_allowed=False).refused(
            "force", variable="level", value=1
        )
        == "not_allowed"
    )
    assert (
        harness(PLANT, PROGRAMS, safety_operation=True).refused("force", variable="level", value=1)
        == "safety_operation"
    )


def test_the_time_limit_stops_forcing_or_the_resource() -> None:
    h = harness(PLANT, PROGRAMS)
    h.ok("force", variable="level", value=95)
    h.ok("start_forcing", timeout_ms=30)
    h.cycle(3)
    assert h.value("alarm") is True
    assert h.resource.system.FORCE_TIME_REMAINING == 10_000_000  # 30 ms - 2 cycles
    h.cycle()
    assert h.ok("forcing")["forcing"]["started"] == []
    assert h.state() == "RUN"

    strict = harness(PLANT, PROGRAMS, global_force_timeout_reaction="stop-resource")
    strict.ok("force", variable="level", value=95)
    strict.ok("start_forcing", timeout_ms=20)
    strict.cycle(3)
    assert strict.state() == "STOP/VALID CONFIGURATION"
    assert any("force time expired" in e["message"] for e in strict.ok("events")["events"])


def test_a_local_time_limit_can_stop_the_program() -> None:
    h = harness(
        PLANT,
        [
            {"name": "Control", "local_forcing_allowed": True,
             "local_force_timeout_reaction": "stop-program"},
            {"name": "Safety"},
        ],
    )  # fmt: skip
    h.ok("force", variable="Control.setpoint", value=1)
    h.ok("start_forcing", program="Control", timeout_ms=20)
    h.cycle(3)
    assert h.state("Control") == "STOP" and h.state("Safety") == "RUN"


def test_resource_stop_and_start_end_forcing() -> None:
    h = harness(PLANT, PROGRAMS)
    h.ok("force", variable="level", value=95)
    h.ok("start_forcing")
    h.ok("stop")
    assert h.ok("forcing")["forcing"]["started"] == []
    h.ok("start")
    h.ok("start_forcing")
    h.ok("stop")
    h.ok("start")
    assert h.ok("forcing")["forcing"]["started"] == []


def test_force_deactivation_ends_forcing_and_blocks_it() -> None:
    h = harness(PLANT, PROGRAMS)
    h.ok("force", variable="level", value=95)
    h.ok("start_forcing")
    h.ok("write", variable="kill", value=True)
    h.cycle(2)
    assert h.ok("forcing")["forcing"]["started"] == []
    assert h.refused("force", variable="level", value=1) == "force_deactivated"
    assert h.refused("start_forcing") == "force_deactivated"


def test_every_force_and_write_is_an_event_with_old_and_new_value() -> None:
    h = harness(PLANT, PROGRAMS)
    h.cycle()
    h.ok("force", variable="Control.setpoint", value=70)
    h.ok("write", variable="Control.n", value=100)
    events = h.ok("events")["events"]
    force = next(e for e in events if e["kind"] == "force")
    write = next(e for e in events if e["kind"] == "write")
    assert force["details"] == {"variable": "Control.setpoint", "old": 50, "new": 70}
    assert write["details"] == {"variable": "Control.n", "old": 1, "new": 100}
    assert h.resource.events.long_term()[-1].kind == "write"
