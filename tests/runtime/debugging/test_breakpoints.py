"""Breakpoints, steps, logpoints and the BKPT state on a resource in this process, on both
execution tiers: with a breakpoint armed the bodies run as Python, and back as C after."""

from __future__ import annotations

from typing import Any

import pytest

from backend.compiler.pipeline import compile_sources
from backend.compiler.source import SourceFile
from runtime import online_writes
from runtime.code.native.tier import NativeTier
from runtime.commands import HANDLERS
from runtime.contract import protocol as p
from runtime.contract.artifact import Artifact, ProgramConfig, ResourceConfig
from runtime.contract.protocol import ProgramState
from runtime.contract.refusal import Refusal
from runtime.resource import Resource
from tests.support.debugged_program import COUNTERS as SOURCE
from tests.support.native_runs import advance, same
from tests.support.native_runs import running as started

FILE = "prog.st"
PROGRAMS = [
    ProgramConfig(name="Main", pou="Main", program_id=1),
    ProgramConfig(name="Other", pou="Other", program_id=2, priority=1),
]


# the same lines without the interface variable, which keeps a configuration's values on
# objects: this one's go into native memory on the native tier
IN_NATIVE_MEMORY = (
    SOURCE.replace(" c : ICount;", "").replace("c := a;", "i := 0;").replace("c.Bump(", "a.Bump(")
)


def artifact(safety: bool = False, source: str = SOURCE) -> Artifact:
    config = ResourceConfig(name="R", watchdog_ms=5_000, safety_operation=safety)
    result = compile_sources([SourceFile(FILE, source)], resource=config, programs=PROGRAMS)
    assert result.artifact is not None, result.diagnostics
    return result.artifact


_RUNNING: list[Resource] = []


def running(built: Artifact, tier: NativeTier | None) -> Resource:
    resource = started(built, tier)
    _RUNNING.append(resource)
    return resource


@pytest.fixture(autouse=True)
def stopped_after() -> Any:
    """Each test's resources stopped at its end: a program left in BKPT is let go of (its
    greenlet stands inside the tracer, which holds this thread's tracing until then)."""
    yield
    while _RUNNING:
        _RUNNING.pop().stop()


@pytest.fixture(params=["python", "native"])
def tier(request: pytest.FixtureRequest) -> NativeTier | None:
    if request.param == "python":
        return None
    native: NativeTier = request.getfixturevalue("native_tier")
    return NativeTier(native.cache, native.toolchain)


def ask(resource: Resource, command: p.Command[Any]) -> Any:
    """A command as the bus would bring it (decoded from its wire form first)."""
    decoded = p.decode_request(p.encode_request(command, None)).command
    return HANDLERS[type(decoded)](resource, decoded)


def debug_set(resource: Resource, *specs: p.BreakpointSpec) -> p.DebugState:
    state: p.DebugState = ask(resource, p.DebugSet(FILE, list(specs))).debug
    return state


def paused(resource: Resource) -> p.DebugPause | None:
    pause: p.DebugPause | None = ask(resource, p.DebugGet()).debug.paused
    return pause


def cycles(resource: Resource, count: int) -> None:
    for _ in range(count):
        advance(resource)


def program(resource: Resource, name: str) -> p.ProgramStatus:
    return next(x for x in resource.status().programs if x.name == name)


def native_bodies(resource: Resource) -> bool:
    """Whether the bodies run as C now: the call of Main's counter's class (a view class
    while the values are in native memory) is not the Python function."""
    counter = resource.variables.program("Main").instance.a
    return not hasattr(type(counter).__dict__["__call__"], "__code__")


