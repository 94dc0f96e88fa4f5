"""The resource's event log: what happened to the controller, who did it, and when.

Two buffers (spec section 13): a short-term ring of every event that overwrites its oldest
entries, and a long-term log of user actions and configuration changes, persisted as JSON
lines in which every entry carries the SHA-256 of the line before it, so that a changed or
removed entry shows. `docs/event-log.md` describes the file format and the rules for a
full long-term log.
"""

from __future__ import annotations

import contextlib
import json
import os
import tempfile
import threading
from collections import deque
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from runtime.contract.event_chain import GENESIS, canonical, entry_line, line_digest
from runtime.contract.outside_json import JsonRefused, read_json
from runtime.contract.protocol import Event

DAY_NS = 86_400 * 10**9
ENTRY_FIELDS = ("details", "kind", "message", "prev", "seq", "time_ns", "user")
_HEX = frozenset("0123456789abcdef")


@dataclass(frozen=True)
class ChainReport:
    ok: bool
    entries: int  # lines that verified before the first problem (all of them when ok)
    problem: str | None = None  # "line N: why"
    line: int | None = None  # 1-based number of the first line that fails


def parse_entry(line: bytes) -> tuple[Event, str]:
    """One long-term line as event and `prev`; ValueError says what is wrong with it."""
    try:  # the file may have been changed by anyone with the disk: outside JSON
        obj = read_json(line, "the line", len(line))
    except JsonRefused as exc:
        raise ValueError("not valid JSON") from exc
    if not isinstance(obj, dict) or sorted(obj) != list(ENTRY_FIELDS):
        raise ValueError(f"not an entry (its fields must be {', '.join(ENTRY_FIELDS)})")
    seq, time_ns, prev, user = obj["seq"], obj["time_ns"], obj["prev"], obj["user"]
    # bool is an int to isinstance, but not a sequence number or a time
    if type(seq) is not int or seq < 1 or type(time_ns) is not int:
        raise ValueError("seq and time_ns must be integers, seq at least 1")
    if not isinstance(obj["kind"], str) or not isinstance(obj["message"], str):
        raise ValueError("kind and message must be strings")
    if user is not None and not isinstance(user, str):
        raise ValueError("user must be a string or null")
    if not isinstance(obj["details"], dict):
        raise ValueError("details must be an object")
    if not isinstance(prev, str) or len(prev) != 64 or not _HEX.issuperset(prev):
        raise ValueError("prev must be 64 lower-case hex digits")
    try:
        in_canonical_form = canonical(obj) == line
    except ValueError:  # NaN or Infinity, which json.loads lets through
        in_canonical_form = False
    if not in_canonical_form:
        raise ValueError("not in canonical form")
    event = Event(seq, time_ns, obj["kind"], obj["message"], user, obj["details"])
    return event, prev


def _first_break(lines: Sequence[bytes]) -> tuple[int, str] | None:
    """Line number and reason of the first line that breaks the chain, or None."""
    before: bytes | None = None
    last_seq = 0
    for number, line in enumerate(lines, start=1):
        try:
            event, prev = parse_entry(line)
        except ValueError as exc:
            return number, str(exc)
        # the first line's prev is the anchor: older entries may have been dropped
        if before is not None and prev != line_digest(before):
            return number, (
                f"prev is not the SHA-256 of line {number - 1} (line {number - 1} was "
                f"changed, entries after it were removed, or this prev was altered)"
            )
        if event.seq <= last_seq:
            return number, f"seq {event.seq} does not follow seq {last_seq}"
        before, last_seq = line, event.seq
    return None


def _split(data: bytes) -> tuple[list[bytes], bytes]:
    """Complete lines and the rest after the last newline (empty unless a write was torn)."""
    lines = data.split(b"\n")
    tail = lines.pop()
    return lines, tail


def verify_chain(path: Path) -> ChainReport:
    """Check a long-term log file: every line a canonical entry whose `prev` is the
    SHA-256 of the line before it, sequence numbers increasing, a newline at the end."""
    try:
        data = path.read_bytes()
    except OSError as exc:
        return ChainReport(False, 0, f"cannot read {path}: {exc.strerror}")
    lines, tail = _split(data)
    broken = _first_break(lines)
    if broken is not None:
        number, why = broken
        return ChainReport(False, number - 1, f"line {number}: {why}", number)
    if tail:
        number = len(lines) + 1
        return ChainReport(False, len(lines), f"line {number}: no newline at its end", number)
    return ChainReport(True, len(lines))


