"""The event log: a short-term ring that overwrites, a long-term log on disk that is
hash-chained, survives a restart and a torn write, and keeps 3 days of user actions."""

from __future__ import annotations

import hashlib
import json
import threading
from pathlib import Path

import pytest

from runtime.contract.event_chain import GENESIS
from runtime.contract.protocol import Event
from runtime.contract.wire import encode
from runtime.event_log import DAY_NS, ChainReport, EventLog, verify_chain

T0 = 1_750_000_000 * 10**9


class FakeClock:
    def __init__(self, now_ns: int = T0) -> None:
        self.now_ns = now_ns

    def __call__(self) -> int:
        return self.now_ns


def seqs(events: list[Event]) -> list[int]:
    return [event.seq for event in events]


def lines_of(path: Path) -> list[bytes]:
    return path.read_bytes().splitlines()


def fill(log: EventLog, count: int, kind: str = "login") -> None:
    for i in range(count):
        log.record(kind, f"entry {i}", user="anna", long_term=True)


def test_ring_keeps_the_newest_entries_with_rising_seq() -> None:
    log = EventLog(FakeClock(), short_capacity=3)
    for i in range(5):
        log.record("state", f"state {i}")
    recent = log.recent()
    assert seqs(recent) == [3, 4, 5]
    assert [event.message for event in recent] == ["state 2", "state 3", "state 4"]


def test_recent_pages_on_after_seq() -> None:
    log = EventLog(FakeClock())
    for i in range(7):
        log.record("write", f"write {i}")
    assert seqs(log.recent(after_seq=0, limit=3)) == [1, 2, 3]
    assert seqs(log.recent(after_seq=3, limit=3)) == [4, 5, 6]
    assert seqs(log.recent(after_seq=6, limit=3)) == [7]
    assert log.recent(after_seq=7) == []
    assert log.recent(limit=0) == []
    with pytest.raises(ValueError):
        log.recent(limit=-1)


def test_event_fields_and_json() -> None:
    clock = FakeClock()
    log = EventLog(clock)
    event = log.record("force", "Forcing was switched on.", user="anna", variable="P.x")
    assert event == Event(1, T0, "force", "Forcing was switched on.", "anna", {"variable": "P.x"})
    assert encode(event) == {
        "seq": 1,
        "time_ns": T0,
        "kind": "force",
        "message": "Forcing was switched on.",
        "user": "anna",
        "details": {"variable": "P.x"},
    }


def test_details_must_be_json() -> None:
    log = EventLog(FakeClock())
    with pytest.raises(TypeError):
        log.record("error", "bad", thing=object())
    with pytest.raises(ValueError):
        log.record("error", "bad", value=float("nan"))
    assert log.recent() == []


def test_details_are_copied_when_recorded() -> None:
    log = EventLog(FakeClock())
    values = [1, 2]
    log.record("parameter", "Parameters changed.", values=values)
    values.append(3)
    assert log.recent()[0].details == {"values": [1, 2]}


def test_only_long_term_entries_go_to_the_long_term_log(tmp_path: Path) -> None:
    log = EventLog(FakeClock(), long_path=tmp_path / "events.jsonl")
    log.record("state", "RUN")
    log.record("login", "anna logged in.", user="anna", long_term=True)
    log.record("state", "STOP")
    log.record("load", "Configuration loaded.", user="anna", long_term=True, crc="DC00E56F")
    assert seqs(log.recent()) == [1, 2, 3, 4]
    assert seqs(log.long_term()) == [2, 4]
    assert log.long_term()[1].details == {"crc": "DC00E56F"}
    assert len(lines_of(tmp_path / "events.jsonl")) == 2


