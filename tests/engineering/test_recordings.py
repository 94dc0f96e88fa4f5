"""The recordings service against a real runtime process over real Zenoh: a recording
started, awaited, downloaded in chunks and read back with the recording reader; triggers,
rotated files, levels; and a hostile peer on the resource's key whose replies to
`record_read` are refused rather than written into a file."""

from __future__ import annotations

import io
import time
from collections.abc import Iterator

import pytest

from backend.engineering import recordings
from backend.engineering.recordings import RecordingSpec
from runtime.contract.protocol import MAX_RECORDING_READ, GetValues
from runtime.contract.recording import Recording, read_recording
from runtime.contract.refusal import Refusal
from tests.conftest import free_port
from tests.support.lying_resource import FILE, Liar, lying_resource
from tests.support.recording_cell import Cell, recording_cell


@pytest.fixture(scope="module")
def cell(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Cell]:
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    with recording_cell(tmp_path_factory.mktemp("recordings"), endpoint) as found:
        yield found


def read(data: bytes) -> Recording:
    recording = read_recording(io.BytesIO(data))
    assert recording.complete, recording.problem
    return recording


def test_fifty_cycles_recorded_downloaded_and_deleted(cell: Cell) -> None:
    op = cell.logged_in("op")
    spec = RecordingSpec(("Main.count", "Main.level", "Main.label"), cycles=50, id="fifty")
    started = recordings.start(op, spec)
    assert started.id == "fifty" and started.variables == 3
    ended = recordings.wait_until_ended(op, "fifty")
    assert (ended.state, ended.cycles, ended.dropped, ended.error) == ("done", 50, 0, None)

    [(name, data)] = recordings.download_recording(op, "fifty")
    assert name == "fifty-1.mcap" and len(data) == ended.files[0].size
    # the bytes are the resource's own file, byte for byte
    [on_disk] = cell.state_dir.rglob(name)
    assert on_disk.read_bytes() == data

    recording = read(data)
    assert recording.header.resource == "Cell" and recording.header.recording == "fifty"
    assert sorted(recording.header.variables) == [
        ("Main.count", "DINT"),
        ("Main.label", "STRING[16]"),
        ("Main.level", "REAL"),
    ]
    assert len(recording.rows) == 50
    counts = recording.column("Main.count")
    # every cycle once, in order: the program counts up by one a cycle
    assert counts == list(range(counts[0], counts[0] + 50))
    assert recording.cycles == list(range(recording.cycles[0], recording.cycles[0] + 50))
    assert recording.column("Main.level") == [(c % 100) / 2.0 for c in counts]
    assert set(recording.column("Main.label")) == {"cell"}
    assert recording.times_ns == sorted(recording.times_ns)

    listed = {r.id: r for r in recordings.list_recordings(op)}
    assert listed["fifty"].state == "done"
    left = recordings.delete(op, "fifty")
    assert "fifty" not in {r.id for r in left}
    assert not on_disk.exists()
    with pytest.raises(Refusal) as gone:
        recordings.download(op, name)
    assert gone.value.code == "unknown_recording"


def test_a_prefix_records_every_variable_below_it(cell: Cell) -> None:
    op = cell.logged_in("op")
    recordings.start(op, RecordingSpec(("Main*",), cycles=5, id="prefix"))
    recordings.wait_until_ended(op, "prefix")
    [(_, data)] = recordings.download_recording(op, "prefix")
    paths = {path for path, _ in read(data).header.variables}
    assert {"Main.count", "Main.level", "Main.alarm", "Main.label", "Main.elapsed"} <= paths
    recordings.delete(op, "prefix")


def soon(cell: Cell, cycles: int) -> int:
    """Main.count some cycles from now: a trigger on it fires once its pre-cycles are in."""
    count: int = cell.logged_in("viewer").ask(GetValues()).values["Main.count"]
    return count + cycles


def test_a_trigger_keeps_the_cycles_before_it(cell: Cell) -> None:
    op = cell.logged_in("op")
    threshold = soon(cell, 50)
    spec = RecordingSpec(
        ("Main.count", "Main.alarm"),
        trigger=f"Main.count >= {threshold}",
        pre_cycles=5,
        cycles=20,
        id="trig",
    )
    started = recordings.start(op, spec)
    assert started.state == "waiting"
    ended = recordings.wait_until_ended(op, "trig")
    assert ended.state == "done" and ended.trigger_cycle is not None
    [(_, data)] = recordings.download_recording(op, "trig")
    recording = read(data)
    counts = recording.column("Main.count")
    # five cycles before the trigger, the trigger's, and 19 after it: 20 from the trigger
    assert counts == list(range(threshold - 5, threshold + 20))
    assert recording.cycles[5] == ended.trigger_cycle
    assert recording.header.trigger.startswith("Main.count >= ")
    assert recording.header.pre_cycles == 5
    recordings.delete(op, "trig")


def test_a_bool_trigger_fires_when_it_becomes_true(cell: Cell) -> None:
    op = cell.logged_in("op")
    spec = RecordingSpec(("Main.alarm", "Main.count"), trigger="Main.alarm", cycles=3, id="edge")
    recordings.start(op, spec)
    recordings.wait_until_ended(op, "edge")
    [(_, data)] = recordings.download_recording(op, "edge")
    recording = read(data)
    assert recording.column("Main.alarm") == [True, False, False]
    assert recording.column("Main.count")[0] % 25 == 0
    recordings.delete(op, "edge")