def _span(ns: int) -> str:
    for unit, size in (("day", DAY_NS), ("hour", 3600 * 10**9), ("second", 10**9)):
        if ns >= size and ns % size == 0:
            count = ns // size
            return f"{count} {unit}" + ("" if count == 1 else "s")
    return f"{ns} ns"


def _fsync_dir(directory: Path) -> None:
    # a rename or a new file is durable only once the directory entry is
    fd = os.open(directory, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


class EventLog:
    """Short-term ring and long-term log of one resource. Any thread may call any method:
    one lock guards both buffers. The long-term log in memory is the truth; the file
    catches up with it, at once in record() or, with write_behind, on a thread of its own
    so that no caller waits for the disk (the cycle thread records events too)."""

    def __init__(
        self,
        wall_ns: Callable[[], int],
        *,
        short_capacity: int = 1000,
        long_path: Path | None = None,
        long_capacity: int = 10_000,
        keep_ns: int = 3 * DAY_NS,
        write_behind: bool = False,
        shares: Mapping[str, int] | None = None,
    ) -> None:
        if short_capacity < 1 or long_capacity < 1 or keep_ns < 0:
            raise ValueError("capacities must be at least 1 and keep_ns not negative")
        # kinds of which the long-term log keeps at most so many entries younger than
        # keep_ns, so that they never crowd out the others (a flood of logins, say)
        self._shares = dict(shares or {})
        self._share_times: dict[str, deque[int]] = {kind: deque() for kind in self._shares}
        self._beyond_share: dict[str, int] = {}
        self._wall_ns = wall_ns
        self._path = long_path
        self._long_capacity = long_capacity
        self._keep_ns = keep_ns
        self._lock = threading.Lock()
        self._short: deque[Event] = deque(maxlen=short_capacity)
        # the long-term log in memory, line for line as in the file; None for a damaged line
        self._lines: list[bytes] = []
        self._events: list[Event | None] = []
        self._head = GENESIS
        self._seq = 0
        # while a "rejected" marker is the last long-term entry, rejections are only counted
        self._marker_open = False
        self._uncounted = 0
        self._rejected = 0
        # the file's side: lines are counted from the first ever kept (dropped ones too),
        # the file holds those before _on_file, unless it is stale and must be rewritten
        # whole (after old entries were dropped, or a write failed)
        self._file_lock = threading.Lock()  # one writer of the file at a time
        self._dropped = 0
        self._on_file = 0
        self._stale = False
        self._wake = threading.Event()
        self._closing = False
        self._writer: threading.Thread | None = None
        notes = self._load(long_path) if long_path is not None else []
        for event in self._events:
            if event is not None and event.kind in self._share_times:
                self._share_times[event.kind].append(event.time_ns)
        now = wall_ns()
        for message, details in notes:
            self._add(now, "error", message, None, details)
        if write_behind and self._path is not None:
            # started here, by whoever makes the log: never by the first recorder
            self._writer = threading.Thread(
                target=self._write_on, name="padt-event-log", daemon=True
            )
            self._writer.start()

    def record(
        self,
        kind: str,
        message: str,
        *,
        user: str | None = None,
        long_term: bool = False,
        **details: Any,
    ) -> Event:
        """Log an event; with long_term=True also in the long-term log, unless that is full
        of entries younger than keep_ns (see rejected_count). Raises TypeError or
        ValueError for details that are not JSON, never for a failed write (that is
        logged as a short-term "error" event instead)."""
        clean: dict[str, Any] = json.loads(canonical(details))
        with self._lock:
            now = self._wall_ns()
            if not long_term:
                return self._add(now, kind, message, user, clean)
            event = self._add_long_term(now, kind, message, user, clean)
        if self._writer is not None:
            self._wake.set()
        else:
            self.flush()
        return event

    def flush(self) -> None:
        """Bring the file up to the long-term log in memory, here and now: append the
        lines it lacks, or rewrite it whole after old entries were dropped or a write
        failed. A failed write (the disk, or a defect: the writing thread must not end)
        is logged as a short-term "error" event and tried again with the next entry.
        Only writers of the file wait for the disk, never a reader or a recorder: the
        lock is not held while writing."""
        with self._file_lock:
            with self._lock:
                path, stale, kept = self._path, self._stale, self._dropped + len(self._lines)
                if path is None or (not stale and self._on_file == kept):
                    return
                lines = self._lines[:] if stale else self._lines[self._on_file - self._dropped :]
                self._stale = False
            try:
                if stale:
                    self._rewrite(path, lines)
                else:
                    self._append(path, lines)
            except Exception as exc:
                with self._lock:
                    self._stale = True
                    first = max(self._on_file - self._dropped, 0)
                    missing = [e.seq for e in self._events[first:] if e is not None]
                    why = f"{type(exc).__name__}: {exc}"
                    message = f"The long-term event log could not be written: {why}"
                    self._add(self._wall_ns(), "error", message, None, {"seqs": missing})
                return
            with self._lock:
                self._on_file = kept

    def close(self) -> None:
        """Stop the writing thread after it wrote everything recorded so far; entries
        recorded after this are written at once."""
        writer, self._writer = self._writer, None
        self._closing = True
        self._wake.set()
        if writer is not None:
            writer.join()
        self.flush()

    def _write_on(self) -> None:
        while not self._closing:
            self._wake.wait()
            self._wake.clear()
            self.flush()

    def recent(self, after_seq: int = 0, limit: int | None = None) -> list[Event]:
        """Short-term events with seq > after_seq, oldest first, at most limit of them
        (the oldest ones, so that a reader pages on with the last seq it got)."""
        if limit is not None and limit < 0:
            raise ValueError("limit must not be negative")
        newer: list[Event] = []
        with self._lock:
            # seq rises along the ring, so a poll for new events reads only those
            for event in reversed(self._short):
                if event.seq <= after_seq:
                    break
                newer.append(event)
        newer.reverse()
        return newer if limit is None else newer[:limit]

    def long_term_after(
        self, after_seq: int = 0, limit: int | None = None
    ) -> list[tuple[Event, str]]:
        """Long-term entries with seq > after_seq, oldest first, at most limit of them, each
        with its `prev` as written, so that a reader can check the chain across pages."""
        found: list[tuple[Event, str]] = []
        with self._lock:
            for event, line in zip(self._events, self._lines, strict=True):
                if event is None or event.seq <= after_seq:
                    continue
                found.append((event, json.loads(line)["prev"]))
                if limit is not None and len(found) == limit:
                    break
        return found

    def long_term(self) -> list[Event]:
        """The long-term entries, oldest first, "rejected" markers included; lines that
        could not be read back from the file are left out (they stay in the file)."""
        with self._lock:
            return [event for event in self._events if event is not None]

    @property
    def rejected_count(self) -> int:
        """Long-term entries rejected since this EventLog was made."""
        with self._lock:
            return self._rejected

    @property
    def head(self) -> str:
        """SHA-256 of the last long-term line: kept elsewhere, it shows a changed last line."""
        with self._lock:
            return self._head

    def _add(
        self, now: int, kind: str, message: str, user: str | None, details: dict[str, Any]
    ) -> Event:
        self._seq += 1
        event = Event(self._seq, now, kind, message, user, details)
        self._short.append(event)
        return event

    def _add_long_term(
        self, now: int, kind: str, message: str, user: str | None, details: dict[str, Any]
    ) -> Event:
        times = self._share_times.get(kind)
        if times is not None:
            while times and now - times[0] > self._keep_ns:
                times.popleft()
            if len(times) >= self._shares[kind]:  # beyond its share: short-term only
                self._beyond_share[kind] = self._beyond_share.get(kind, 0) + 1
                return self._add(now, kind, message, user, details)
            held = self._beyond_share.pop(kind, 0)
            if held:
                details = {**details, "short_term_only": held}
        uncounted = self._uncounted if self._marker_open else 0
        drop = self._room(now, 2 if uncounted else 1)
        if drop is None:
            event = self._add(now, kind, message, user, details)
            self._reject(now)
            return event
        # the count goes in before the entry so that seq keeps rising along the file
        new: list[Event] = []
        if uncounted:
            message_ = (
                f"{uncounted} more entries were rejected while the long-term event log was "
                f"full and no entry was older than {_span(self._keep_ns)}."
            )
            new.append(self._add(now, "rejected", message_, None, {"rejected": uncounted}))
        event = self._add(now, kind, message, user, details)
        new.append(event)
        self._keep(drop, new)
        self._marker_open = False
        self._uncounted = 0
        if times is not None:
            times.append(now)
        return event

    def _room(self, now: int, incoming: int) -> int | None:
        """How many of the oldest entries go to make room, or None if they are too young."""
        # at most everything: with a capacity of 1 a count and its entry still go in
        drop = min(len(self._lines) + incoming - self._long_capacity, len(self._lines))
        if drop <= 0:
            return 0
        for event in self._events[:drop]:
            # a damaged line has no time it can be trusted for; it counts as old
            if event is not None and now - event.time_ns <= self._keep_ns:
                return None
        return drop

    def _reject(self, now: int) -> None:
        self._rejected += 1
        if self._marker_open:
            self._uncounted += 1
            return
        message = (
            f"An entry was rejected because the long-term event log is full "
            f"({self._long_capacity} entries) and no entry is older than "
            f"{_span(self._keep_ns)}; further rejections are counted until it accepts again."
        )
        marker = self._add(now, "rejected", message, None, {"rejected": 1})
        # the marker may take the log one over its capacity: it must not be lost
        self._keep(0, [marker])
        self._marker_open = True
        self._uncounted = 0

    def _keep(self, drop: int, events: list[Event]) -> None:
        """Drop the oldest `drop` entries and chain `events` on, in memory; flush() writes."""
        for event in events:
            line = entry_line(event, self._head)
            self._lines.append(line)
            self._events.append(event)
            self._head = line_digest(line)
        del self._lines[:drop]
        del self._events[:drop]
        self._dropped += drop
        self._stale = self._stale or drop > 0

    @staticmethod
    def _append(path: Path, lines: list[bytes]) -> None:
        created = not path.exists()
        fd = os.open(path, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o600)
        try:
            whole = os.fstat(fd).st_size
            data = memoryview(b"".join(line + b"\n" for line in lines))
            while data:
                data = data[os.write(fd, data) :]
            os.fsync(fd)
        except OSError:
            # a partial line would run into the next entry: cut back to the last whole line
            with contextlib.suppress(OSError):
                os.ftruncate(fd, whole)
            raise
        finally:
            os.close(fd)
        if created:
            _fsync_dir(path.parent)

    @staticmethod
    def _rewrite(path: Path, lines: list[bytes]) -> None:
        # readers and a crash see either the old file or the new one, never half of it
        fd, temp = tempfile.mkstemp(dir=path.parent, prefix=f"{path.name}.", suffix=".tmp")
        try:
            with os.fdopen(fd, "wb") as file:
                with contextlib.suppress(OSError):
                    os.fchmod(file.fileno(), os.stat(path).st_mode & 0o777)
                file.write(b"".join(line + b"\n" for line in lines))
                file.flush()
                os.fsync(file.fileno())
            os.replace(temp, path)
        except BaseException:
            with contextlib.suppress(OSError):
                os.unlink(temp)
            raise
        _fsync_dir(path.parent)

    def _load(self, path: Path) -> list[tuple[str, dict[str, Any]]]:
        """Read an existing long-term log; returns the short-term notes to record."""
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            for stale in path.parent.iterdir():  # left by a crash during a rewrite
                if stale.name.startswith(f"{path.name}.") and stale.name.endswith(".tmp"):
                    stale.unlink()
            data = path.read_bytes() if path.exists() else b""
        except OSError as exc:
            self._path = None
            message = f"The long-term event log cannot be read ({exc}); it is kept in memory only."
            return [(message, {})]
        notes: list[tuple[str, dict[str, Any]]] = []
        lines, tail = _split(data)
        torn: int | None = None
        if tail:
            torn = len(lines) + 1
        elif lines and not _is_json(lines[-1]):
            torn = len(lines)
            lines.pop()
        if torn is not None:
            size = sum(len(line) + 1 for line in lines)
            message = f"The long-term event log ended in an incomplete line {torn}; it was dropped."
            try:
                os.truncate(path, size)
            except OSError as exc:
                self._path = None
                message += f" The file could not be cut ({exc}); it is kept in memory only."
            notes.append((message, {"line": torn}))
        broken = _first_break(lines)
        if broken is not None:
            number, why = broken
            message = (
                f"The long-term event log failed verification at line {number}: {why}. "
                f"New entries are appended after its last line."
            )
            notes.append((message, {"line": number}))
        self._lines = lines
        self._on_file = len(lines)
        self._events = [_event_or_none(line) for line in lines]
        self._head = line_digest(lines[-1]) if lines else GENESIS
        self._seq = max((e.seq for e in self._events if e is not None), default=0)
        last = self._events[-1] if self._events else None
        self._marker_open = last is not None and last.kind == "rejected"
        return notes


def _is_json(line: bytes) -> bool:
    try:
        read_json(line, "the line", len(line))
    except JsonRefused:
        return False
    return True


def _event_or_none(line: bytes) -> Event | None:
    try:
        return parse_entry(line)[0]
    except ValueError:
        return None
