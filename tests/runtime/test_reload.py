"""Reload (online change, spec section 9) through the command path: preconditions, values
carried over by name, the five traps of step chains and actions reproduced and warned
about, a reload the budget refuses, forcing surviving, and the all-or-nothing download."""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import pytest

from runtime import reload_switch
from runtime.contract.artifact import crc32_hex
from runtime.reload import SwitchOverTooLong, switch_over
from tests.support.resource_harness import Harness, compiled, harness

PLANT = """
TYPE Point : STRUCT x : INT; y : REAL; END_STRUCT; END_TYPE
VAR_GLOBAL total : DINT; points : ARRAY[1..3] OF Point; END_VAR
FUNCTION_BLOCK Counter
VAR_INPUT go : BOOL; END_VAR
VAR count : INT; inner : TON; END_VAR
IF go THEN count := count + 1; END_IF;
inner(IN := go, PT := T#1s);
END_FUNCTION_BLOCK
PROGRAM Main
VAR_EXTERNAL total : DINT; points : ARRAY[1..3] OF Point; END_VAR
VAR c : Counter; level : INT; small : DINT; name : STRING[10] := 'tank'; END_VAR
VAR RETAIN kept : INT; END_VAR
c(go := TRUE);
level := level + 2;
small := small + 1;
kept := kept + 1;
total := total + 1;
points[2].x := points[2].x + 1;
END_PROGRAM
"""


def reload(h: Harness, text: str, **args: Any) -> dict[str, Any]:
    h.send(compiled(text, **args.pop("params", {})))
    return h.cmd("reload", **args)


def preview(h: Harness, text: str, **args: Any) -> dict[str, Any]:
    h.send(compiled(text))
    reply = h.ok("reload_preview", **args)
    plan: dict[str, Any] = reply["plan"]
    return plan


def actions(plan: dict[str, Any]) -> dict[str, str]:
    return {c["path"]: c["action"] for c in plan["changes"]}


def test_values_carry_over_by_name_through_fbs_and_arrays_of_structs() -> None:
    h = harness(PLANT)
    h.cycle(5)
    changed = PLANT.replace("level := level + 2;", "level := level + 20;")
    changed = changed.replace("small : DINT;", "small : INT;")  # narrowing: initialised
    changed = changed.replace("level : INT;", "level : DINT;")  # widening: converted
    changed = changed.replace("VAR RETAIN kept", "VAR RETAIN held")  # renamed: a new variable
    changed = changed.replace("kept := kept + 1;", "held := held + 1;")
    plan = preview(h, changed)
    summary = actions(plan)
    assert summary["Main.c.count"] == "kept"
    assert summary["Main.c.inner.ET"] == "kept"
    assert summary["Main.level"] == "converted"
    assert summary["Main.small"] == "initialised"
    assert (summary["Main.held"], summary["Main.kept"]) == ("new", "deleted")
    assert summary["points[2].x"] == "kept" and summary["total"] == "kept"
    assert plan["hazards"] == [] and plan["possible"] is True
    before = h.resource.variables.values()
    assert reload(h, changed)["ok"]
    after = h.resource.variables.values()
    for path in ("Main.c.count", "Main.c.inner.ET", "points[2].x", "total", "Main.name"):
        assert after[path] == before[path], path
    assert after["Main.level"] == before["Main.level"] == 10
    assert (after["Main.small"], after["Main.held"]) == (0, 0)
    h.cycle()
    assert h.value("Main.level") == 30  # the new code runs on the carried value
    assert h.value("Main.c.count") == 6 and h.value("total") == 6
    assert h.value("Main.c.inner.ET") == 50_000_000  # the FB's timer ran on


def test_a_rename_map_carries_values_and_renamed_instances_start_afresh() -> None:
    h = harness(PLANT)
    h.cycle(3)
    renamed = PLANT.replace("c : Counter;", "counter : Counter;").replace("c(go", "counter(go")
    renamed = renamed.replace("VAR RETAIN kept", "VAR RETAIN held")
    renamed = renamed.replace("kept := kept + 1;", "held := held + 1;")
    plan = preview(h, renamed)
    assert actions(plan)["Main.counter.count"] == "new"  # renamed FB instance: afresh
    mapped = preview(h, renamed, renames={"Main.counter": "Main.c", "Main.held": "Main.kept"})
    assert actions(mapped)["Main.counter.count"] == "kept"
    assert reload(h, renamed, renames={"Main.counter": "Main.c", "Main.held": "Main.kept"})["ok"]
    assert (h.value("Main.counter.count"), h.value("Main.held")) == (3, 3)


