"""Resource and program states (spec section 4), single step (12), parameters (6) and the
system variables that act on the resource (7), driven through the command handler."""

from __future__ import annotations

import pytest

from backend.compiler.pipeline import compile_sources
from backend.compiler.source import SourceFile
from tests.support.resource_harness import harness

TWO = """
VAR_GLOBAL
  valve AT %QX0.0 : BOOL;
  speed AT %QW1 : INT;
  level AT %IW0 : INT;
END_VAR
PROGRAM Control
VAR_EXTERNAL valve : BOOL; speed : INT; level : INT; END_VAR
VAR n : DINT; seen : INT; END_VAR
n := n + 1;
seen := level;
valve := TRUE;
speed := 1200;
END_PROGRAM
PROGRAM Clock
VAR t : TON; n : DINT; q : BOOL; END_VAR
n := n + 1;
t(IN := TRUE, PT := T#50ms);
q := t.Q;
END_PROGRAM
"""
PROGRAMS = [{"name": "Control"}, {"name": "Clock", "priority": 1}]


def test_outputs_are_safe_in_stop_and_live_in_run() -> None:
    h = harness(TWO, PROGRAMS, start=False)
    assert h.resource.io.outputs == {"valve": False, "speed": 0}
    h.ok("start")
    h.cycle()
    assert h.resource.io.outputs == {"valve": True, "speed": 1200}
    h.ok("stop")
    assert h.state() == "STOP/VALID CONFIGURATION"
    assert h.resource.io.outputs == {"valve": False, "speed": 0}
    assert h.value("valve") is True  # the variable keeps its value; the field gets 0


def test_an_output_can_have_its_own_safe_value() -> None:
    # a valve that must open to be safe (energise to trip), and a speed held at 300
    h = harness(TWO, PROGRAMS, start=False, safe_values={"valve": True, "SPEED": 300})
    assert h.resource.io.outputs == {"valve": True, "speed": 300}
    h.ok("start")
    h.cycle()
    h.ok("write", variable="Control.n", value=0)
    h.resource.error_stop("test")
    assert h.resource.io.outputs == {"valve": True, "speed": 300}


def test_a_safe_value_must_fit_a_located_output() -> None:
    for values, message in (
        ({"level": 1}, "safe value for 'level': no global output (%Q)"),
        (
            {"speed": 70000},
            "safe value for 'speed': 70000 is outside the range of INT (-32768..32767)",
        ),
        ({"nothing": True}, "safe value for 'nothing': no global output (%Q)"),
    ):
        result = compile_sources([SourceFile("t.st", TWO)], safe_values=values)
        assert [d.message for d in result.diagnostics] == [message]


def test_inputs_are_read_at_the_start_of_the_cycle() -> None:
    h = harness(TWO, PROGRAMS)
    h.resource.io.set_inputs({"level": 42})
    h.cycle()
    assert h.value("Control.seen") == 42


def test_run_up_stop_when_no_program_runs_and_programs_start_on_their_own() -> None:
    h = harness(TWO, PROGRAMS)
    h.cycle()
    h.ok("stop_program", program="Control")
    assert h.state("Control") == "STOP"
    h.cycle(2)
    assert h.value("Control.n") == 1 and h.value("Clock.n") == 3
    h.ok("stop_program", program="Clock")
    assert h.state() == "RUN/UP STOP"
    h.ok("start_program", program="Control")
    assert h.state() == "RUN"
    h.cycle()
    assert h.value("Control.n") == 2


def test_start_allowed_off_keeps_a_program_stopped() -> None:
    h = harness(TWO, [{"name": "Control", "start_allowed": False}, {"name": "Clock"}])
    h.cycle()
    assert h.state("Control") == "STOP"
    assert h.refused("start_program", program="Control") == "not_allowed"


