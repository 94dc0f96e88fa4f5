"""Recordings of a real runtime process, opened by an MCAP reader nobody here wrote (the
TypeScript `@mcap/core` under node, tests/support/mcap_reader.cjs): every message, channel,
schema, the header metadata and the attachments it finds are those our reader finds (a
logpoint's messages those the mcap package's reader finds). And a
runtime killed (SIGKILL) in the middle of a recording, or a file cut at any byte, leaves a
file both read up to its last whole chunk."""

from __future__ import annotations

import base64
import itertools
import json
import os
import signal
import time
from dataclasses import asdict
from pathlib import Path
from typing import Any

from mcap.reader import make_reader

from backend.compiler.pipeline import compile_sources
from backend.compiler.source import SourceFile
from backend.engineering.resource_client import ResourceClient
from runtime.clock import VirtualClock
from runtime.contract import protocol as p
from runtime.contract.artifact import Artifact, ProgramConfig, ResourceConfig
from runtime.contract.recording import (
    ARTIFACT_ATTACHMENT,
    INPUTS_SCHEMA,
    LOG_SCHEMA,
    METADATA,
    START_ATTACHMENT,
    VALUES_SCHEMA,
    Recording,
    RecordingHeader,
    inputs_topic,
    log_topic,
    pick,
    read_recording,
    values_topic,
)
from runtime.contract.state_folder import recordings_path
from runtime.recorder import Recordings
from runtime.resource import Resource
from tests.support.mcap_node import node_or_skip, read_with_node
from tests.support.runtime_process import running_resource, store_artifact, wait_for

PLANT = """
TYPE Reading : STRUCT raw : INT; scaled : REAL; ok : BOOL; END_STRUCT; END_TYPE
VAR_GLOBAL
  level AT %IW0 : INT;
  pump AT %QX0.0 : BOOL;
  alarms : DINT;
  mode : STRING[16] := 'auto';
END_VAR
PROGRAM Control
VAR_EXTERNAL level : INT; pump : BOOL; alarms : DINT; mode : STRING[16]; END_VAR
VAR
  t : TON; n : DINT; seed : UDINT := 7; noise : LREAL; r : Reading;
  history : ARRAY[0..3] OF INT; held : TIME; high : BOOL;
END_VAR
n := n + 1;
seed := seed * 1103515245 + 12345;
noise := UDINT_TO_LREAL(seed MOD 1000) / 1000.0;
r.raw := level;
r.scaled := INT_TO_REAL(level) / 10.0 + LREAL_TO_REAL(noise);
r.ok := level > 0;
history[n MOD 4] := level;
IF level < 300 THEN pump := TRUE; ELSIF level > 700 THEN pump := FALSE; END_IF;
t(IN := level > 650, PT := T#50ms);
IF t.Q AND NOT high THEN alarms := alarms + 1; mode := 'alarm'; END_IF;
high := t.Q;
held := t.ET;
END_PROGRAM
"""


LOGGED_LINE = PLANT.splitlines().index("history[n MOD 4] := level;") + 1


def compiled(source: str, program: str) -> Artifact:
    config = ResourceConfig(
        name="Plant", target_cycle_ms=10, safety_operation=False, global_forcing_allowed=True
    )
    result = compile_sources(
        [SourceFile("plant.st", source)],
        resource=config,
        programs=[ProgramConfig(program, program, 1)],
    )
    assert result.artifact is not None, [str(d) for d in result.diagnostics]
    return result.artifact


def info_of(client: ResourceClient, recording_id: str) -> p.RecordingInfo:
    [info] = [r for r in client.ask(p.RecordList()).recordings if r.id == recording_id]
    return info


MCAP_MAGIC = b"\x89MCAP0\r\n"


def download(client: ResourceClient, name: str, into: Path) -> bytes:
    """The file over the bus by record_read, as a user downloads it, once its writer has
    finished it (it ends with the MCAP magic)."""

    def whole() -> bytes:
        data, offset = b"", 0
        while True:
            chunk = client.ask(p.RecordRead(name, offset))
            data += base64.b64decode(chunk.data)
            offset = len(data)
            if offset >= chunk.size:
                return data

    got = [b""]

    def finished() -> bool:
        got[0] = whole()
        return len(got[0]) > 16 and got[0].endswith(MCAP_MAGIC)

    wait_for(f"{name} to be finished", finished)
    into.write_bytes(got[0])
    return got[0]


