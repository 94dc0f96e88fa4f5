"""The writer thread of a recording: takes what the cycle queued and writes it into MCAP
files (runtime/contract/recording.py), compressing chunks, rotating files by size or time.
The cycle never waits for it: `offer` appends to a bounded queue or counts a drop; and
while a cycle runs, the writer waits for its end (`CycleGate`) rather than compete with it
for the interpreter.

A chunk is closed at least every `FLUSH_S` seconds, so a file cut by a crash (SIGKILL,
power) loses at most that much: readers take it up to its last whole chunk.
"""

from __future__ import annotations

import collections
import json
import logging
import math
import threading
import time
from collections.abc import Callable
from dataclasses import replace
from itertools import chain
from pathlib import Path
from typing import Any, BinaryIO

from mcap.writer import CompressionType, Writer

from runtime.contract.recording import (
    INPUTS_JSON_SCHEMA,
    INPUTS_SCHEMA,
    LOG_JSON_SCHEMA,
    LOG_SCHEMA,
    VALUES_SCHEMA,
    CycleInputs,
    LoggedHit,
    RecordingHeader,
    inputs_topic,
    log_topic,
    nest,
    values_schema,
    values_topic,
)
from runtime.contract.values import jsonable

log = logging.getLogger(__name__)

FLUSH_S = 1.0  # the longest a message waits in an open chunk
CHUNK_BYTES = 512 * 1024  # uncompressed bytes of a chunk
MAX_QUEUED_VALUES = 2_000_000  # values waiting for the writer, over all queued cycles
MAX_PAUSE_S = 0.05  # the longest a writer waits for a CPU cycle to end
_IDLE_S = 0.02
_SLICE = 1_000  # values encoded between two looks at the cycle


class CycleGate:
    """Tells the writer threads when a CPU cycle runs, so that they wait for its end
    instead of taking the interpreter from it (the threads of a process share one, and
    each would get it every switch interval): a recording then costs the cycle only its
    own copying of the values. A cycle that has run MAX_PAUSE_S (or never said it ended:
    the resource stopped in it) holds them back no longer."""

    def __init__(self) -> None:
        self._idle = threading.Event()
        self._idle.set()
        self._began = 0.0

    def begins(self) -> None:
        self._began = time.monotonic()
        self._idle.clear()

    def ends(self) -> None:
        self._idle.set()

    def wait(self) -> None:
        if not self._idle.is_set():
            left = MAX_PAUSE_S - (time.monotonic() - self._began)
            if left > 0:
                self._idle.wait(left)


class Values:
    """One cycle's values, as the cycle thread queued them."""

    __slots__ = ("cycle", "time_ns", "values")

    def __init__(self, cycle: int, time_ns: int, values: list[Any]) -> None:
        self.cycle, self.time_ns, self.values = cycle, time_ns, values


class Inputs:
    __slots__ = ("inputs", "time_ns")

    def __init__(self, time_ns: int, inputs: CycleInputs) -> None:
        self.time_ns, self.inputs = time_ns, inputs


class Logged:
    """A logpoint hit (`LoggedHit`) at its calendar time, with the recording's logpoint
    messages dropped before it."""

    __slots__ = ("dropped", "hit", "time_ns")

    def __init__(self, time_ns: int, hit: LoggedHit, dropped: int) -> None:
        self.time_ns, self.hit, self.dropped = time_ns, hit, dropped


Item = Values | Inputs | Logged