def test_a_runtime_error_names_program_pou_and_line_and_a_start_restarts_it_cold() -> None:
    text = """
    FUNCTION_BLOCK Divider
    VAR_INPUT d : INT; END_VAR
    VAR_OUTPUT q : INT; END_VAR
    q := 100 / d;
    END_FUNCTION_BLOCK
    PROGRAM P
    VAR div : Divider; d : INT := 5; n : INT; END_VAR
    n := n + 1;
    div(d := d);
    END_PROGRAM
    PROGRAM Other VAR n : INT; END_VAR n := n + 1; END_PROGRAM
    """
    h = harness(text, [{"name": "P"}, {"name": "Other"}])
    h.cycle()
    h.ok("write", variable="P.d", value=0)
    h.cycle(2)
    assert h.state("P") == "ERROR"
    assert h.value("Other.n") == 3
    error = [e for e in h.ok("events")["events"] if e["kind"] == "error"][-1]
    assert error["details"] == {
        "program": "P",
        "pou": "Divider",
        "file": "test.st",
        "line": 5,
        "cause": "integer division by zero",
    }
    h.ok("start_program", program="P")
    assert h.state("P") == "RUN"
    h.cycle()
    assert (h.value("P.n"), h.value("P.d")) == (1, 5)  # from its initial values


def test_error_stop_needs_init_and_init_cold_starts() -> None:
    text = """
    PROGRAM P
    VAR n : INT; END_VAR
    n := n + 1;
    IF n = 3 THEN SYS.EMERGENCY_STOP_2 := TRUE; END_IF;
    END_PROGRAM
    """
    h = harness(text)
    h.cycle(3)
    assert h.state() == "ERROR STOP"
    assert "Emergency Stop 2" in str(h.resource.status().error)
    assert h.refused("start") == "state"
    h.ok("init")
    assert h.state() == "STOP/VALID CONFIGURATION"
    h.ok("start")
    h.cycle()
    assert h.value("P.n") == 1  # cold: from the initial values


def test_an_emergency_stop_set_within_a_time_slice_stops_the_resource_too() -> None:
    # a program with a time slice runs by another path than one without
    text = """
    PROGRAM P
    VAR n, i : INT; END_VAR
    n := n + 1;
    FOR i := 1 TO 3 DO END_FOR;
    IF n = 2 THEN SYS.EMERGENCY_STOP_4 := TRUE; END_IF;
    END_PROGRAM
    """
    h = harness(text, [{"name": "P", "max_duration_us": 1_000}])
    h.cycle()
    assert h.state() == "RUN"
    h.cycle()
    assert h.state() == "ERROR STOP"
    assert "Emergency Stop 4" in str(h.resource.status().error)


def test_coldstart_and_start_cycle_flags_are_true_in_the_first_cycle_only() -> None:
    text = """
    PROGRAM P
    VAR cold, first : INT; n : INT; END_VAR
    n := n + 1;
    IF SYS.COLDSTART THEN cold := n; END_IF;
    IF SYS.START_CYCLE THEN first := first + 1; END_IF;
    END_PROGRAM
    """
    h = harness(text)
    h.cycle(3)
    assert (h.value("P.cold"), h.value("P.first")) == (1, 1)
    h.ok("stop")
    h.ok("start")  # a start after a stop: not a cold start, but a first cycle
    h.cycle(2)
    assert (h.value("P.cold"), h.value("P.first")) == (1, 2)


def test_read_only_in_run_blocks_stop_and_start() -> None:
    text = """
    VAR_GLOBAL lock : BOOL; END_VAR
    PROGRAM P VAR_EXTERNAL lock : BOOL; END_VAR SYS.READ_ONLY_IN_RUN := lock; END_PROGRAM
    """
    h = harness(text)
    h.ok("write", variable="lock", value=True)
    h.cycle()
    assert h.refused("stop") == "read_only"
    assert h.state() == "RUN"
    h.ok("write", variable="lock", value=False)
    h.cycle()
    h.ok("stop")