def test_file_format_is_canonical_json_lines_chained_by_sha256(tmp_path: Path) -> None:
    path = tmp_path / "events.jsonl"
    log = EventLog(FakeClock(), long_path=path)
    log.record("login", "anna logged in.", user="anna", long_term=True, role="ä")
    log.record("start", "Resource started.", user="anna", long_term=True)
    data = path.read_bytes()
    assert data.endswith(b"\n")
    first, second = data.splitlines()
    assert first == (
        b'{"details":{"role":"\\u00e4"},"kind":"login","message":"anna logged in.",'
        b'"prev":"'
        + GENESIS.encode()
        + b'","seq":1,"time_ns":'
        + str(T0).encode()
        + b',"user":"anna"}'
    )
    assert json.loads(second)["prev"] == hashlib.sha256(first).hexdigest()
    assert log.head == hashlib.sha256(second).hexdigest()
    assert verify_chain(path).ok


def test_long_term_log_survives_a_new_instance_and_seq_goes_on(tmp_path: Path) -> None:
    path = tmp_path / "state" / "events.jsonl"
    first = EventLog(FakeClock(), long_path=path)
    first.record("login", "anna logged in.", user="anna", long_term=True)
    first.record("state", "RUN")
    first.record("load", "Configuration loaded.", user="anna", long_term=True)
    first.record("state", "STOP")  # short-term only: its seq is not remembered
    kept = first.long_term()

    second = EventLog(FakeClock(T0 + 10**9), long_path=path)
    assert second.long_term() == kept
    assert second.recent() == []
    event = second.record("stop", "Resource stopped.", user="bert", long_term=True)
    assert event.seq == 4
    assert seqs(second.long_term()) == [1, 3, 4]
    report = verify_chain(path)
    assert report.ok and report.entries == 3 and report.problem is None


def test_memory_only_long_term_log_without_a_path() -> None:
    clock = FakeClock()
    log = EventLog(clock, long_capacity=2, keep_ns=0)
    for _ in range(3):
        fill(log, 1)
        clock.now_ns += 1
    assert seqs(log.long_term()) == [2, 3]


def chained_file(tmp_path: Path, count: int) -> Path:
    path = tmp_path / "events.jsonl"
    fill(EventLog(FakeClock(), long_path=path), count)
    assert verify_chain(path).ok
    return path


def test_one_changed_byte_is_reported_at_the_next_line(tmp_path: Path) -> None:
    path = chained_file(tmp_path, 5)
    path.write_bytes(path.read_bytes().replace(b"entry 1", b"entry 7"))
    report = verify_chain(path)
    assert not report.ok
    assert report.line == 3 and report.entries == 2
    assert report.problem is not None
    assert report.problem.startswith("line 3: prev is not the SHA-256 of line 2")


def test_a_changed_byte_that_breaks_the_form_is_reported_at_its_line(tmp_path: Path) -> None:
    path = chained_file(tmp_path, 5)
    lines = lines_of(path)
    lines[3] = lines[3].replace(b'"seq":', b'"seq": ')
    path.write_bytes(b"\n".join(lines) + b"\n")
    report = verify_chain(path)
    assert (report.ok, report.line, report.problem) == (
        False,
        4,
        "line 4: not in canonical form",
    )


def test_a_removed_entry_is_reported(tmp_path: Path) -> None:
    path = chained_file(tmp_path, 5)
    lines = lines_of(path)
    del lines[2]
    path.write_bytes(b"\n".join(lines) + b"\n")
    report = verify_chain(path)
    assert not report.ok and report.line == 3


def test_reordered_entries_are_reported(tmp_path: Path) -> None:
    path = chained_file(tmp_path, 4)
    lines = lines_of(path)
    lines[1], lines[2] = lines[2], lines[1]
    path.write_bytes(b"\n".join(lines) + b"\n")
    report = verify_chain(path)
    assert not report.ok and report.line == 2


def test_verify_chain_on_missing_empty_and_torn_files(tmp_path: Path) -> None:
    missing = verify_chain(tmp_path / "nothing.jsonl")
    assert not missing.ok and missing.problem is not None and "cannot read" in missing.problem
    empty = tmp_path / "empty.jsonl"
    empty.write_bytes(b"")
    assert verify_chain(empty).ok
    path = chained_file(tmp_path, 2)
    with path.open("ab") as file:
        file.write(b'{"details":{},"ki')
    report = verify_chain(path)
    assert (report.ok, report.entries, report.line) == (False, 2, 3)