def test_a_breakpoint_for_one_instance_stops_only_there(tier: NativeTier | None) -> None:
    resource = running(artifact(), tier)
    cycles(resource, 2)
    state = debug_set(resource, p.BreakpointSpec(17, instance="Main.b", condition="step = 2"))
    assert state.breakpoints[0].verified and state.breakpoints[0].line == 17
    cycles(resource, 1)
    where = paused(resource)
    assert where == p.DebugPause("Main", "Counter", FILE, 17, "breakpoint", 1)
    frames = ask(resource, p.DebugStack("Main")).frames
    assert [(f.name, f.instance, f.line) for f in frames] == [
        ("Counter", "Main.b", 17),
        ("Main", "Main", 29),
    ]
    # a.total was written this cycle (a ran first); b stands before its first statement
    shown = {v.name: v for v in ask(resource, p.DebugVariables("Main", 0)).variables}
    assert shown["step"].value == 2 and shown["step"].path == "Main.b.step"
    status = program(resource, "Main")
    assert status.state == ProgramState.BKPT and status.paused_at == f"{FILE}:17 (POU Counter)"
    assert resource.status().state == p.ResourceState.RUN  # held, not stopped
    # the other program runs on while Main stands
    before = program(resource, "Other").cycles
    cycles(resource, 5)
    assert program(resource, "Other").cycles == before + 5
    assert program(resource, "Main").state == ProgramState.BKPT
    ask(resource, p.DebugClear())
    cycles(resource, 1)
    assert program(resource, "Main").state == ProgramState.RUN and paused(resource) is None


ENDLESS = """
PROGRAM Main
VAR n : DINT; END_VAR
WHILE TRUE DO n := n + 1; END_WHILE;
END_PROGRAM
"""


def test_a_breakpoint_stops_after_the_watchdog_struck_in_this_process(
    tier: NativeTier | None,
) -> None:
    # the watchdog's exception used to be taken back in a way that left CPython's "pending
    # exception" signal on for good: every later debug run in the process spun at the
    # entry of the first POU it traced until the watchdog ended the cycle again
    config = ResourceConfig(name="R", watchdog_ms=100)
    endless = compile_sources([SourceFile(FILE, ENDLESS)], resource=config).artifact
    assert endless is not None
    resource = running(endless, tier)
    cycles(resource, 1)
    assert resource.state == p.ResourceState.ERROR_STOP
    assert "watchdog" in (resource.error or "")
    resource.init()  # a cold start of another configuration, debugged
    resource.load(artifact())
    resource.tier_up(wait=True)
    resource.start()
    cycles(resource, 2)
    debug_set(resource, p.BreakpointSpec(17, instance="Main.b", condition="step = 2"))
    cycles(resource, 1)
    assert paused(resource) == p.DebugPause("Main", "Counter", FILE, 17, "breakpoint", 1)
    assert resource.status().state == p.ResourceState.RUN  # held, not stopped


def test_step_into_a_method_through_an_interface_and_out_again(tier: NativeTier | None) -> None:
    resource = running(artifact(), tier)
    debug_set(resource, p.BreakpointSpec(31))  # n := c.Bump(by := 3);
    cycles(resource, 1)
    assert paused(resource) == p.DebugPause("Main", "Main", FILE, 31, "breakpoint", 1)
    into = ask(resource, p.DebugStep("Main", "into")).debug.paused
    assert (into.pou, into.line, into.reason) == ("Counter", 21, "step")
    frames = ask(resource, p.DebugStack("Main")).frames
    assert (frames[0].kind, frames[0].name, frames[0].instance) == (
        "method",
        "Counter.BUMP",
        "Main.a",
    )
    local = {v.name: v.value for v in ask(resource, p.DebugVariables("Main", 0)).variables}
    assert local["by"] == 3
    over = ask(resource, p.DebugStep("Main", "over")).debug.paused
    assert (over.pou, over.line) == ("Counter", 22)
    out = ask(resource, p.DebugStep("Main", "out")).debug.paused
    assert (out.pou, out.line) == ("Main", 32)  # the rest of line 31 ran; the FOR is next
    assert ask(resource, p.DebugVariables("Main", 0)).variables[3].name == "n"


