"""Logpoints recorded into recordings: a real runtime process over Zenoh with a logpoint in a
loop of 1,000 hits a second writes, into the recording running, a message per hit it logs
on `/<resource>/log` (the expressions' values, the hits not logged over the rate), read back
by an MCAP reader nobody here wrote; exactly the hits the event stream shows, none without
a recording, an empty channel in a recording without logpoints; the values and a replay of
the same file are unchanged."""

from __future__ import annotations

import json
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest
from mcap.reader import make_reader

from backend.compiler.pipeline import compile_sources
from backend.compiler.source import SourceFile
from backend.engineering.replay import replay
from backend.engineering.resource_client import ResourceClient
from runtime.contract import protocol as p
from runtime.contract.artifact import Artifact, ProgramConfig, ResourceConfig
from runtime.contract.recording import (
    LOG_SCHEMA,
    log_topic,
    read_recording,
    values_topic,
)
from runtime.contract.state_folder import recordings_path
from tests.support.mcap_node import node_or_skip, read_with_node
from tests.support.ports import free_port
from tests.support.runtime_process import running_resource, store_artifact

FILE = "plant.st"
SOURCE = """\
PROGRAM Loop
VAR i : INT; n : DINT; sum : DINT; END_VAR
n := n + 1;
FOR i := 1 TO 10 DO
  sum := sum + i;
END_FOR;
END_PROGRAM

PROGRAM Other
VAR ticks : DINT; END_VAR
ticks := ticks + 1;
END_PROGRAM
"""
IN_THE_LOOP = SOURCE.splitlines().index("  sum := sum + i;") + 1
LOGGED = ["i", "sum", "n * 2"]
LOGPOINT = p.BreakpointSpec(IN_THE_LOOP, program="Loop", log=LOGGED)
BURST, PER_SECOND = 20, 20  # runtime/debugging/breakpoints.py


def artifact(watchdog_ms: int = 200) -> Artifact:
    config = ResourceConfig(
        name="Plant", target_cycle_ms=10, watchdog_ms=watchdog_ms, safety_operation=False
    )
    programs = [ProgramConfig("Loop", "Loop", 1), ProgramConfig("Other", "Other", 2)]
    result = compile_sources([SourceFile(FILE, SOURCE)], resource=config, programs=programs)
    assert result.artifact is not None, [str(d) for d in result.diagnostics]
    return result.artifact


@pytest.fixture(scope="module")
def plant(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[ResourceClient, Path]]:
    """One runtime process for the module, running: the tests take turns with it."""
    state = tmp_path_factory.mktemp("plant")
    store_artifact(state, artifact())
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    with running_resource("Plant", state, endpoint) as (_process, client):
        assert client.command("start")["ok"]
        yield client, state


def wait_for(what: str, check: Callable[[], bool], timeout_s: float = 60) -> None:
    deadline = time.monotonic() + timeout_s
    while not check():
        assert time.monotonic() < deadline, f"waited {timeout_s:g} s for {what}"
        time.sleep(0.05)


def info_of(client: ResourceClient, recording_id: str) -> p.RecordingInfo:
    [info] = [r for r in client.ask(p.RecordList()).recordings if r.id == recording_id]
    return info


def log_events(client: ResourceClient, after: int) -> list[p.Event]:
    events = client.ask(p.GetEvents(after=after, limit=p.MAX_EVENTS)).events
    return [e for e in events if e.kind == "log"]


def last_seq(client: ResourceClient) -> int:
    events = client.ask(p.GetEvents(limit=p.MAX_EVENTS)).events
    return events[-1].seq if events else 0


def recorded(
    client: ResourceClient, state: Path, recording_id: str
) -> tuple[p.RecordingInfo, Path]:
    """The recording stopped and its one file finished."""
    client.ask(p.RecordStop(recording_id))
    wait_for("the file finished", lambda: info_of(client, recording_id).state == "done")
    info = info_of(client, recording_id)
    [file] = info.files
    return info, recordings_path(state) / file.name


def ours(path: Path, topic: str) -> list[tuple[int, int, dict[str, Any]]]:
    """(log time, sequence, message) of a topic, by the mcap package's reader."""
    with path.open("rb") as stream:
        return [
            (m.log_time, m.sequence, json.loads(m.data))
            for _, _, m in make_reader(stream).iter_messages(topics=[topic])
        ]


def as_event(message: dict[str, Any]) -> str:
    """The text of the "log" event of the same hit (runtime/debugging/debugger.py)."""
    shown = [f"{text} = {value}" for text, value in message["values"].items()]
    more = f" ({message['unlogged']} more hits not logged)" if message["unlogged"] else ""
    where = f"{message['file']}:{message['line']} in {message['program']}"
    return f"{where}: {', '.join(shown)}{more}"