def values_rows(recording: Recording, messages: list[dict[str, Any]]) -> list[list[Any]]:
    """The node reader's values messages as our reader's rows (the header's order)."""
    paths = [path for path, _ in recording.header.variables]
    return [[pick(m["data"]["values"], path) for path in paths] for m in messages]


def same_in_node(path: Path) -> tuple[Recording, dict[str, Any]]:
    """One complete file as our reader and @mcap/core read it: the same header, schemas,
    channels, metadata and every message."""
    ours = read_recording(path)
    theirs = read_with_node(path, every_message=True)
    assert ours.complete and theirs["complete"] and theirs["error"] is None, theirs["error"]
    assert theirs["header"] == {"profile": "", "library": "padt"}

    # schemas and channels: the same, each channel with its schema
    assert sorted((s["name"], s["encoding"]) for s in theirs["schemas"]) == [
        (INPUTS_SCHEMA, "jsonschema"),
        (VALUES_SCHEMA, "jsonschema"),
        (LOG_SCHEMA, "jsonschema"),
    ]
    assert sorted((c["topic"], c["message_encoding"], c["schema"]) for c in theirs["channels"]) == [
        (inputs_topic("Plant"), "json", INPUTS_SCHEMA),
        (log_topic("Plant"), "json", LOG_SCHEMA),
        (values_topic("Plant"), "json", VALUES_SCHEMA),
    ]
    [values_schema] = [s["data"] for s in theirs["schemas"] if s["name"] == VALUES_SCHEMA]
    recorded = values_schema["properties"]["values"]["properties"]
    assert recorded["Control"]["properties"]["r"]["properties"]["scaled"]["description"] == "REAL"

    # the header metadata, with the part
    [metadata] = theirs["metadata"]
    assert metadata["name"] == METADATA
    assert RecordingHeader.from_metadata(metadata["metadata"]) == ours.header

    # every message: counts, cycles, log times, values, inputs
    values = theirs["messages"][values_topic("Plant")]
    inputs = theirs["messages"][inputs_topic("Plant")]
    assert values["count"] == len(ours.rows) and inputs["count"] == len(ours.inputs)
    logged = logpoint_messages(path)
    statistics = theirs["statistics"]
    assert int(statistics["message_count"]) == len(ours.rows) + len(ours.inputs) + len(logged)
    assert [m["data"]["cycle"] for m in values["all"]] == ours.cycles
    assert [int(m["log_time"]) for m in values["all"]] == ours.times_ns
    assert values["first"]["cycle"] == ours.cycles[0]
    assert values_rows(ours, [{"data": values["first"]}]) == [ours.rows[0]]
    assert values_rows(ours, values["all"]) == ours.rows
    assert [m["data"]["cycle"] for m in inputs["all"]] == [i.cycle for i in ours.inputs]
    assert [m["data"]["before"] for m in inputs["all"]] == [
        [list(pair) for pair in i.before] for i in ours.inputs
    ]
    assert [m["data"]["after"] for m in inputs["all"]] == [
        [list(pair) for pair in i.after] for i in ours.inputs
    ]
    # the logpoint's messages: the same, at the same log times (their time_ns is the log
    # time, a number past JavaScript's exact integers)
    log = theirs["messages"].get(log_topic("Plant"), {"count": 0, "all": []})
    assert log["count"] == len(logged)
    assert [m["log_time"] for m in log["all"]] == [str(t) for t, _ in logged]
    assert [{**m["data"], "time_ns": 0} for m in log["all"]] == [
        {**m, "time_ns": 0} for _, m in logged
    ]
    return ours, theirs


def logpoint_messages(path: Path) -> list[tuple[int, dict[str, Any]]]:
    """(log time, message) on the log topic, by the mcap package's reader."""
    with path.open("rb") as stream:
        messages = make_reader(stream).iter_messages(topics=[log_topic("Plant")])
        return [(m.log_time, json.loads(m.data)) for _, _, m in messages]