def test_a_broken_chain_is_reported_on_load_and_appending_goes_on(tmp_path: Path) -> None:
    path = chained_file(tmp_path, 4)
    path.write_bytes(path.read_bytes().replace(b"entry 1", b"entry 9"))
    log = EventLog(FakeClock(), long_path=path)
    [note] = log.recent()
    assert note.kind == "error"
    assert "failed verification at line 3" in note.message
    assert note.details == {"line": 3}
    assert len(log.long_term()) == 4
    log.record("login", "bert logged in.", user="bert", long_term=True)
    assert lines_of(path)[-1].startswith(b'{"details":{},"kind":"login"')
    # the new entry chains from the last line, so the break stays the only one
    report = verify_chain(path)
    assert report.line == 3 and report.entries == 2
    lines = lines_of(path)
    assert json.loads(lines[-1])["prev"] == hashlib.sha256(lines[-2]).hexdigest()


def test_a_torn_last_line_is_dropped_on_load(tmp_path: Path) -> None:
    path = chained_file(tmp_path, 3)
    whole = path.read_bytes()
    path.write_bytes(whole + b'{"details":{},"kind":"lo')
    log = EventLog(FakeClock(), long_path=path)
    [note] = log.recent()
    assert note.kind == "error" and "incomplete line 4" in note.message
    assert path.read_bytes() == whole
    assert len(log.long_term()) == 3
    log.record("login", "bert logged in.", user="bert", long_term=True)
    assert verify_chain(path) == ChainReport(True, 4)


def test_a_last_line_that_is_not_json_is_dropped_on_load(tmp_path: Path) -> None:
    path = chained_file(tmp_path, 2)
    whole = path.read_bytes()
    path.write_bytes(whole + b'{"details":{},"kind"\n')
    log = EventLog(FakeClock(), long_path=path)
    assert "incomplete line 3" in log.recent()[0].message
    assert path.read_bytes() == whole


def test_full_log_of_young_entries_rejects_with_one_marker(tmp_path: Path) -> None:
    path = tmp_path / "events.jsonl"
    clock = FakeClock()
    log = EventLog(clock, long_path=path, long_capacity=3)
    fill(log, 3)
    clock.now_ns = T0 + DAY_NS
    rejected = log.record("parameter", "Cycle time set to 50 ms.", user="anna", long_term=True)
    log.record("parameter", "Watchdog set to 100 ms.", user="anna", long_term=True)
    log.record("parameter", "Cycle time set to 60 ms.", user="anna", long_term=True)
    entries = log.long_term()
    assert [event.kind for event in entries] == ["login"] * 3 + ["rejected"]
    marker = entries[-1]
    assert marker.details == {"rejected": 1}
    assert marker.seq == rejected.seq + 1 and marker.time_ns == T0 + DAY_NS
    assert "full" in marker.message and "3 days" in marker.message
    assert log.rejected_count == 3
    # rejected entries still are in the short-term ring, the marker too
    assert [event.kind for event in log.recent()[3:]] == [
        "parameter",
        "rejected",
        "parameter",
        "parameter",
    ]
    assert verify_chain(path).ok