def test_preconditions_refuse_and_keep_the_old_configuration() -> None:
    stopped = harness(PLANT, start=False)
    assert reload(stopped, PLANT)["error"]["code"] == "state"

    h = harness(PLANT)
    h.cycle()
    crc = h.resource.status().crc
    refused = reload(h, PLANT, params={"safety_time_ms": 800})
    assert refused["error"]["code"] == "needs_download"
    assert "safety_time_ms" in refused["error"]["message"]
    h.resource.system.RELOAD_DEACTIVATION = True
    assert reload(h, PLANT)["error"]["code"] == "reload_deactivated"
    h.resource.system.RELOAD_DEACTIVATION = False
    h.resource.system.READ_ONLY_IN_RUN = True
    assert reload(h, PLANT)["error"]["code"] == "read_only"
    h.resource.system.READ_ONLY_IN_RUN = False
    assert h.resource.status().crc == crc
    events = [e for e in h.ok("events")["events"] if e["kind"] == "reload"]
    assert len(events) == 3 and all(e["details"]["old_crc"] == crc for e in events)

    off = harness(PLANT, reload_allowed=False)
    assert reload(off, PLANT, params={"reload_allowed": False})["error"]["code"] == "not_allowed"
    locked = harness(PLANT, [{"name": "Main", "reload_allowed": False}])
    change = PLANT.replace("level + 2", "level + 3")
    locked.send(compiled(change, [{"name": "Main", "reload_allowed": False}]))
    reply = locked.cmd("reload")
    assert reply["error"]["code"] == "needs_download"
    assert "Reload Allowed of program Main is OFF" in reply["error"]["message"]


def test_a_program_in_the_middle_of_its_cycle_is_not_switched() -> None:
    text = """
    PROGRAM Slow VAR i, k : DINT; END_VAR FOR i := 1 TO 10 DO k := k + 1; END_FOR; END_PROGRAM
    """
    programs = [{"name": "Slow", "max_duration_us": 4, "max_cycles": 5}]
    h = harness(text, programs)
    h.cycle()
    h.send(compiled(text.replace("k + 1", "k + 2"), programs))
    assert h.cmd("reload")["error"]["code"] == "busy"
    h.cycle(2)  # the program cycle ends
    h.send(compiled(text.replace("k + 1", "k + 2"), programs))
    assert h.ok("reload")["reload"]["carried"] > 0


def test_a_reload_over_budget_is_refused_and_the_old_configuration_runs_on() -> None:
    # a struct that gains a member: each of its 8,000 instances is copied into a new one,
    # 32,000 values at the estimated switch-over cost do not fit a 6 ms watchdog
    text = "PROGRAM Big VAR n : DINT; a : ARRAY[1..8000] OF Point; END_VAR n := n + 1; END_PROGRAM"
    text = "TYPE Point : STRUCT x, y, z, w : INT; END_STRUCT; END_TYPE\n" + text
    h = harness(text, watchdog_ms=6, safety_time_ms=20, target_cycle_ms=5)
    h.cycle(3)
    trace_before = [v["Big.n"] for v in h.trace]
    changed = text.replace("n := n + 1;", "n := n + 100;").replace("w : INT;", "w, v : INT;")
    h.send(compiled(changed, watchdog_ms=6, safety_time_ms=20, target_cycle_ms=5))
    refused = h.cmd("reload")
    assert refused["error"]["code"] == "budget", refused
    h.cycle(3)
    assert [v["Big.n"] for v in h.trace] == [*trace_before, 4, 5, 6]  # old code, same values
    # raising the watchdog for this reload (never below the project's value) lets it pass
    h.send(compiled(changed, watchdog_ms=6, safety_time_ms=20, target_cycle_ms=5))
    assert h.cmd("reload", watchdog_ms=5)["error"]["code"] == "bad_value"
    h.send(compiled(changed, watchdog_ms=6, safety_time_ms=20, target_cycle_ms=5))
    assert h.cmd("reload", watchdog_ms=100, target_cycle_ms=100)["ok"]
    h.cycle()
    assert h.value("Big.n") == 106


def test_forcing_survives_a_reload() -> None:
    h = harness(PLANT)
    h.ok("force", variable="total", value=500)
    h.ok("start_forcing")
    h.cycle()
    assert reload(h, PLANT.replace("level + 2", "level + 3"))["ok"]
    h.cycle()
    assert h.value("total") == 500
    assert h.ok("forcing")["forcing"]["started"] == [""]