def test_a_breakpoint_in_a_function_shows_its_locals(tier: NativeTier | None) -> None:
    resource = running(artifact(), tier)
    debug_set(resource, p.BreakpointSpec(11, program="Main"))  # Twice := tmp;
    cycles(resource, 1)
    frames = ask(resource, p.DebugStack("Main")).frames
    assert [(f.kind, f.name) for f in frames] == [
        ("function", "Twice"),
        ("function block", "Counter"),
        ("program", "Main"),
    ]
    local = {v.name: v.value for v in ask(resource, p.DebugVariables("Main", 0)).variables}
    assert local == {"x": 1, "Twice": 0, "tmp": 2}
    # to the end of the program cycle; a step from there begins the next one
    end = ask(resource, p.DebugStep("Main", "cycle")).debug.paused
    assert (end.line, end.reason) == (0, "cycle end")
    first = ask(resource, p.DebugStep("Main", "over")).debug.paused
    assert (first.pou, first.line) == ("Main", 28)


def test_hit_count_and_writes_at_a_break(tier: NativeTier | None) -> None:
    resource = running(artifact(), tier)
    state = debug_set(resource, p.BreakpointSpec(33, hit_count=5))  # n := n + i; 3 a cycle
    cycles(resource, 1)
    assert paused(resource) is None
    cycles(resource, 1)
    assert paused(resource) is not None
    i = {v.name: v.value for v in ask(resource, p.DebugVariables("Main", 0)).variables}["i"]
    assert i == 2  # the fifth pass: the second of the second cycle
    assert ask(resource, p.DebugGet()).debug.breakpoints[0].hits == 5
    # the file's points sent again with one more: the first keeps its id and its hits
    again = debug_set(resource, p.BreakpointSpec(33, hit_count=5), p.BreakpointSpec(28))
    assert [(b.id, b.hits) for b in again.breakpoints] == [(1, 5), (2, 0)]
    online_writes.write(resource, "Main.n", 1000)  # writes are allowed at a break
    ask(resource, p.DebugStep("Main", "over"))
    n = {v.name: v.value for v in ask(resource, p.DebugVariables("Main", 0)).variables}["n"]
    assert n == 1002
    assert state.breakpoints[0].spec.hit_count == 5


def assert_seven_cycles_alike(debugged: Resource, plain: Resource) -> None:
    """Main had seven program cycles on both, and every value is the same."""
    assert program(debugged, "Main").cycles == program(plain, "Main").cycles == 7
    ours, theirs = debugged.variables.read_values()(), plain.variables.read_values()()
    assert sorted(ours) == sorted(theirs)
    assert all(same(ours[path], theirs[path]) for path in ours), (ours, theirs)


def test_native_bodies_give_way_while_armed_and_the_values_are_the_same(
    native_tier: NativeTier,
) -> None:
    debugged = running(artifact(), NativeTier(native_tier.cache, native_tier.toolchain))
    plain = running(artifact(), None)
    assert native_bodies(debugged)
    cycles(debugged, 3)
    cycles(plain, 3)
    debug_set(debugged, p.BreakpointSpec(18))
    assert not native_bodies(debugged)
    cycles(debugged, 1)  # Main stops in its fourth program cycle ...
    assert paused(debugged) is not None
    ask(debugged, p.DebugStep("Main", "cycle"))  # ... which a step finishes
    ask(debugged, p.DebugClear())  # Main runs on, as C again
    assert native_bodies(debugged)
    cycles(debugged, 3)
    cycles(plain, 4)
    assert_seven_cycles_alike(debugged, plain)