class TraceWriter:
    """One recording's files: `<id>-<part>.mcap` in `folder`."""

    def __init__(
        self,
        folder: Path,
        header: RecordingHeader,
        attachments: dict[str, bytes],
        rotate_bytes: int,
        rotate_ns: int | None,
        gate: CycleGate | None = None,
    ) -> None:
        self.folder, self.header = folder, header
        self._gate = gate or CycleGate()
        self._attachments = attachments  # written into the first file only
        self._rotate_bytes, self._rotate_ns = rotate_bytes, rotate_ns
        self._paths = [v for v, _ in header.variables]
        self._values: ValuesEncoder | None = None  # laid out by the writer thread
        self._schema = b""  # the values' JSON schema, the same in every file
        self._limit = max(64, MAX_QUEUED_VALUES // max(1, len(self._paths)))
        self._queue: collections.deque[Item] = collections.deque()
        self.dropped = 0  # cycles not written: the queue was full (counted by the cycle)
        self.written = 0  # values messages written
        self.files: list[Path] = []
        self.error: str | None = None
        self._closing = threading.Event()
        self._thread = threading.Thread(
            target=self._run, name=f"recording-{header.recording}", daemon=True
        )
        self._stream: BinaryIO | None = None
        self._mcap: Writer | None = None
        self._channels = (0, 0, 0)  # values, inputs, log
        self._file_began_ns = 0
        self._thread.start()

    # ---- the cycle thread
    def offer(self, item: Item) -> bool:
        """Queue an item; False when the writer is that far behind (a cycle's values are
        counted as a dropped cycle; the caller counts the rest)."""
        if len(self._queue) >= self._limit or self.error is not None:
            if isinstance(item, Values):
                self.dropped += 1
            return False
        self._queue.append(item)  # deque.append is atomic: no lock for the cycle
        return True

    def close(self) -> None:
        """Write what is queued, finish the file (non-blocking: the thread does it)."""
        self._closing.set()

    # ---- any thread
    @property
    def finished(self) -> bool:
        return not self._thread.is_alive()

    def join(self, timeout_s: float | None = None) -> None:
        self._thread.join(timeout_s)

    # ---- the writer thread
    def _run(self) -> None:
        last_flush = time.monotonic()
        try:
            self._values = ValuesEncoder(self._paths)
            while True:
                closing = self._closing.is_set()
                wrote = self._drain()
                if closing:
                    break
                now = time.monotonic()
                if self._mcap is not None and now - last_flush >= FLUSH_S:
                    self._mcap.flush()  # type: ignore[no-untyped-call]  # a whole chunk on disk
                    last_flush = now
                if not wrote:
                    time.sleep(_IDLE_S)
        except Exception as exc:  # a full disk, say: the recording fails, the cycle goes on
            log.exception("recording %s failed", self.header.recording)
            self.error = f"{type(exc).__name__}: {exc}"
            self._queue.clear()
        finally:
            self._finish_file()

    def _drain(self) -> bool:
        wrote = False
        while self._queue:
            self._gate.wait()
            item = self._queue.popleft()
            self._write(item)
            wrote = True
        return wrote

    def _write(self, item: Item) -> None:
        if self._mcap is None or self._due_for_rotation(item.time_ns):
            self._finish_file()
            self._begin_file(item.time_ns)
        assert self._mcap is not None
        if isinstance(item, Values):
            assert self._values is not None
            message = self._values.encode(item.cycle, item.values, self._gate.wait)
            self._mcap.add_message(
                self._channels[0], item.time_ns, message, item.time_ns, item.cycle
            )
            self.written += 1
        elif isinstance(item, Logged):
            hit = item.hit
            message = _json(hit.message(item.time_ns, item.dropped))
            self._mcap.add_message(
                self._channels[2], item.time_ns, message, item.time_ns, hit.cycle
            )
        else:
            self._mcap.add_message(
                self._channels[1],
                item.time_ns,
                _json(item.inputs.json()),
                item.time_ns,
                item.inputs.cycle,
            )

    def _due_for_rotation(self, time_ns: int) -> bool:
        assert self._stream is not None
        if self._stream.tell() >= self._rotate_bytes:
            return True
        return self._rotate_ns is not None and time_ns - self._file_began_ns >= self._rotate_ns

    def _begin_file(self, time_ns: int) -> None:
        header = replace(self.header, part=len(self.files) + 1)
        path = self.folder / f"{header.recording}-{header.part}.mcap"
        self._stream = path.open("wb")
        self.files.append(path)
        self._file_began_ns = time_ns
        mcap = Writer(self._stream, chunk_size=CHUNK_BYTES, compression=CompressionType.ZSTD)
        mcap.start(profile="", library="padt")
        mcap.add_metadata("padt.recording", header.metadata())
        if not self._schema:
            self._schema = _json(values_schema(header.variables))
        schema = mcap.register_schema(VALUES_SCHEMA, "jsonschema", self._schema)
        values = mcap.register_channel(values_topic(header.resource), "json", schema)
        inputs = 0
        if header.all_inputs:
            schema = mcap.register_schema(INPUTS_SCHEMA, "jsonschema", _json(INPUTS_JSON_SCHEMA))
            inputs = mcap.register_channel(inputs_topic(header.resource), "json", schema)
        # in every file, so that a viewer finds the topic: empty while no logpoint logs
        schema = mcap.register_schema(LOG_SCHEMA, "jsonschema", _json(LOG_JSON_SCHEMA))
        logged = mcap.register_channel(log_topic(header.resource), "json", schema)
        if header.part == 1:
            for name, data in sorted(self._attachments.items()):
                mcap.add_attachment(time_ns, time_ns, name, "application/json", data)
        self._mcap, self._channels = mcap, (values, inputs, logged)

    def _finish_file(self) -> None:
        if self._mcap is not None:
            self._mcap.finish()  # type: ignore[no-untyped-call]
            self._mcap = None
        if self._stream is not None:
            self._stream.close()
            self._stream = None


class ValuesEncoder:
    """A values message as JSON text, byte for byte what `_json({"cycle": n, "values":
    nest(paths, values)})` gives, without building the nested dictionaries: `json.dumps`
    of a dictionary makes a tuple per entry, and tens of thousands of them per message set
    off the garbage collector, whose full collections stop the cycle thread for tens of
    milliseconds in a large process. The text between two values is laid out once; a
    value is encoded in Python, so the cycle thread gets the interpreter in between."""

    def __init__(self, paths: list[str]) -> None:
        self._pieces: list[str] = []  # the text before each value
        self._order: list[int] = []  # which value comes next in the text
        pending = [',"values":']

        def lay_out(node: dict[str, Any]) -> None:
            pending.append("{")
            for n, (key, child) in enumerate(node.items()):
                pending.append(("," if n else "") + json.dumps(key) + ":")
                if isinstance(child, dict):
                    lay_out(child)
                else:
                    self._pieces.append("".join(pending))
                    pending.clear()
                    self._order.append(child)
            pending.append("}")

        lay_out(nest(paths, list(range(len(paths)))))
        self._tail = "".join(pending) + "}"
        self._in_order = self._order == list(range(len(paths)))

    def encode(
        self, cycle: int, values: list[Any], pause: Callable[[], None] = lambda: None
    ) -> bytes:
        """The message; `pause` is called every _SLICE values (to let a cycle run)."""
        if not self._in_order:
            values = [values[i] for i in self._order]
        parts = [f'{{"cycle":{int(cycle)}']
        for start in range(0, len(values), _SLICE):
            if start:
                pause()
            end = start + _SLICE
            pieces = zip(self._pieces[start:end], map(_leaf, values[start:end]), strict=True)
            parts.append("".join(chain.from_iterable(pieces)))
        parts.append(self._tail)
        return "".join(parts).encode()


def _leaf(value: Any) -> str:
    kind = type(value)
    if kind is int:
        return int.__repr__(value)
    if kind is float and math.isfinite(value):
        return float.__repr__(value)
    if kind is bool:
        return "true" if value else "false"
    return _json(value).decode()


def _json(data: Any) -> bytes:
    try:
        return json.dumps(data, separators=(",", ":"), allow_nan=False).encode()
    except ValueError:  # a NaN or infinity: as text, since strict JSON has none
        return json.dumps(_finite(data), separators=(",", ":")).encode()


def _finite(data: Any) -> Any:
    if isinstance(data, dict):
        return {key: _finite(value) for key, value in data.items()}
    if isinstance(data, list | tuple):
        return [_finite(item) for item in data]
    return jsonable(data)
