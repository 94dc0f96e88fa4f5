"""The usual CPU cycle in C (runtime/cycle_core.py, padt_cycle.c) against the Python cycle,
its reference: two resources of one configuration on the native tier, one cycling in C
where it can, the other always in Python, compared after every cycle in everything a user
sees of a cycle: the values, the cycle statistics, the system variables, the programs'
states, errors and statistics, the outputs and the events."""

from __future__ import annotations

import random
import time
from collections.abc import Callable
from dataclasses import asdict, replace

import pytest

from runtime.clock import RealClock
from runtime.code.native.tier import NativeTier
from runtime.contract.artifact import ProgramConfig
from runtime.contract.refusal import Refusal
from runtime.online_writes import simulate
from runtime.program_control import start_program, stop_program
from runtime.resource import Resource
from tests.support.native_runs import CYCLE_NS, compiled, running, same

SOURCE = """
VAR_GLOBAL
    level AT %IW0 : INT;
    lamp AT %QX0.0 : BOOL;
    count : DINT;
    cold : BOOL;
    seen_tick : UDINT;
    last_cycle : TIME;
    stop_at : DINT := 1000;
    mirror : DINT;
END_VAR

PROGRAM Main
VAR n : INT; zero : INT; q : INT; t : TON; END_VAR
    n := n + 1;
    count := count + 1;
    IF SYS.COLDSTART THEN cold := TRUE; END_IF;
    seen_tick := SYS.SYSTEM_TICK;
    last_cycle := SYS.CYCLE_TIME_LAST;
    lamp := level > 10;
    t(IN := TRUE, PT := T#350ms);
    IF n = 6 THEN q := 10 / zero; END_IF;
    IF count >= stop_at THEN SYS.EMERGENCY_STOP_2 := TRUE; END_IF;
END_PROGRAM

PROGRAM Other
VAR k : INT; END_VAR
    k := k + 1;
    mirror := count * 2;
END_PROGRAM
"""

PROGRAMS = [
    ProgramConfig(name="Main", pou="Main", program_id=1, priority=1),
    ProgramConfig(name="Other", pou="Other", program_id=2, priority=2),
]


def seen(resource: Resource) -> dict[str, object]:
    """What a user sees of the resource after a cycle."""
    return {
        "state": resource.state,
        "error": resource.error,
        "cycle_count": resource.cycle_count,
        "stats": asdict(resource.stats),
        "system": asdict(resource.system),
        "programs": [
            (p.name, p.state, p.error, p.time_ns, asdict(p.stats)) for p in resource.programs
        ],
        "outputs": dict(resource.io.outputs),
        "events": [(e.kind, e.message, e.details) for e in resource.events.recent(0)],
    }


def in_c(resource: Resource) -> bool:
    """One CPU cycle in C when it is a usual one (True), else in Python (False)."""
    core = resource._core
    assert core is not None, "the native tier put no cycle core in place"
    if core.cycle():
        return True
    resource._core = None
    try:
        resource.cycle()
    finally:
        resource._core = core
    return False


def in_python(resource: Resource) -> None:
    core, resource._core = resource._core, None
    try:
        resource.cycle()
    finally:
        resource._core = core


Step = Callable[[Resource], None]


def run_side_by_side(
    tier: NativeTier, cycles: int, before: dict[int, Step], periods: list[int] | None = None
) -> list[bool]:
    """Both resources through `cycles` cycles, `before[n]` done to both before cycle n,
    the clock `periods[n - 1]` further after it (100 ms), the values moved into native
    memory or out between two cycles as the cycle driver has them (`tier_up`); which
    cycles ran in C."""
    artifact = compiled(SOURCE, PROGRAMS)
    c_side, python_side = running(artifact, tier), running(artifact, tier)
    ran_in_c = []
    for cycle in range(1, cycles + 1):
        refused = []
        for resource in (c_side, python_side):
            step = before.get(cycle)
            try:
                if step is not None:
                    step(resource)
            except Refusal as refusal:  # as a command is refused: the same on both sides
                refused.append(str(refusal))
            resource.tier_up()
        assert len(refused) in (0, 2) and len(set(refused)) < 2, refused
        ran_in_c.append(in_c(c_side))
        in_python(python_side)
        for resource in (c_side, python_side):
            period = periods[cycle - 1] if periods else CYCLE_NS
            resource.clock.advance(period)  # type: ignore[attr-defined]
        assert seen(c_side) == seen(python_side), f"cycle {cycle}"
        expected, found = python_side.variables.values(), c_side.variables.values()
        assert expected.keys() == found.keys()
        assert all(same(expected[k], found[k]) for k in expected), f"cycle {cycle}"
    return ran_in_c


def test_a_usual_cycle_runs_in_c_and_leaves_what_python_leaves(native_tier: NativeTier) -> None:
    """Two programs with views of their own, a timer, inputs delivered, an output, the first
    cycle's flags, a division by zero that puts Main in ERROR, and overruns of the target
    cycle time: every cycle in C, each leaving what the Python cycle leaves."""

    def deliver(value: int) -> Step:
        return lambda resource: resource.io.set_inputs({"level": value})

    def target_50_ms(resource: Resource) -> None:  # 100 ms cycles: each one overruns
        resource.params = replace(resource.params, target_cycle_ms=50)

    ran_in_c = run_side_by_side(native_tier, 12, {2: deliver(40), 3: target_50_ms, 9: deliver(3)})
    assert all(ran_in_c)


