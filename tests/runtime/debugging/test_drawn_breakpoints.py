"""A drawn body is debugged at its elements (docs/language.md, "Graphical bodies"): a
breakpoint on an element's line stops there, the drawing's hidden values are among the
variables, and a step goes to the next element in execution order; on both tiers."""

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
from runtime.resource import Resource
from tests.support.native_runs import advance
from tests.support.native_runs import running as started

FILE = "ladder.st"
LADDER = """PROGRAM Main
VAR start, stop, motor : BOOL; n : INT; END_VAR
LD
  1: LEFT_RAIL -> (_, _) {at 0 0}
  2: CONTACT start := 1 {at 40 0}
  3: CONTACT[NEGATED] stop := 2 {at 80 0}
  4: COIL motor := 3 {at 200 0}
  5: IN n {at 40 60}
  6: IN 1 {at 40 90}
  7: BLOCK ADD (EN := 4, IN1 := 5, IN2 := 6) -> (ENO, OUT) {at 100 60}
  8: OUT n := 7.OUT {at 200 60}
END_LD
END_PROGRAM
"""


def _artifact() -> Artifact:
    config = ResourceConfig(name="R", watchdog_ms=5_000, safety_operation=False)
    text = LADDER
    programs = [ProgramConfig(name="Main", pou="Main", program_id=1)]
    result = compile_sources([SourceFile(FILE, text)], resource=config, programs=programs)
    assert result.artifact is not None, result.diagnostics
    return result.artifact


def _ask(resource: Resource, command: p.Command[Any]) -> Any:
    decoded = p.decode_request(p.encode_request(command, None)).command
    return HANDLERS[type(decoded)](resource, decoded)


@pytest.fixture(params=["python", "native"])
def resource(request: pytest.FixtureRequest) -> Any:
    tier = None
    if request.param == "native":
        shared: NativeTier = request.getfixturevalue("native_tier")
        tier = NativeTier(shared.cache, shared.toolchain)
    running = started(_artifact(), tier)
    yield running
    running.stop()


def test_a_breakpoint_on_an_element_stops_there_and_steps_go_element_by_element(
    resource: Resource,
) -> None:
    online_writes.write(resource, "Main.start", True)
    advance(resource)
    state = _ask(resource, p.DebugSet(FILE, [p.BreakpointSpec(7, condition="n >= 2")])).debug
    assert state.breakpoints[0].verified and state.breakpoints[0].line == 7
    for _ in range(4):
        advance(resource)
    pause = _ask(resource, p.DebugGet()).debug.paused
    assert (pause.file, pause.line, pause.reason) == (FILE, 7, "breakpoint")
    status = next(x for x in resource.status().programs if x.name == "Main")
    assert status.state == ProgramState.BKPT and status.paused_at == f"{FILE}:7 (POU Main)"
    shown = {v.name: v.value for v in _ask(resource, p.DebugVariables("Main", 0)).variables}
    assert shown["n"] == 2 and shown["_TMP_LD4"] is True and shown["motor"] is True
    # the coil, then the block (the IN elements have no statement), then the OUT element
    over = _ask(resource, p.DebugStep("Main", "over")).debug.paused
    assert (over.line, over.reason) == (10, "step")
    over = _ask(resource, p.DebugStep("Main", "over")).debug.paused
    assert (over.line, over.reason) == (11, "step")
    _ask(resource, p.DebugClear())
    advance(resource)
    assert next(x for x in resource.status().programs if x.name == "Main").state == (
        ProgramState.RUN
    )