def test_entries_older_than_three_days_make_room(tmp_path: Path) -> None:
    path = tmp_path / "events.jsonl"
    clock = FakeClock()
    log = EventLog(clock, long_path=path, long_capacity=3)
    fill(log, 3)
    clock.now_ns = T0 + DAY_NS
    log.record("parameter", "rejected one", user="anna", long_term=True)
    log.record("parameter", "rejected two", user="anna", long_term=True)
    log.record("parameter", "rejected three", user="anna", long_term=True)
    clock.now_ns = T0 + 4 * DAY_NS
    stored = log.record("load", "Configuration loaded.", user="anna", long_term=True)
    entries = log.long_term()
    # the day-1 marker is exactly 3 days old, not older: it stays
    assert [(event.kind, event.details) for event in entries] == [
        ("rejected", {"rejected": 1}),
        ("rejected", {"rejected": 2}),
        ("load", {}),
    ]
    assert entries[-1] == stored and entries[1].seq == stored.seq - 1
    report = verify_chain(path)
    assert report.ok and report.entries == 3
    assert json.loads(lines_of(path)[0])["prev"] != GENESIS
    assert sorted(p.name for p in tmp_path.iterdir()) == ["events.jsonl"]
    # the log is accepting again: the next rejection writes a new marker
    clock.now_ns = T0 + 5 * DAY_NS
    fill(log, 1)
    assert [event.kind for event in log.long_term()] == ["rejected", "load", "login"]
    assert verify_chain(path).ok


def test_a_single_rejection_needs_no_count_when_room_comes(tmp_path: Path) -> None:
    path = tmp_path / "events.jsonl"
    clock = FakeClock()
    log = EventLog(clock, long_path=path, long_capacity=3)
    fill(log, 3)
    clock.now_ns = T0 + DAY_NS
    log.record("parameter", "rejected", user="anna", long_term=True)
    clock.now_ns = T0 + 4 * DAY_NS
    log.record("load", "Configuration loaded.", user="anna", long_term=True)
    assert [event.kind for event in log.long_term()] == ["login", "rejected", "load"]
    assert verify_chain(path).ok


def test_an_open_marker_survives_a_restart(tmp_path: Path) -> None:
    path = tmp_path / "events.jsonl"
    clock = FakeClock()
    log = EventLog(clock, long_path=path, long_capacity=2)
    fill(log, 3)
    again = EventLog(clock, long_path=path, long_capacity=2)
    fill(again, 2)
    assert [event.kind for event in again.long_term()] == ["login", "login", "rejected"]
    assert again.rejected_count == 2


def test_keep_ns_and_capacity_one(tmp_path: Path) -> None:
    path = tmp_path / "events.jsonl"
    clock = FakeClock()
    log = EventLog(clock, long_path=path, long_capacity=1, keep_ns=10)
    fill(log, 3)
    assert [event.kind for event in log.long_term()] == ["login", "rejected"]
    assert "10 ns" in log.long_term()[1].message
    clock.now_ns += 11
    log.record("load", "Configuration loaded.", long_term=True)
    # everything old goes; the count and the entry take the log one over its capacity
    assert [(e.kind, e.details) for e in log.long_term()] == [
        ("rejected", {"rejected": 1}),
        ("load", {}),
    ]
    assert verify_chain(path).ok


def test_a_failed_write_is_logged_not_raised_and_the_file_catches_up(tmp_path: Path) -> None:
    path = tmp_path / "events.jsonl"
    log = EventLog(FakeClock(), long_path=path)
    fill(log, 1)
    path.unlink()
    path.mkdir()  # nothing can be appended to a directory
    event = log.record("login", "bert logged in.", user="bert", long_term=True)
    note = log.recent()[-1]
    assert note.kind == "error" and "could not be written" in note.message
    assert note.details == {"seqs": [event.seq]}
    assert seqs(log.long_term()) == [1, 2]  # kept in memory, not lost
    path.rmdir()
    log.record("login", "carl logged in.", user="carl", long_term=True)
    # the next entry rewrote the file whole: nothing missing, the chain unbroken
    assert [json.loads(line)["seq"] for line in lines_of(path)] == [1, 2, 4]
    assert verify_chain(path) == ChainReport(True, 3)