def test_single_step_freezes_one_program_while_the_others_run() -> None:
    h = harness(TWO, PROGRAMS)
    h.cycle(2)
    h.ok("freeze", program="Clock")
    assert h.state("Clock") == "RUN_FREEZE"
    h.cycle(5)
    assert (h.value("Control.n"), h.value("Clock.n")) == (7, 2)  # Clock stands still
    for step in range(1, 4):
        h.ok("step_program", program="Clock")
        assert h.value("Clock.n") == 2 + step
        # one step = one cycle interval (10 ms) of the program's own time
        assert h.value("Clock.t.ET") == (1 + step) * 10_000_000
    h.ok("step_program", program="Clock")
    h.ok("step_program", program="Clock")
    assert h.value("Clock.q") is True  # 50 ms after the timer started, as in operation
    h.ok("unfreeze", program="Clock")
    h.cycle()
    assert h.state("Clock") == "RUN" and h.value("Clock.n") == 8


def test_single_step_is_refused_in_safety_operation_and_without_freeze_allowed() -> None:
    safe = harness(TWO, PROGRAMS, safety_operation=True)
    assert safe.refused("freeze", program="Clock") == "safety_operation"
    no_freeze = harness(TWO, [{"name": "Control", "freeze_allowed": False}, {"name": "Clock"}])
    assert no_freeze.refused("freeze", program="Control") == "not_allowed"


def test_olt_writes_are_refused_in_safety_operation() -> None:
    h = harness(TWO, PROGRAMS, safety_operation=True)
    assert h.refused("write", variable="Control.n", value=5) == "safety_operation"


def test_online_parameter_changes_are_checked_and_logged() -> None:
    h = harness(TWO, PROGRAMS, watchdog_ms=100, safety_time_ms=600)
    h.ok("set_parameter", name="watchdog_ms", value=250)
    assert h.ok("parameters")["resource"]["watchdog_ms"] == 250
    assert h.refused("set_parameter", name="watchdog_ms", value=400) == "bad_value"  # > 600/2
    assert h.refused("set_parameter", name="watchdog_ms", value=3) == "bad_value"  # < 6
    assert h.refused("set_parameter", name="safety_time_ms", value=900) == "not_online"
    assert h.refused("set_parameter", name="multitasking_mode", value=2) == "not_online"
    h.ok("set_parameter", name="allow_online_settings", value=False)
    assert h.refused("set_parameter", name="target_cycle_ms", value=20) == "not_allowed"
    changes = [e for e in h.ok("events")["events"] if e["kind"] == "parameter"]
    assert [e["details"]["name"] for e in changes] == ["watchdog_ms", "allow_online_settings"]


@pytest.mark.parametrize(
    "bad",
    [
        {"cmd": "freeze"},
        {"cmd": "write", "variable": 3, "value": 1},
        {"cmd": "start_forcing", "timeout_ms": -1},
    ],
)
def test_bad_requests_get_structured_errors(bad: dict[str, object]) -> None:
    h = harness(TWO, PROGRAMS)
    name = str(bad.pop("cmd"))
    assert h.refused(name, **bad) == "bad_request"


def test_read_only_system_variables_carry_the_resource_values() -> None:
    text = """
    PROGRAM P
    VAR wd : TIME; crc : DWORD; last : TIME; tick : UDINT; n : INT; END_VAR
    n := n + 1;
    wd := SYS.WATCHDOG_TIME;
    crc := SYS.CONFIGURATION_CRC;
    last := SYS.CYCLE_TIME_LAST;
    tick := SYS.SYSTEM_TICK;
    END_PROGRAM
    """
    h = harness(text, watchdog_ms=150)
    h.cycle(4)
    assert h.value("P.wd") == 150_000_000
    assert h.value("P.crc") == int(str(h.resource.status().crc), 16)
    assert h.value("P.tick") == 30  # 3 cycles of 10 ms since the runtime came up
    assert h.value("P.last") == 0  # on virtual time a program without loops costs nothing