# ---- the five traps (spec section 9), each warned about and then shown to be real

CHAIN = """
PROGRAM Chain
VAR go : BOOL; n : INT; END_VAR
n := n + 1;
INITIAL_STEP Idle: END_STEP
STEP Busy: END_STEP
STEP Done: END_STEP
TRANSITION FROM Idle TO Busy := go; END_TRANSITION
TRANSITION FROM Busy TO Done := FALSE; END_TRANSITION
TRANSITION FROM Done TO Idle := FALSE; END_TRANSITION
END_PROGRAM
"""


def busy_chain() -> Harness:
    h = harness(CHAIN)
    h.ok("write", variable="Chain.go", value=True)
    h.cycle(2)
    assert h.value("Chain.Busy.X") is True
    return h


def hazards(plan: dict[str, Any]) -> list[str]:
    return [h["kind"] for h in plan["hazards"]]


def test_deleting_the_active_step_leaves_no_active_step() -> None:
    h = busy_chain()
    without_busy = """
    PROGRAM Chain
    VAR go : BOOL; n : INT; END_VAR
    n := n + 1;
    INITIAL_STEP Idle: END_STEP
    STEP Done: END_STEP
    TRANSITION FROM Idle TO Done := go; END_TRANSITION
    TRANSITION FROM Done TO Idle := FALSE; END_TRANSITION
    END_PROGRAM
    """
    plan = preview(h, without_busy)
    assert hazards(plan) == ["active-step-deleted"]
    assert "step Busy of Chain is active" in plan["hazards"][0]["message"]
    assert reload(h, without_busy)["ok"]
    h.cycle(3)
    assert (h.value("Chain.Idle.X"), h.value("Chain.Done.X")) == (False, False)


def test_renaming_the_initial_step_while_another_is_active_gives_two_active_steps() -> None:
    h = busy_chain()
    h.ok("write", variable="Chain.go", value=False)  # Start -> Busy must not fire at once
    renamed = CHAIN.replace("Idle", "Start")
    plan = preview(h, renamed)
    assert "initial-step-renamed" in hazards(plan)
    assert reload(h, renamed)["ok"]
    h.cycle()
    assert (h.value("Chain.Start.X"), h.value("Chain.Busy.X")) == (True, True)


TIMED = """
PROGRAM Timed
VAR go : BOOL; late : BOOL; END_VAR
INITIAL_STEP Idle: END_STEP
STEP Wait: late(D, T#10s); END_STEP
TRANSITION FROM Idle TO Wait := go; END_TRANSITION
TRANSITION FROM Wait TO Idle := FALSE; END_TRANSITION
END_PROGRAM
"""


def test_deleting_a_timed_qualifier_lets_the_timer_expire_at_once() -> None:
    h = harness(TIMED)
    h.ok("write", variable="Timed.go", value=True)
    h.cycle(5)
    assert h.value("Timed.late") is False  # 10 s delay: far off
    changed = TIMED.replace("late(D, T#10s);", "late(N);")
    plan = preview(h, changed)
    assert hazards(plan) == ["timed-qualifier-deleted"]
    assert "qualifier D of action late in step Wait" in plan["hazards"][0]["message"]
    assert reload(h, changed)["ok"]
    h.cycle()
    assert h.value("Timed.late") is True  # at once, not after 10 s


SET = """
PROGRAM Latch
VAR go : BOOL; horn : BOOL; END_VAR
INITIAL_STEP Idle: END_STEP
STEP Alarm: horn(S); END_STEP
STEP Quiet: horn(R); END_STEP
TRANSITION FROM Idle TO Alarm := go; END_TRANSITION
TRANSITION FROM Alarm TO Quiet := NOT go; END_TRANSITION
TRANSITION FROM Quiet TO Idle := TRUE; END_TRANSITION
END_PROGRAM
"""


def test_deleting_an_s_qualifier_of_a_set_action_leaves_it_set() -> None:
    h = harness(SET)
    h.ok("write", variable="Latch.go", value=True)
    h.cycle(3)
    assert h.value("Latch.horn") is True
    changed = SET.replace("STEP Alarm: horn(S); END_STEP", "STEP Alarm: END_STEP")
    plan = preview(h, changed)
    assert hazards(plan) == ["set-qualifier-deleted"]
    assert "while the action is set" in plan["hazards"][0]["message"]
    assert reload(h, changed)["ok"]
    h.cycle(3)
    assert h.value("Latch.Alarm.X") is True
    assert h.value("Latch.horn") is True  # no step sets it any more, and it stays set