def test_written_behind_no_recorder_waits_for_the_disk(tmp_path: Path) -> None:
    path = tmp_path / "events.jsonl"
    log = EventLog(FakeClock(), long_path=path, write_behind=True)
    with log._file_lock:  # the disk is busy: the writer cannot get on
        fill(log, 3)
        assert seqs(log.long_term()) == [1, 2, 3]  # at once, in memory
        assert log.long_term_after(1, 1)[0][0].seq == 2
        assert not path.exists() or len(lines_of(path)) < 3
    log.close()  # everything recorded is written before it returns
    assert verify_chain(path) == ChainReport(True, 3)
    again = EventLog(FakeClock(), long_path=path)
    assert seqs(again.long_term()) == [1, 2, 3] and again.head == log.head


def test_a_defect_in_the_writer_is_logged_and_the_next_entry_tries_again(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    path = tmp_path / "events.jsonl"
    log = EventLog(FakeClock(), long_path=path, write_behind=True)

    def broken(path: Path, lines: list[bytes]) -> None:
        raise ValueError("a defect")

    monkeypatch.setattr(log, "_append", broken)
    fill(log, 1)
    log.flush()  # what the writer thread does; it meets the same defect
    assert any("ValueError: a defect" in e.message for e in log.recent())
    monkeypatch.undo()
    fill(log, 1)
    log.close()
    assert verify_chain(path) == ChainReport(True, 2)


def test_written_behind_drops_and_failures_end_in_one_whole_file(tmp_path: Path) -> None:
    path = tmp_path / "events.jsonl"
    clock = FakeClock()
    log = EventLog(clock, long_path=path, long_capacity=3, keep_ns=0, write_behind=True)
    fill(log, 2)
    log.flush()
    path.unlink()
    path.mkdir()
    clock.now_ns += 1
    fill(log, 3)  # drops the oldest while the file cannot be written
    log.flush()
    assert any("could not be written" in e.message for e in log.recent())
    path.rmdir()
    log.close()
    assert [json.loads(line)["seq"] for line in lines_of(path)] == seqs(log.long_term())
    assert len(lines_of(path)) == 3
    assert verify_chain(path).ok


def test_stale_temporary_files_are_removed_on_load(tmp_path: Path) -> None:
    path = chained_file(tmp_path, 1)
    stale = tmp_path / "events.jsonl.abc123.tmp"
    stale.write_bytes(b"half")
    EventLog(FakeClock(), long_path=path)
    assert not stale.exists()


def test_recording_while_another_thread_reads() -> None:
    log = EventLog(FakeClock(), short_capacity=50)
    done = threading.Event()
    seen: list[list[int]] = []

    def read() -> None:
        while not done.is_set():
            if snapshot := seqs(log.recent()):
                seen.append(snapshot)

    reader = threading.Thread(target=read)
    reader.start()
    for i in range(5000):
        log.record("write", f"write {i}")
    done.set()
    reader.join()
    assert seqs(log.recent()) == list(range(4951, 5001))
    # every snapshot is a run of consecutive seqs: never a half-appended ring
    for snapshot in seen:
        assert snapshot == list(range(snapshot[0], snapshot[0] + len(snapshot)))


def test_bad_arguments() -> None:
    with pytest.raises(ValueError):
        EventLog(FakeClock(), short_capacity=0)
    with pytest.raises(ValueError):
        EventLog(FakeClock(), long_capacity=0)


def test_a_line_nested_far_too_deep_is_reported_not_raised(tmp_path: Path) -> None:
    """The file may have been changed by anyone with the disk: a line of 100,000 `[`
    in the middle is a broken chain, and a last one a torn line, never a RecursionError."""
    path = chained_file(tmp_path, 3)
    lines = lines_of(path)
    deep = b"[" * 100_000
    path.write_bytes(b"\n".join([lines[0], deep, *lines[1:]]) + b"\n")
    report = verify_chain(path)
    assert (report.ok, report.line) == (False, 2)
    assert report.problem == "line 2: not valid JSON"
    path.write_bytes(b"\n".join(lines) + b"\n" + deep + b"\n")
    log = EventLog(FakeClock(), long_path=path)
    assert "incomplete line 4" in log.recent()[0].message
    assert len(log.long_term()) == 3