def test_a_recording_with_all_inputs_reads_the_same_in_node(
    tmp_path: Path, zenoh_endpoint: str
) -> None:
    node_or_skip()  # before minutes of work: skip at once without the reader
    store_artifact(tmp_path, compiled(PLANT, "Control"))
    with running_resource("Plant", tmp_path, zenoh_endpoint) as (_process, client):
        assert client.command("write", variable="level", value=500)["ok"]
        assert client.command("start")["ok"]
        every = ["Control.*", "level", "alarms", "mode"]
        started = client.ask(p.RecordStart(every, all_inputs=True, rotate_s=1, id="io"))
        assert started.recording.state == "recording" and started.recording.all_inputs
        logpoint = p.BreakpointSpec(LOGGED_LINE, log=["n", "level", "r.scaled"])
        assert client.ask(p.DebugSet("plant.st", [logpoint])).debug.breakpoints[0].verified
        # what the programs take from outside: writes, a forced input, forcing ended
        for level in (250, 680, 720, 400):
            time.sleep(0.3)
            assert client.command("write", variable="level", value=level)["ok"]
        assert client.command("force", variable="level", value=690)["ok"]
        assert client.command("start_forcing")["ok"]
        time.sleep(0.4)
        assert client.command("stop_forcing")["ok"]
        time.sleep(0.5)
        client.ask(p.DebugClear())
        client.ask(p.RecordStop("io"))
        wait_for("the file finished", lambda: info_of(client, "io").state == "done")
        stopped = info_of(client, "io")
        assert stopped.dropped == 0
        assert len(stopped.files) >= 2  # a new file every second
        paths = []
        for file in stopped.files:
            paths.append(tmp_path / file.name)
            data = download(client, file.name, paths[-1])
            assert data == (recordings_path(tmp_path) / file.name).read_bytes()

    parts = [same_in_node(path) for path in paths]
    ours = [recording for recording, _ in parts]
    assert [r.header.part for r in ours] == list(range(1, len(paths) + 1))
    cycles = [cycle for recording in ours for cycle in recording.cycles]
    assert len(cycles) == stopped.cycles > 100
    assert all(b == a + 1 for a, b in itertools.pairwise(cycles))  # none lost at a rotation

    # the attachments of an all-inputs recording, in its first file only
    first, theirs = parts[0]
    assert first.header.all_inputs and first.header.resource == "Plant"
    attachments = {a["name"]: a for a in theirs["attachments"]}
    assert sorted(attachments) == [ARTIFACT_ATTACHMENT, START_ATTACHMENT]
    assert attachments[ARTIFACT_ATTACHMENT]["text"] == first.artifact
    assert json.loads(attachments[ARTIFACT_ATTACHMENT]["text"])["crc"] == first.header.crc
    assert first.start is not None
    assert json.loads(attachments[START_ATTACHMENT]["text"]) == json.loads(
        json.dumps(asdict(first.start))
    )
    assert all(not later["attachments"] for _, later in parts[1:])

    # the logpoint's hits, in the files of the time they ran in, with the values it logged
    logged = [m for path in paths for _, m in logpoint_messages(path)]
    assert len(logged) >= 20  # its burst at least
    assert {m["line"] for m in logged} == {LOGGED_LINE}
    assert all(
        m["errors"] == {} and list(m["values"]) == ["n", "level", "r.scaled"] for m in logged
    )

    # the run did what the plant did: the writes and the forced level are in the inputs
    inputs = [i for recording in ours for i in recording.inputs]
    written = {value for i in inputs for path, value in i.before if path == "level"}
    assert {250, 680, 720, 400, 690} <= written
    alarms = [v for recording in ours for v in recording.column("alarms")]
    modes = [v for recording in ours for v in recording.column("mode")]
    assert max(alarms) >= 1 and "alarm" in modes


POINTS = 100  # x3 variables: a counter, a noisy REAL and a BOOL each


def big_program() -> str:
    """A program with a few hundred variables that change every cycle like a plant's: some
    counting, some noisy REALs, some switching."""
    declarations = [f"  c{n} : DINT; r{n} : REAL; b{n} : BOOL;" for n in range(POINTS)]
    body = [
        f"c{n} := c{n} + {n % 7 + 1}; seed := seed * 1103515245 + 12345; "
        f"r{n} := {n}.5 + UDINT_TO_REAL(seed MOD 1000) / 100.0; b{n} := (c{n} MOD 5) = 0;"
        for n in range(POINTS)
    ]
    lines = ["PROGRAM Big", "VAR", "  seed : UDINT := 1;", *declarations, "END_VAR", *body]
    return "\n".join([*lines, "END_PROGRAM"])


