"""A runtime process driven over real Zenoh on 127.0.0.1: commands, values, liveliness."""

from __future__ import annotations

import json
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
import zenoh

from backend.compiler.pipeline import compile_sources
from backend.compiler.source import SourceFile
from backend.engineering.resource_client import ResourceClient
from frontend.resource_feed import ResourceFeed
from runtime.contract.artifact import ResourceConfig
from runtime.contract.keyspace import alive_key, command_key
from runtime.contract.refusal import Refusal
from runtime.contract.wire import encode
from tests.support.runtime_process import (
    client_session,
    router,
    running_resource,
    runtime_process,
    store_artifact,
    wait_until_answering,
    write_demo_artifact,
)


def test_start_stop_step_over_zenoh(tmp_path: Path, zenoh_endpoint: str) -> None:
    crc = write_demo_artifact(tmp_path)
    with running_resource("Tank1", tmp_path, zenoh_endpoint) as (_, client):
        status = client.command("status")["status"]
        assert status["state"] == "RUN"  # the demo project autostarts
        assert status["crc"] == crc

        stopped = client.command("stop")["status"]
        assert stopped["state"] == "STOP/VALID CONFIGURATION"
        before = client.command("values")
        time.sleep(0.3)
        assert client.command("values") == before  # nothing runs in STOP

        client.command("step")
        after = client.command("values")
        assert after["cycle"] == before["cycle"] + 1
        # no plant answers here: TankControl holds its last good level, commands the pump off
        held = after["values"]
        assert held["tankLevel"] == -1 and held["TankControl.alarmPlant"] is True
        assert held["TankControl.level"] == before["values"]["TankControl.level"]
        assert held["pumpCommand"] is False

        assert client.command("start")["status"]["state"] == "RUN"
        time.sleep(0.35)
        assert client.command("values")["cycle"] >= after["cycle"] + 2