PULSE = """
PROGRAM Pulse
VAR go : BOOL; fired : INT; END_VAR
INITIAL_STEP Idle: Leave(R); END_STEP
STEP Run: Leave(P0); END_STEP
TRANSITION FROM Idle TO Run := go; END_TRANSITION
TRANSITION FROM Run TO Idle := NOT go; END_TRANSITION
ACTION Leave: fired := fired + 1; END_ACTION
END_PROGRAM
"""


def test_deleting_p0_while_its_flag_is_true_fires_the_trigger() -> None:
    h = harness(PULSE)
    h.ok("write", variable="Pulse.go", value=True)
    h.cycle(3)
    assert h.value("Pulse.fired") == 0  # P0 fires when the step is left: not yet
    changed = PULSE.replace("STEP Run: Leave(P0); END_STEP", "STEP Run: END_STEP")
    plan = preview(h, changed)
    assert hazards(plan) == ["p0-deleted"]
    assert "while its flag is TRUE" in plan["hazards"][0]["message"]
    assert reload(h, changed)["ok"]
    h.cycle()
    assert h.value("Pulse.fired") == 1  # fired although the step is still active


# ---- download: all or nothing


def test_a_corrupted_or_cut_transfer_is_refused_and_the_old_configuration_stays() -> None:
    h = harness(PLANT, start=False)
    crc = h.resource.status().crc
    h.ok("write", variable="Main.level", value=7)
    new = compiled(PLANT.replace("level + 2", "level + 5"))
    text = new.to_json()
    h.ok("transfer_begin", size=len(text), crc=crc32_hex(text))
    h.ok("transfer_chunk", offset=0, data=text[:1000])
    cut = h.cmd("load")
    assert cut["error"]["code"] == "transfer" and "incomplete" in cut["error"]["message"]
    corrupted = text[:500] + ("X" if text[500] != "X" else "Y") + text[501:]
    h.ok("transfer_begin", size=len(text), crc=crc32_hex(text))
    h.ok("transfer_chunk", offset=0, data=corrupted)
    bad = h.cmd("load")
    assert bad["error"]["code"] == "transfer" and "CRC" in bad["error"]["message"]
    assert h.resource.status().crc == crc and h.value("Main.level") == 7
    refusals = [e for e in h.ok("events")["events"] if e["kind"] == "load"]
    assert [e["details"]["old_crc"] for e in refusals[-2:]] == [crc, crc]
    h.send(new)
    assert h.ok("load")["status"]["crc"] == new.crc
    assert h.value("Main.level") == 0  # a download is a cold start
    h.ok("start")
    h.send(new)
    assert h.cmd("load")["error"]["code"] == "state"  # only in STOP


def test_a_reload_against_another_running_configuration_is_refused() -> None:
    h = harness(PLANT)
    running = h.resource.status().crc
    change = PLANT.replace("level + 2", "level + 3")
    h.send(compiled(change))
    assert h.cmd("reload", expected_crc="00000000")["error"]["code"] == "changed"
    assert h.resource.status().crc == running
    h.send(compiled(change))
    assert h.ok("reload", expected_crc=running)["reload"]["old_crc"] == running


def test_a_configuration_for_another_resource_is_refused() -> None:
    h = harness(PLANT, start=False)
    other = compiled(PLANT)
    foreign = replace(other, resource=replace(other.resource, name="Other")).with_crc()
    h.send(foreign)
    assert h.refused("load") == "resource"
    assert h.refused("transfer_begin", size=10, crc="0") == "bad_request"  # the decoder's


def test_a_switch_over_past_its_deadline_leaves_the_old_configuration_untouched() -> None:
    text = "PROGRAM Big VAR n : DINT; a : ARRAY[1..600] OF Point; END_VAR n := n + 1; END_PROGRAM"
    text = "TYPE Point : STRUCT x : INT; END_STRUCT; END_TYPE\n" + text
    h = harness(text)
    h.cycle(2)
    before = h.resource.variables.values()
    job = reload_switch.begin(h.resource, compiled(text.replace("n + 1", "n + 2")), {})
    job.prepare()
    assert job.prepared is not None and job.instances is not None
    with pytest.raises(SwitchOverTooLong):
        switch_over(job.prepared, job.instances, deadline_ns=0)  # long past
    assert h.resource.variables.values() == before
    assert h.resource.status().crc == job.old_artifact.crc
    h.cycle()
    assert h.value("Big.n") == 3  # the old code runs on