def test_without_a_recording_a_logpoint_writes_no_file(
    plant: tuple[ResourceClient, Path],
) -> None:
    client, state = plant
    files = sorted(recordings_path(state).glob("*")) if recordings_path(state).is_dir() else []
    known = [r.id for r in client.ask(p.RecordList()).recordings]
    seq = last_seq(client)
    client.ask(p.DebugSet(FILE, [LOGPOINT]))
    wait_for("logpoint events", lambda: len(log_events(client, seq)) >= BURST + 5)
    client.ask(p.DebugSet(FILE, []))
    assert [r.id for r in client.ask(p.RecordList()).recordings] == known
    after = sorted(recordings_path(state).glob("*")) if recordings_path(state).is_dir() else []
    assert after == files


def test_a_logpoint_in_a_loop_is_recorded_rate_bounded_as_the_event_stream_shows_it(
    plant: tuple[ResourceClient, Path],
) -> None:
    node_or_skip()
    client, state = plant
    started = client.ask(p.RecordStart(["Loop.*"], all_inputs=True, id="logged")).recording
    assert started.state == "recording"
    wait_for("cycles recorded", lambda: info_of(client, "logged").cycles >= 20)
    seq = last_seq(client)
    armed_at = time.monotonic()
    [armed] = client.ask(p.DebugSet(FILE, [LOGPOINT])).debug.breakpoints
    assert armed.verified and armed.line == IN_THE_LOOP
    wait_for("hits over the rate", lambda: len(log_events(client, seq)) >= BURST + 30)
    client.ask(p.DebugSet(FILE, []))
    armed_for_s = time.monotonic() - armed_at
    wait_for("cycles after", lambda: info_of(client, "logged").cycles >= 300)
    info, path = recorded(client, state, "logged")
    assert info.dropped == 0
    events = [e.message for e in log_events(client, seq)]

    theirs = read_with_node(path, every_message=True)
    assert theirs["complete"] and theirs["error"] is None, theirs["error"]
    channels = {c["topic"]: c for c in theirs["channels"]}
    assert channels[log_topic("Plant")]["schema"] == LOG_SCHEMA
    [schema] = [s["data"] for s in theirs["schemas"] if s["name"] == LOG_SCHEMA]
    assert set(schema["properties"]) >= {"cycle", "time_ns", "program", "values", "unlogged"}
    logged = theirs["messages"][log_topic("Plant")]
    messages = [m["data"] for m in logged["all"]]
    # both readers find the same messages at the same log times; the time in a message is
    # its log time, exact in Python (JavaScript's numbers lose the last digits of it)
    mine = ours(path, log_topic("Plant"))
    assert [{**m, "time_ns": 0} for _, _, m in mine] == [{**m, "time_ns": 0} for m in messages]
    assert [str(t) for t, _, _ in mine] == [m["log_time"] for m in logged["all"]]
    assert all(t == m["time_ns"] for t, _, m in mine)
    assert [s for _, s, _ in mine] == [m["cycle"] for m in messages]
    messages = [m for _, _, m in mine]

    # rate-bounded: the burst, then 20 a second, the rest counted
    assert BURST <= len(messages) <= BURST + PER_SECOND * armed_for_s + 1
    assert len(messages) == len(events) == logged["count"]
    assert sum(m["unlogged"] for m in messages) > len(messages)  # most were held back
    assert all(m["dropped"] == 0 and m["errors"] == {} for m in messages)
    # the very hits the event stream shows, in order
    assert [as_event(m) for m in messages] == events

    # each hit where it ran: its cycle's recorded values agree with the logged ones
    recording = read_recording(path)  # the PADT's reader takes the file as before
    assert recording.complete and len(recording.rows) == info.cycles
    cycle_of = {c: n for n, c in enumerate(recording.cycles)}
    for message in messages:
        assert (message["program"], message["file"]) == ("Loop", FILE)
        assert message["line"] == IN_THE_LOOP and list(message["values"]) == LOGGED
        row = cycle_of[message["cycle"]]
        i, total = int(message["values"]["i"]), int(message["values"]["sum"])
        assert int(message["values"]["n * 2"]) == 2 * recording.column("Loop.n")[row]
        assert total == recording.column("Loop.sum")[row] - 55 + i * (i - 1) // 2
        begins = recording.times_ns[row]
        ends = recording.times_ns[row + 1] if row + 1 < len(recording.times_ns) else None
        assert begins <= message["time_ns"] and (ends is None or message["time_ns"] < ends)

    # and the file replays as before: the logpoint's messages change nothing
    assert replay(recording, artifact()).summary() == f"replay: {info.cycles} cycles, identical"


def test_a_recording_without_logpoints_has_an_empty_log_channel(
    plant: tuple[ResourceClient, Path],
) -> None:
    node_or_skip()
    client, state = plant
    client.ask(p.RecordStart(["Loop.n"], id="quiet"))
    wait_for("cycles recorded", lambda: info_of(client, "quiet").cycles >= 30)
    info, path = recorded(client, state, "quiet")
    theirs = read_with_node(path, every_message=True)
    assert theirs["complete"], theirs["error"]
    topics = sorted(c["topic"] for c in theirs["channels"])
    assert topics == [log_topic("Plant"), values_topic("Plant")]
    assert list(theirs["messages"]) == [values_topic("Plant")]
    assert theirs["messages"][values_topic("Plant")]["count"] == info.cycles