def test_a_frozen_program_stepped_on_forced_levels(tmp_path: Path, zenoh_endpoint: str) -> None:
    """What a commissioning engineer does without the plant: force the level, freeze the
    program and step it; the pump stops at the high level, then rests the refill delay
    (2 s: 20 program cycles of 100 ms) at the low one and starts again."""
    write_demo_artifact(tmp_path)
    with running_resource("Tank1", tmp_path, zenoh_endpoint) as (_, client):

        def step_with(**forced: Any) -> dict[str, Any]:
            for name, value in forced.items():
                assert client.command("force", variable=name, value=value)["ok"]
            assert client.command("step_program", program="TankControl")["ok"]
            return dict(client.command("values")["values"])

        assert client.command("start_forcing")["ok"]  # global: tankLevel is a global
        assert client.command("freeze", program="TankControl")["ok"]
        starts = client.command("values")["values"]["TankControl.pumpStarts"]
        high = step_with(tankLevel=850)
        assert (high["TankControl.level"], high["TankControl.alarmPlant"]) == (850, False)
        assert (high["TankControl.pump"], high["pumpCommand"]) == (False, False)
        resting = [step_with(tankLevel=250)] + [step_with() for _ in range(20)]
        assert [v["TankControl.level"] for v in resting] == [250] * 21
        elapsed_ms = [v["TankControl.refillDelay.ET"] // 1_000_000 for v in resting]
        assert elapsed_ms[:20] == list(range(0, 2000, 100))  # one cycle time per step
        assert [v["TankControl.pump"] for v in resting] == [False] * 20 + [True]
        assert resting[-1]["pumpCommand"] is True
        assert resting[-1]["TankControl.pumpStarts"] == starts + 1

        lost = step_with(tankLevel=-1)  # the plant's level lost: last good level held
        assert (lost["TankControl.level"], lost["TankControl.alarmPlant"]) == (250, True)
        assert (lost["TankControl.pump"], lost["pumpCommand"]) == (True, False)
        assert client.command("unfreeze", program="TankControl")["ok"]
        assert client.command("stop_forcing")["ok"]


def test_bad_commands_get_structured_errors(tmp_path: Path, zenoh_endpoint: str) -> None:
    write_demo_artifact(tmp_path)
    with (
        router(zenoh_endpoint),
        runtime_process("Tank1", tmp_path, zenoh_endpoint),
        client_session(zenoh_endpoint) as session,
    ):
        client = ResourceClient(session, "Tank1")
        wait_until_answering(client)
        assert client.command("explode")["error"]["code"] == "unknown_command"
        assert client.command("step")["error"]["code"] == "state"  # step needs STOP
        before = client.command("status")["status"]["cycle"]
        garbage = (b"not json", b"[1, 2]", b"x" * 100_000, b"\xff\xfe", b'{"cmd": 7}')
        for payload in garbage:
            replies = list(session.get(command_key("Tank1"), payload=payload, timeout=5))
            sample = replies[0].ok
            assert sample is not None
            reply = json.loads(sample.payload.to_bytes())
            assert reply["ok"] is False and reply["error"]["message"]
        for bad in ({"variable": 3, "value": 1}, {"variable": "TankControl.level"}):
            assert client.command("write", **bad)["error"]["code"] == "bad_request"
        status = client.command("status")["status"]
        assert status["state"] == "RUN"
        deadline = time.monotonic() + 10
        while client.command("status")["status"]["cycle"] <= before + 2:
            assert time.monotonic() < deadline, "the cycle stopped"  # it goes on
            time.sleep(0.05)


def test_two_resources_on_one_router(tmp_path: Path, zenoh_endpoint: str) -> None:
    """Each resource answers its own commands; liveliness tells which ones are there."""
    for name in ("Left", "Right"):
        config = ResourceConfig(name=name, target_cycle_ms=20, autostart="cold")
        text = f"PROGRAM P VAR n : DINT; tag : STRING := '{name}'; END_VAR n := n + 1; END_PROGRAM"
        result = compile_sources([SourceFile("p.st", text)], resource=config)
        assert result.artifact is not None
        store_artifact(tmp_path / name, result.artifact)
    with (
        router(zenoh_endpoint),
        runtime_process("Left", tmp_path / "Left", zenoh_endpoint),
        runtime_process("Right", tmp_path / "Right", zenoh_endpoint),
        client_session(zenoh_endpoint) as session,
    ):
        left, right = ResourceClient(session, "Left"), ResourceClient(session, "Right")
        wait_until_answering(left)
        wait_until_answering(right)
        assert left.command("values")["values"]["P.tag"] == "Left"
        assert right.command("values")["values"]["P.tag"] == "Right"
        assert left.command("stop")["status"]["state"] == "STOP/VALID CONFIGURATION"
        assert right.command("status")["status"]["state"] == "RUN"
        found = {
            str(reply.ok.key_expr).split("/")[3]
            for reply in session.liveliness().get("padt/v2/res/*/alive", timeout=5)
            if reply.ok is not None
        }
        assert found == {"Left", "Right"}


def test_watch_sets_push_only_what_is_watched_with_quality(
    tmp_path: Path, zenoh_endpoint: str
) -> None:
    write_demo_artifact(tmp_path)
    pushed: list[dict[str, Any]] = []

    def latest(predicate: Callable[[dict[str, Any]], bool]) -> dict[str, Any]:
        deadline = time.monotonic() + 10
        while time.monotonic() < deadline:
            if pushed and predicate(pushed[-1]):
                return pushed[-1]
            time.sleep(0.02)
        raise AssertionError(f"no such message; last: {pushed[-1:]}")

    with running_resource("Tank1", tmp_path, zenoh_endpoint) as (_, client):
        watch = client.watch(
            ["tankcontrol.level", "TankControl.pump"], lambda m: pushed.append(encode(m)), 50
        )
        assert watch.variables == ["TankControl.level", "TankControl.pump"]
        first = latest(lambda m: m["values"]["TankControl.level"]["quality"] == "live")
        assert sorted(first["values"]) == ["TankControl.level", "TankControl.pump"]
        cycles = [m["cycle"] for m in pushed]
        assert cycles == sorted(cycles)

        assert client.command("start_forcing", program="TankControl")["ok"]
        assert client.command("force", variable="TankControl.pump", value=True)["ok"]
        latest(lambda m: m["values"]["TankControl.pump"] == {"value": True, "quality": "forced"})
        assert client.command("stop")["ok"]
        latest(lambda m: m["values"]["TankControl.level"]["quality"] == "stale")

        # a typo gets an error, not an empty field
        with pytest.raises(Refusal, match="unknown_variable"):
            client.watch(["TankControl.levle"], print)
        assert client.command("watches")["watches"] == [watch.watch_id]
        with client_session(zenoh_endpoint) as other_session:  # a second client ...
            other = ResourceClient(other_session, "Tank1").watch(["TankControl.level"], print)
            assert other.watch_id in client.command("watches")["watches"]
        # ... goes away without a word: its liveliness token goes, and so does its set
        deadline = time.monotonic() + 10
        while other.watch_id in client.command("watches")["watches"]:
            assert time.monotonic() < deadline, "the departed client's watch set stayed"
            time.sleep(0.05)
        watch.close()
        deadline = time.monotonic() + 10
        while client.command("watches")["watches"]:
            assert time.monotonic() < deadline
            time.sleep(0.05)


def test_events_are_pushed_in_order(tmp_path: Path, zenoh_endpoint: str) -> None:
    write_demo_artifact(tmp_path)
    events: list[dict[str, Any]] = []
    with running_resource("Tank1", tmp_path, zenoh_endpoint) as (_, client):
        client.on_events(lambda e: events.append(encode(e)))
        assert client.command("stop")["ok"]
        assert client.command("write", variable="TankControl.level", value=400)["ok"]
        deadline = time.monotonic() + 10
        while len([e for e in events if e["kind"] in ("stop", "write")]) < 2:
            assert time.monotonic() < deadline, events
            time.sleep(0.02)
        client.close()
    kinds = [e["kind"] for e in events]
    assert kinds.index("stop") < kinds.index("write")
    write = next(e for e in events if e["kind"] == "write")
    assert write["details"]["variable"] == "TankControl.level"
    assert write["details"]["new"] == 400
    seqs = [e["seq"] for e in events]
    assert seqs == sorted(seqs)


def test_liveliness_ends_with_the_process(tmp_path: Path, zenoh_endpoint: str) -> None:
    write_demo_artifact(tmp_path)
    events: list[str] = []
    with router(zenoh_endpoint), client_session(zenoh_endpoint) as session:
        watcher = session.liveliness().declare_subscriber(
            alive_key("Tank1"), lambda s: events.append(str(s.kind)), history=True
        )
        client = ResourceClient(session, "Tank1")
        with runtime_process("Tank1", tmp_path, zenoh_endpoint) as process:
            wait_until_answering(client)
            process.kill()  # no orderly shutdown: the token must vanish anyway
            process.wait()
            deadline = time.monotonic() + 5
            while str(zenoh.SampleKind.DELETE) not in events and time.monotonic() < deadline:
                time.sleep(0.05)
        watcher.undeclare()
    assert events[0] == str(zenoh.SampleKind.PUT)
    assert str(zenoh.SampleKind.DELETE) in events


def test_target_cycle_modes_and_an_online_change(tmp_path: Path, zenoh_endpoint: str) -> None:
    """`fixed` stretches cycles to the target; `dynamic` runs the next one as soon as the
    commands are answered; an online change of the target takes effect at once. (Coarse
    counts only, within the time the two reads of the count can span: a slow machine makes
    fewer cycles, never more.)"""
    config = ResourceConfig(
        name="Modes", target_cycle_ms=50, target_cycle_mode="fixed", autostart="cold"
    )
    text = "PROGRAM P VAR n : DINT; END_VAR n := n + 1; END_PROGRAM"
    result = compile_sources([SourceFile("p.st", text)], resource=config)
    assert result.artifact is not None
    store_artifact(tmp_path, result.artifact)

    def cycles_in(client: ResourceClient, seconds: float) -> tuple[int, float]:
        """The cycles between two reads of the count, and a bound of the time between the
        reads: from before the first question to after the second answer (an answer late
        under load lengthens the time the count covers)."""
        started = time.monotonic()
        before = int(client.command("status")["status"]["cycle"])
        time.sleep(seconds)
        after = int(client.command("status")["status"]["cycle"])
        return after - before, time.monotonic() - started

    with running_resource("Modes", tmp_path, zenoh_endpoint) as (_, client):
        cycles, elapsed = cycles_in(client, 1.0)
        assert cycles <= elapsed / 0.050 + 2, (cycles, elapsed)
        reply = client.command("set_parameter", name="target_cycle_mode", value="dynamic")
        assert reply["ok"], reply
        assert cycles_in(client, 1.0)[0] > 200  # no waiting for the target any more
        client.command("set_parameter", name="target_cycle_mode", value="fixed")
        client.command("set_parameter", name="target_cycle_ms", value=100)
        cycles, elapsed = cycles_in(client, 1.0)
        assert cycles <= elapsed / 0.100 + 2, (cycles, elapsed)
        events = client.command("events")["events"]
        changes = [e["details"]["name"] for e in events if e["kind"] == "parameter"]
        assert changes == ["target_cycle_mode", "target_cycle_mode", "target_cycle_ms"]
        # that the changes count no overrun is tested on a virtual clock
        # (test_watch_quotas.py): here a late period is a matter of the machine's load


def test_the_ui_watches_again_when_the_runtime_comes_back(
    tmp_path: Path, zenoh_endpoint: str
) -> None:
    write_demo_artifact(tmp_path)
    with router(zenoh_endpoint), client_session(zenoh_endpoint) as session:
        feed = ResourceFeed(ResourceClient(session, "Tank1"))
        feed.show(["TankControl.level"])  # what a screen shows
        try:
            for attempt in range(2):  # the runtime, then a new one after a crash
                with runtime_process("Tank1", tmp_path, zenoh_endpoint) as process:
                    deadline = time.monotonic() + 20
                    while True:
                        with feed.latest.lock:
                            quality = dict(feed.latest.quality)
                        if quality.get("TankControl.level") == "live":
                            break
                        assert time.monotonic() < deadline, f"no live values (run {attempt})"
                        time.sleep(0.05)
                    process.kill()
                    process.wait()
                with feed.latest.lock:
                    feed.latest.quality.clear()
        finally:
            feed.close()