def test_rotated_files_come_in_order_and_continue_each_other(cell: Cell) -> None:
    op = cell.logged_in("op")
    spec = RecordingSpec(("Main.count",), seconds=3, rotate_s=1, id="rotating")
    recordings.start(op, spec)
    ended = recordings.wait_until_ended(op, "rotating")
    files = recordings.download_recording(op, "rotating")
    assert len(files) >= 2, ended
    assert [recordings.part_number(name) for name, _ in files] == list(range(1, len(files) + 1))
    parts = [read(data) for _, data in files]
    assert [part.header.part for part in parts] == list(range(1, len(files) + 1))
    counts = [c for part in parts for c in part.column("Main.count")]
    assert counts == list(range(counts[0], counts[0] + len(counts)))
    assert len(counts) == ended.cycles
    recordings.delete(op, "rotating")


def test_a_reader_lists_and_downloads_but_may_not_record(cell: Cell) -> None:
    op, viewer = cell.logged_in("op"), cell.logged_in("viewer")
    with pytest.raises(Refusal) as refused:
        recordings.start(viewer, RecordingSpec(("Main.count",), cycles=5))
    assert refused.value.code == "forbidden"
    recordings.start(op, RecordingSpec(("Main.count",), cycles=5, id="for-viewer"))
    recordings.wait_until_ended(viewer, "for-viewer")
    [(_, data)] = recordings.download_recording(viewer, "for-viewer")
    assert len(read(data).rows) == 5
    with pytest.raises(Refusal) as refused:
        recordings.delete(viewer, "for-viewer")
    assert refused.value.code == "forbidden"
    recordings.delete(op, "for-viewer")


def test_a_running_recording_is_stopped_and_its_file_closed(cell: Cell) -> None:
    op = cell.logged_in("op")
    recordings.start(op, RecordingSpec(("Main.count",), id="open-ended"))
    deadline = time.monotonic() + 0.5  # as if Ctrl-C came then
    ended = recordings.wait_until_ended(
        op, "open-ended", stop_asked=lambda: time.monotonic() > deadline
    )
    assert ended.state == "done" and ended.cycles > 0
    [(_, data)] = recordings.download_recording(op, "open-ended")
    assert len(read(data).rows) == ended.cycles
    recordings.delete(op, "open-ended")


def test_unknown_variables_and_recordings_are_refused(cell: Cell) -> None:
    op = cell.logged_in("op")
    with pytest.raises(Refusal) as refused:
        recordings.start(op, RecordingSpec(("Main.nothing",), cycles=5))
    assert "Main.nothing" in refused.value.message
    with pytest.raises(Refusal) as refused:
        recordings.stop(op, "never")
    with pytest.raises(Refusal) as refused:
        recordings.download_recording(op, "never")
    assert refused.value.code == "unknown_recording"
    with pytest.raises(Refusal) as refused:
        recordings.download(op, "../identity-1.mcap")  # not a name record_list gives
    assert refused.value.code == "bad_request"


# ---- a hostile peer answering on the resource's key


@pytest.fixture(scope="module")
def liar() -> Iterator[Liar]:
    with lying_resource(f"tcp/127.0.0.1:{free_port()}") as found:
        yield found


def test_a_download_takes_the_file_in_chunks_in_order(liar: Liar) -> None:
    liar.lie = "none"
    assert recordings.download(liar.client, "x-1.mcap") == FILE
    assert recordings.download_recording(liar.client, "x") == [("x-1.mcap", FILE)]


@pytest.mark.parametrize(
    ("lie", "says"),
    [
        ("offset", f"bytes from {MAX_RECORDING_READ - 10} instead of {MAX_RECORDING_READ}"),
        ("shrinks", f"the file shrank from {len(FILE)} to {MAX_RECORDING_READ} bytes"),
        ("base64", "data that is not base64"),
        ("empty", f"no bytes at {MAX_RECORDING_READ} of {len(FILE)}"),
        ("negative", "a size of -1 bytes"),
    ],
)
def test_a_reply_that_is_not_the_part_asked_for_ends_the_download(
    liar: Liar, lie: str, says: str
) -> None:
    liar.lie = lie
    with pytest.raises(Refusal) as refused:
        recordings.download(liar.client, "x-1.mcap")
    assert refused.value.code == "bad_reply"
    assert says in refused.value.message and "x-1.mcap" in refused.value.message


def test_a_file_said_to_be_larger_than_the_caller_takes_is_refused_at_once(liar: Liar) -> None:
    liar.lie = "terabyte"
    liar.asked.clear()
    with pytest.raises(Refusal) as refused:
        recordings.download(liar.client, "x-1.mcap", max_bytes=len(FILE))
    assert refused.value.code == "too_large"
    assert f"{1 << 40:,} bytes" in refused.value.message and "x-1.mcap" in refused.value.message
    assert liar.asked == ["record_read"]  # nothing fetched past the first piece