def test_in_native_memory_the_values_leave_for_a_breakpoint_and_come_back_after(
    native_tier: NativeTier,
) -> None:
    """Armed, the values move to objects between two cycles (the debugger knows instances
    by identity), the program stops and steps there; cleared, they go back into native
    memory and the bodies run as C on it again, the values those of a run never debugged."""
    built = artifact(source=IN_NATIVE_MEMORY)
    debugged = running(built, NativeTier(native_tier.cache, native_tier.toolchain))
    plain = running(built, None)
    assert debugged.variables.image is not None and native_bodies(debugged)
    cycles(debugged, 3)
    cycles(plain, 3)
    debug_set(debugged, p.BreakpointSpec(18))
    debugged.tier_up()  # between two cycles, as the cycle driver does
    assert debugged.variables.image is None and not native_bodies(debugged)
    cycles(debugged, 1)
    pause = paused(debugged)
    assert pause is not None and pause.line == 18
    ask(debugged, p.DebugStep("Main", "cycle"))
    ask(debugged, p.DebugClear())
    debugged.tier_up()
    assert debugged.variables.image is not None and native_bodies(debugged)
    cycles(debugged, 3)
    cycles(plain, 4)
    assert_seven_cycles_alike(debugged, plain)


def test_a_logpoint_records_without_stopping_and_is_rate_bounded() -> None:
    resource = running(artifact(), None)
    debug_set(resource, p.BreakpointSpec(33, log=["i", "n * 2"]))
    cycles(resource, 30)  # 90 hits in 3 s of virtual time
    assert paused(resource) is None and program(resource, "Main").cycles == 30
    logged = [e.message for e in resource.events.recent(0, 1000) if e.kind == "log"]
    assert logged[0].startswith(f"{FILE}:33 in Main: i = 1, n * 2 = ")
    assert len(logged) < 90  # 20 at once, 20 a second after
    assert any("more hits not logged" in message for message in logged)


def test_conditions_read_time_literals_and_logpoints_show_st_literals() -> None:
    resource = running(artifact(), None)
    debug_set(
        resource,
        p.BreakpointSpec(33, condition="T#1s500ms > T#1s AND i >= 2"),
        p.BreakpointSpec(28, log=["n > 5", "T#2s", "3.5", "a.total"]),
    )
    cycles(resource, 1)
    assert paused(resource) == p.DebugPause("Main", "Main", FILE, 33, "breakpoint", 1)
    logged = [e.message for e in resource.events.recent(0, 1000) if e.kind == "log"]
    assert logged == [f"{FILE}:28 in Main: n > 5 = FALSE, T#2s = T#2s, 3.5 = 3.5, a.total = 0"]


def test_a_silent_client_lets_the_program_continue() -> None:
    resource = running(artifact(), None)
    ask(resource, p.DebugOptions(5))
    debug_set(resource, p.BreakpointSpec(28))
    cycles(resource, 1)
    assert program(resource, "Main").state == ProgramState.BKPT
    cycles(resource, 49)  # 4.9 s
    assert program(resource, "Main").state == ProgramState.BKPT
    cycles(resource, 3)
    assert program(resource, "Main").state == ProgramState.RUN
    assert ask(resource, p.DebugGet()).debug.breakpoints == []
    messages = [e.message for e in resource.events.recent(0, 1000) if e.kind == "debug"]
    assert "no debug command for 5 s: breakpoints cleared, the program continues" in messages


def test_refused_in_safety_operation_and_a_bad_condition_is_not_armed() -> None:
    safe = running(artifact(safety=True), None)
    with pytest.raises(Refusal) as refused:
        debug_set(safe, p.BreakpointSpec(28))
    assert refused.value.code == "safety_operation"
    resource = running(artifact(), None)
    state = debug_set(
        resource,
        p.BreakpointSpec(28, condition="n >"),
        p.BreakpointSpec(2),
        p.BreakpointSpec(500),
        p.BreakpointSpec(28, program="Nobody"),
        p.BreakpointSpec(28, condition="(" * 250 + "1" + ")" * 250),
    )
    messages = [(b.verified, b.line, b.message) for b in state.breakpoints]
    assert messages[0] == (False, 0, "'n >': more expected")
    assert messages[1] == (True, 10, None)  # moved to the first statement after line 2
    assert messages[2] == (False, 0, f"no statement at or after line 500 of {FILE}")
    assert messages[3] == (False, 0, "no program 'Nobody'")
    assert messages[4][2] is not None and messages[4][2].endswith("nested too deep")


