"""Cold start, warm start and power failure (spec section 10): the context is saved
atomically; a valid one gives a warm start with every value and the active SFC steps back,
anything else a cold start; safety-related programs always cold-start. The kill test
pulls the plug (SIGKILL) at random moments and checks every restart."""

from __future__ import annotations

import json
import os
import random
import signal
import time
from pathlib import Path
from typing import Any

import pytest

from backend.compiler.pipeline import compile_sources
from backend.compiler.source import SourceFile
from backend.engineering.resource_client import ResourceClient
from runtime.clock import VirtualClock
from runtime.context import ContextInvalid, load_context, save_context
from runtime.contract.artifact import Artifact, ProgramConfig, ResourceConfig
from runtime.contract.state_folder import context_path
from runtime.online_writes import write
from runtime.program_control import start_program, stop_program
from runtime.resource import Resource
from runtime.restart import take_context, warm_start
from tests.support.runtime_process import (
    client_session,
    router,
    runtime_process,
    store_artifact,
    wait_until_answering,
)

PLANT = """
PROGRAM Counter
VAR n : DINT; t : TON; warm, cold : DINT; END_VAR
n := n + 1;
t(IN := TRUE, PT := T#1s);
IF SYS.WARMSTART THEN warm := warm + 1; END_IF;
IF SYS.COLDSTART THEN cold := cold + 1; END_IF;
END_PROGRAM
PROGRAM Chart
VAR go : BOOL; END_VAR
INITIAL_STEP Idle: END_STEP
STEP Busy: END_STEP
TRANSITION FROM Idle TO Busy := go; END_TRANSITION
TRANSITION FROM Busy TO Idle := NOT go; END_TRANSITION
END_PROGRAM
PROGRAM Trip
VAR n : DINT; END_VAR
n := n + 1;
END_PROGRAM
"""


def compiled(autostart: str = "off") -> Artifact:
    config = ResourceConfig(
        name="Plant", target_cycle_ms=10, autostart=autostart, safety_operation=False
    )
    programs = [
        ProgramConfig("Counter", "Counter", 1),
        ProgramConfig("Chart", "Chart", 2),
        ProgramConfig("Trip", "Trip", 3, safety_related=True),
    ]
    result = compile_sources([SourceFile("plant.st", PLANT)], resource=config, programs=programs)
    assert result.artifact is not None, [str(d) for d in result.diagnostics]
    return result.artifact


def powered_up(artifact: Artifact, path: Path) -> Resource:
    """A fresh resource on the same configuration, warm when the context is valid."""
    resource = Resource("Plant", VirtualClock())
    resource.load(artifact)
    saved = load_context(path, artifact.crc)
    if not isinstance(saved, ContextInvalid):
        warm_start(resource, saved)
    return resource


def run(resource: Resource, cycles: int) -> None:
    clock = resource.clock
    assert isinstance(clock, VirtualClock)
    for _ in range(cycles):
        resource.cycle()
        clock.advance(10_000_000)


def test_a_warm_start_restores_values_timers_and_steps(tmp_path: Path) -> None:
    artifact = compiled()
    first = powered_up(artifact, tmp_path / "context.json")
    first.start()
    write(first, "Chart.go", True)
    run(first, 30)
    before = first.variables.values()
    assert before["Chart.Busy.X"] is True and before["Counter.t.ET"] == 290_000_000
    context = take_context(first)
    assert context is not None
    save_context(tmp_path / "context.json", context)

    second = powered_up(artifact, tmp_path / "context.json")
    assert second.status().start == "warm"
    assert {k: v for k, v in second.variables.values().items() if not k.startswith("Trip.")} == {
        k: v for k, v in before.items() if not k.startswith("Trip.")
    }
    assert second.variables.value("Trip.n") == 0  # safety-related: always a cold start
    second.start()
    run(second, 1)
    assert (second.variables.value("Counter.warm"), second.variables.value("Counter.cold")) == (
        1,
        1,
    )
    assert second.variables.value("Counter.n") == 31
    assert second.variables.value("Chart.Busy.X") is True  # the active step came back
    run(second, 70)  # time stood still while the power was off: 290 ms + 700 ms
    assert second.variables.value("Counter.t.Q") is False
    run(second, 1)
    assert second.variables.value("Counter.t.Q") is True  # the timer ran on from where it stood


def test_a_program_stopped_before_the_power_failure_stays_stopped(tmp_path: Path) -> None:
    artifact = compiled()
    first = powered_up(artifact, tmp_path / "context.json")
    first.start()
    run(first, 3)
    stop_program(first, "Chart")
    context = take_context(first)
    assert context is not None
    save_context(tmp_path / "context.json", context)
    second = powered_up(artifact, tmp_path / "context.json")
    second.start()
    assert {p.name: p.state.value for p in second.programs} == {
        "Counter": "RUN",
        "Chart": "STOP",
        "Trip": "RUN",
    }
    start_program(second, "Chart")
    assert second.variables.program("Chart").state.value == "RUN"


def test_a_context_of_another_configuration_gives_a_cold_start(tmp_path: Path) -> None:
    artifact = compiled()
    first = powered_up(artifact, tmp_path / "context.json")
    first.start()
    run(first, 5)
    context = take_context(first)
    assert context is not None
    save_context(tmp_path / "context.json", context)
    other = compiled(autostart="cold")  # another parameter: another configuration CRC
    assert other.crc != artifact.crc
    resource = powered_up(other, tmp_path / "context.json")
    assert resource.status().start == "cold"
    assert resource.variables.value("Counter.n") == 0


def restored_values(artifact: Artifact, state_dir: Path) -> tuple[str, dict[str, Any]]:
    """What a restart must show: the values of the context on disk now (or the initial
    values when there is no valid one), computed in this process."""
    resource = powered_up(artifact, context_path(state_dir))
    expected = resource.status().start
    return str(expected), json.loads(json.dumps(resource.variables.values()))


def kill_loop(tmp_path: Path, endpoint: str, kills: int, seed: int) -> None:
    artifact = compiled()
    store_artifact(tmp_path, artifact)
    rng = random.Random(seed)
    starts = {"warm": 0, "cold": 0}
    highest = 0
    with router(endpoint), client_session(endpoint) as session:
        client = ResourceClient(session, "Plant")
        for kill in range(kills):
            # the plug is pulled: what is on disk now is what the restart must show
            expected_start, expected = restored_values(artifact, tmp_path)
            with runtime_process(
                "Plant", tmp_path, endpoint, "--context-period-ms", "5"
            ) as process:
                wait_until_answering(client)
                # it came up in STOP (Autostart OFF): nothing has run since it read the
                # context, so its values must be exactly those of the context
                status = client.command("status")["status"]
                assert status["start"] == expected_start, f"kill {kill}"
                assert client.command("values")["values"] == expected, f"kill {kill}"
                starts[expected_start] += 1
                if expected_start == "warm":
                    highest = max(highest, expected["Counter.n"])
                assert client.command("start")["ok"]
                time.sleep(rng.uniform(0.02, 0.3))
                os.kill(process.pid, signal.SIGKILL)
                process.wait()
    assert starts["warm"] >= kills // 2, starts  # most restarts found a saved context
    assert highest > 0


def test_power_failure_restarts_warm_or_cold_never_corrupt(
    tmp_path: Path, zenoh_endpoint: str
) -> None:
    kill_loop(tmp_path, zenoh_endpoint, kills=4, seed=1)


@pytest.mark.slow
def test_power_failure_100_times(tmp_path: Path, zenoh_endpoint: str) -> None:
    kill_loop(tmp_path, zenoh_endpoint, kills=100, seed=2)