def test_sigkill_during_a_recording_leaves_a_file_read_to_its_last_whole_chunk(
    tmp_path: Path, zenoh_endpoint: str
) -> None:
    store_artifact(tmp_path, compiled(big_program(), "Big"))
    with running_resource("Plant", tmp_path, zenoh_endpoint) as (process, client):
        assert client.command("start")["ok"]
        started = client.ask(p.RecordStart(["Big.*"], id="cut")).recording
        assert started.variables == 3 * POINTS + 1
        wait_for("300 cycles recorded", lambda: info_of(client, "cut").cycles >= 300)
        time.sleep(1.5)  # the last chunk is being filled
        os.kill(process.pid, signal.SIGKILL)
        process.wait()
    [path] = sorted(recordings_path(tmp_path).glob("cut-*.mcap"))

    ours = read_recording(path)
    assert not ours.complete and ours.problem
    assert len(ours.rows) >= 100, (len(ours.rows), ours.problem)
    assert all(len(row) == 3 * POINTS + 1 and None not in row for row in ours.rows)
    assert all(b == a + 1 for a, b in itertools.pairwise(ours.cycles))
    counters = ours.column("Big.c3")
    assert all(b - a == 4 for a, b in itertools.pairwise(counters))  # not a cycle lost inside

    node_or_skip()
    theirs = read_with_node(path, every_message=True)
    # the stream reader stops at the cut: waiting for bytes that never come, or with an error
    assert not theirs["complete"]
    assert theirs["header"] == {"profile": "", "library": "padt"}
    [metadata] = theirs["metadata"]
    assert RecordingHeader.from_metadata(metadata["metadata"]) == ours.header
    values = theirs["messages"][values_topic("Plant")]
    assert values["count"] == len(ours.rows)
    assert [m["data"]["cycle"] for m in values["all"]] == ours.cycles
    assert values_rows(ours, values["all"]) == ours.rows


def test_a_file_cut_anywhere_reads_the_same_in_both_readers(tmp_path: Path) -> None:
    """Power can fail at any byte: whatever is left, both readers find the same messages,
    those of the whole chunks before the cut."""
    resource = Resource("Plant", VirtualClock(epoch_ns=1_700_000_000 * 10**9))
    recordings = Recordings(tmp_path / "recordings")
    resource.recordings = recordings
    resource.load(compiled(big_program(), "Big"))
    resource.start()
    recordings.start(resource, p.RecordStart(["Big.*"], cycles=400, id="whole"))
    clock = resource.clock
    assert isinstance(clock, VirtualClock)
    for _ in range(400):
        resource.cycle()
        clock.advance(10_000_000)
    recordings.close()
    data = (tmp_path / "recordings" / "whole-1.mcap").read_bytes()
    assert len(read_recording(tmp_path / "recordings" / "whole-1.mcap").rows) == 400

    cuts: list[tuple[Path, Recording]] = []
    for fraction in (0.1, 0.25, 0.4, 0.55, 0.7, 0.85, 0.97):
        cut = tmp_path / f"cut-{fraction}.mcap"
        cut.write_bytes(data[: int(len(data) * fraction)])
        ours = read_recording(cut)  # a cut inside a record's fields was a struct.error
        assert not ours.complete and ours.problem, fraction
        cuts.append((cut, ours))
    found = [len(ours.rows) for _, ours in cuts]
    assert found == sorted(found) and found[0] < found[-1]  # more bytes, more cycles
    assert found[-1] == 400  # a cut in the summary at the end loses no message

    node_or_skip()
    for cut, ours in cuts:
        theirs = read_with_node(cut, every_message=True)
        assert not theirs["complete"], cut.name
        messages = theirs["messages"].get(values_topic("Plant"), {"count": 0, "all": []})
        assert messages["count"] == len(ours.rows), cut.name
        assert [m["data"]["cycle"] for m in messages["all"]] == ours.cycles, cut.name
        assert values_rows(ours, messages["all"]) == ours.rows, cut.name