def test_a_stop_ends_the_break_and_a_reload_waits_for_continue() -> None:
    resource = running(artifact(), None)
    debug_set(resource, p.BreakpointSpec(28))
    cycles(resource, 1)
    with pytest.raises(Refusal) as refused:
        resource.debugger.refuse_reload()
    assert "continue it before an online change" in refused.value.message
    resource.stop()
    assert program(resource, "Main").state == ProgramState.STOP and paused(resource) is None
    resource.start()
    cycles(resource, 1)  # the breakpoint stays armed for the next start
    assert paused(resource) == p.DebugPause("Main", "Main", FILE, 28, "breakpoint", 1)


CHART = """\
PROGRAM Chart
VAR go : BOOL; n : INT; END_VAR
INITIAL_STEP Idle :
END_STEP

STEP Busy :
  Work(N);
END_STEP

TRANSITION FROM Idle TO Busy := go;
END_TRANSITION

TRANSITION FROM Busy TO Idle := n >= 3;
END_TRANSITION

ACTION Work :
  n := n + 1;
END_ACTION
END_PROGRAM
"""


def test_breakpoints_at_a_step_and_a_transition_of_a_chart(tier: NativeTier | None) -> None:
    config = ResourceConfig(name="R", watchdog_ms=5_000, safety_operation=False)
    programs = [ProgramConfig(name="Chart", pou="Chart", program_id=1)]
    result = compile_sources([SourceFile(FILE, CHART)], resource=config, programs=programs)
    assert result.artifact is not None, result.diagnostics
    resource = running(result.artifact, tier)
    state = debug_set(resource, p.BreakpointSpec(6))  # STEP Busy: stops while it is active
    assert state.breakpoints[0].verified
    cycles(resource, 3)
    assert paused(resource) is None  # Busy is not active: `go` is FALSE
    online_writes.write(resource, "Chart.go", True)
    cycles(resource, 2)  # the transition fires; in the next cycle Busy is active
    where = paused(resource)
    assert where is not None and (where.pou, where.line) == ("Chart", 6)
    ask(resource, p.DebugClear())
    debug_set(resource, p.BreakpointSpec(13))  # TRANSITION FROM Busy TO Idle
    cycles(resource, 1)
    where = paused(resource)
    assert where is not None and where.line == 13
    shown = {v.name: v.value for v in ask(resource, p.DebugVariables("Chart", 0)).variables}
    assert shown["go"] is True and shown["n"] >= 1


WRITER = """\
VAR_GLOBAL out1, out2 : INT; END_VAR
PROGRAM Writer
out1 := out1 + 1;
out2 := out2 + 1;
END_PROGRAM
PROGRAM Reader
VAR seen : INT; END_VAR
seen := out1;
END_PROGRAM
"""


def test_at_a_break_what_the_program_wrote_so_far_is_out(tier: NativeTier | None) -> None:
    config = ResourceConfig(name="R", watchdog_ms=5_000, safety_operation=False)
    programs = [
        ProgramConfig(name="Writer", pou="Writer", program_id=1),
        ProgramConfig(name="Reader", pou="Reader", program_id=2, priority=1),
    ]
    result = compile_sources([SourceFile(FILE, WRITER)], resource=config, programs=programs)
    assert result.artifact is not None, result.diagnostics
    resource = running(result.artifact, tier)
    cycles(resource, 2)
    debug_set(resource, p.BreakpointSpec(4))  # out2 := out2 + 1;
    cycles(resource, 1)
    values = resource.variables.read_values()()
    assert (values["out1"], values["out2"]) == (3, 2)  # out1 written, out2 not yet
    cycles(resource, 1)
    assert resource.variables.read_values()()["Reader.seen"] == 3