def test_an_emergency_stop_by_logic_halts_the_cycle_in_c_as_in_python(
    native_tier: NativeTier,
) -> None:
    """Main sets an Emergency Stop switch in the third cycle (count 3 >= 3): the cycle ends
    in ERROR STOP in C, Other not run; the cycles after it are not usual ones."""

    def stop_soon(resource: Resource) -> None:
        simulate(resource, "stop_at", 3)

    ran_in_c = run_side_by_side(native_tier, 5, {2: stop_soon})
    assert ran_in_c == [True, True, True, False, False]


@pytest.mark.parametrize("unusual", ["forcing", "tap", "stop"])
def test_an_unusual_cycle_is_left_to_python(native_tier: NativeTier, unusual: str) -> None:
    """Forcing started, the stores from outside kept for a recording, STOP: the Python
    cycle runs those, and both sides stay alike."""

    def make_unusual(resource: Resource) -> None:
        if unusual == "forcing":
            resource.params = replace(
                resource.params, safety_operation=False, global_forcing_allowed=True
            )
            resource.forcing.force("lamp", True)
            resource.forcing.start()
        elif unusual == "tap":
            resource.variables.tap = []
        else:
            resource.stop()

    ran_in_c = run_side_by_side(native_tier, 4, {3: make_unusual})
    assert ran_in_c == [True, True, False, False]


def _force(resource: Resource) -> None:
    resource.params = replace(resource.params, safety_operation=False, global_forcing_allowed=True)
    resource.forcing.force("lamp", True)
    resource.forcing.start()


def _target(ms: int) -> Step:
    def target(resource: Resource) -> None:
        resource.params = replace(resource.params, target_cycle_ms=ms)

    return target


# what may happen between two cycles, as commands and the I/O do it
ACTIONS: dict[str, Step] = {
    "inputs": lambda r: r.io.set_inputs({"level": r.cycle_count % 30}),
    "write": lambda r: simulate(r, "seen_tick", 7),
    "force": _force,
    "unforce": lambda r: r.forcing.stop(),
    "reset statistics": lambda r: r.reset_stats(),
    "target 50 ms": _target(50),
    "no target": _target(0),
    "stop Other": lambda r: stop_program(r, "Other"),
    "start Other": lambda r: start_program(r, "Other"),
    "restart Main": lambda r: start_program(r, "Main"),  # from ERROR: its fresh instance
    "stop": lambda r: r.stop(),
    "start": lambda r: r.start(),
}


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_random_commands_between_cycles_leave_both_cycles_alike(
    native_tier: NativeTier, seed: int
) -> None:
    """Commands drawn at random between cycles of random lengths (inputs, writes, forcing,
    statistics reset, target cycle time, programs stopped, started and restarted from
    ERROR, the resource stopped and started): after every cycle both sides alike."""
    draw = random.Random(seed)
    cycles = 60
    before = {
        n: ACTIONS[draw.choice(sorted(ACTIONS))]
        for n in range(2, cycles + 1)
        if draw.random() < 0.4
    }
    periods = [draw.choice([CYCLE_NS, 20_000_000, 170_000_000]) for _ in range(cycles)]
    ran_in_c = run_side_by_side(native_tier, cycles, before, periods)
    assert any(ran_in_c) and not all(ran_in_c)


def test_on_a_real_clock_the_statistics_of_cycles_in_c_add_up(native_tier: NativeTier) -> None:
    """Durations differ from run to run, so the C cycle's statistics are held to what the
    Python cycle's are by their definition: each cycle counted once, its duration added
    to the total, the least, the most and the mean kept, the system variables showing the
    statistics as the cycle began, DATE_AND_TIME the calendar time it began."""
    resource = Resource("R", RealClock())
    resource.native = native_tier
    resource.load(compiled(SOURCE, PROGRAMS))
    resource.tier_up(wait=True)
    resource.start()
    core = resource._core
    assert core is not None
    for _ in range(30):
        prior = asdict(resource.stats)
        wall_before = time.time_ns()
        assert core.cycle()
        wall_after = time.time_ns()
        stats, system = resource.stats, resource.system
        assert stats.count == prior["count"] + 1
        assert stats.last_ns == stats.total_ns - prior["total_ns"] >= 0
        least = stats.last_ns if prior["count"] == 0 else min(prior["min_ns"], stats.last_ns)
        assert (stats.min_ns, stats.max_ns) == (least, max(prior["max_ns"], stats.last_ns))
        assert stats.mean_ns == stats.total_ns // stats.count
        shown = [getattr(system, f"CYCLE_TIME_{name}") for name in ("LAST", "MIN", "MAX", "MEAN")]
        assert shown == [prior["last_ns"], prior["min_ns"], prior["max_ns"], prior["mean_ns"]]
        assert wall_before <= system.DATE_AND_TIME <= wall_after
        assert stats.last_period_ns > 0 or prior["count"] == 0
    assert resource.cycle_count == 30


def test_the_python_tier_cycles_in_python(native_tier: NativeTier) -> None:
    """Without the native tier (`--no-native-code`, no C compiler) there is no C cycle."""
    assert running(compiled(SOURCE, PROGRAMS), None)._core is None
    assert running(compiled(SOURCE, PROGRAMS), native_tier)._core is not None
