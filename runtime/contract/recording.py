"""The recording file (docs/recording.md): MCAP with JSON-schema channels that Foxglove and
the mcap tools open. The resource writes it (`runtime/recorder.py`); the PADT reads it for
trends and replay (`read_recording`). A file cut short by a crash reads up to its last
whole chunk.

What is in a file:
- metadata `padt.recording`: the header (`RecordingHeader`), every value a string;
- channel `/<resource>/values` (schema `padt.CycleValues`): one message per CPU cycle,
  `{"cycle": n, "values": {...}}` with the values nested by the dots of their paths
  (`TankControl.level` -> `values.TankControl.level`), so that a Foxglove plot path reads
  like the variable;
- with all inputs, channel `/<resource>/inputs` (schema `padt.CycleInputs`): per CPU cycle
  what the programs took from outside (`CycleInputs`), and the attachments
  `artifact.json` (the configuration that ran) and `start.json` (its state when the
  recording began: `StartState`).
- channel `/<resource>/log` (schema `padt.LogpointHit`): every logpoint hit the debugger
  logged while the recording wrote (`LoggedHit`), one message each; empty when none was.
The log time of a message is the start of its CPU cycle in calendar time (Unix ns).
"""

from __future__ import annotations

import json
import struct
from collections.abc import Iterator
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any, BinaryIO

import lz4.frame  # type: ignore[import-untyped]
import zstandard
from mcap.exceptions import McapError, RecordLengthLimitExceeded
from mcap.records import Attachment, Channel, Chunk, Message, Metadata
from mcap.stream_reader import StreamReader, breakup_chunk

from runtime.contract.outside_json import MIB, JsonRefused, read_json
from runtime.contract.values import is_reference_type

FORMAT = "padt-recording"
VERSION = 1
PROFILE = ""  # no well-known profile: JSON-schema channels with JSON messages
METADATA = "padt.recording"
VALUES_SCHEMA = "padt.CycleValues"
INPUTS_SCHEMA = "padt.CycleInputs"
LOG_SCHEMA = "padt.LogpointHit"
ARTIFACT_ATTACHMENT = "artifact.json"
START_ATTACHMENT = "start.json"
# What a file read back may hold (docs/recording.md, "Limits"): the recorder writes chunks
# of 512 KiB; anything past these is refused before it is read or unpacked.
MAX_RECORD_BYTES = 256 * MIB  # one record as stored: an attachment, a compressed chunk
MAX_CHUNK_BYTES = 64 * MIB  # one chunk unpacked


def values_topic(resource: str) -> str:
    return f"/{resource}/values"


def inputs_topic(resource: str) -> str:
    return f"/{resource}/inputs"


def log_topic(resource: str) -> str:
    return f"/{resource}/log"


@dataclass(frozen=True)
class RecordingHeader:
    resource: str
    project: str
    crc: str  # the configuration CRC at the start
    variables: list[tuple[str, str]]  # (path, IEC type), in the order of the values
    all_inputs: bool
    started_ns: int  # wall-clock time the recording began (Unix ns)
    recording: str  # its id
    part: int  # 1, 2, ... as the files rotate
    trigger: str = ""  # `variable op value`, or empty
    pre_cycles: int = 0

    def metadata(self) -> dict[str, str]:
        """As MCAP metadata: a map of strings."""
        data = asdict(self)
        return {
            "format": FORMAT,
            "version": str(VERSION),
            **{k: v if isinstance(v, str) else json.dumps(v) for k, v in data.items()},
        }

    @staticmethod
    def from_metadata(data: dict[str, str]) -> RecordingHeader:
        if data.get("format") != FORMAT or data.get("version") != str(VERSION):
            raise RecordingUnreadable(
                f"not a padt recording of version {VERSION} "
                f"(format {data.get('format')!r}, version {data.get('version')!r})"
            )
        try:
            return RecordingHeader(
                resource=data["resource"],
                project=data["project"],
                crc=data["crc"],
                variables=[
                    (str(p), str(t))
                    for p, t in read_json(data["variables"], "the header's variables", 64 * MIB)
                ],
                all_inputs=bool(read_json(data["all_inputs"], "the header's all_inputs", 16)),
                started_ns=int(data["started_ns"]),
                recording=data["recording"],
                part=int(data["part"]),
                trigger=data.get("trigger", ""),
                pre_cycles=int(data.get("pre_cycles", "0")),
            )
        except (KeyError, ValueError, TypeError) as exc:
            raise RecordingUnreadable(f"the recording's header is damaged ({exc})") from None


@dataclass
class CycleInputs:
    """What the programs of one CPU cycle took from outside, in the order it happened:
    `before`: every variable set from outside since the programs of the cycle before
    ended (inputs, writes, forces, Modbus clients: `[path, value]`); `after`: those set
    after the programs ran and before the outputs were written (forces); `system`: the
    system variables that changed; `programs`: each program whose state or start time
    changed, `[state, clock time its program cycle last started]`;
    `begin_ns`: the resource clock at the cycle's start, which every program's time
    follows. A cycle that ran no programs (STOP) is not recorded."""

    cycle: int
    begin_ns: int
    wall_ns: int
    before: list[tuple[str, Any]] = field(default_factory=list)
    after: list[tuple[str, Any]] = field(default_factory=list)
    system: dict[str, Any] = field(default_factory=dict)
    programs: dict[str, Any] = field(default_factory=dict)  # name -> [state, last start]
    cut: list[str] = field(default_factory=list)  # programs whose time slice ended them

    def json(self) -> dict[str, Any]:
        return {
            "cycle": self.cycle,
            "begin_ns": self.begin_ns,
            "wall_ns": self.wall_ns,
            "before": [[p, v] for p, v in self.before],
            "after": [[p, v] for p, v in self.after],
            "system": self.system,
            "programs": self.programs,
            "cut": self.cut,
        }

    @staticmethod
    def from_json(data: dict[str, Any]) -> CycleInputs:
        return CycleInputs(
            cycle=int(data["cycle"]),
            begin_ns=int(data["begin_ns"]),
            wall_ns=int(data["wall_ns"]),
            before=[(str(p), v) for p, v in data["before"]],
            after=[(str(p), v) for p, v in data["after"]],
            system=dict(data["system"]),
            programs={str(k): v for k, v in data["programs"].items()},
            cut=[str(name) for name in data.get("cut", [])],
        )


@dataclass(frozen=True)
class StartState:
    """The state of the configuration the moment the recording began: the context of a
    warm start (runtime/restart.py) with every program's clock."""

    context: dict[str, Any]  # take_context's fields, as JSON
    programs: dict[str, dict[str, Any]]  # name -> {"last_start_ns", "count", "state"}
    system: dict[str, Any]  # every system variable
    cycle: int  # the CPU cycle count


def nest(paths: list[str], values: list[Any]) -> dict[str, Any]:
    """Values nested by the dots of their paths (`A.b.c` -> {"A": {"b": {"c": v}}})."""
    root: dict[str, Any] = {}
    for path, value in zip(paths, values, strict=True):
        node = root
        *parents, leaf = path.split(".")
        for part in parents:
            node = node.setdefault(part, {})
        node[leaf] = value
    return root


def pick(nested: dict[str, Any], path: str) -> Any:
    node: Any = nested
    for part in path.split("."):
        node = node[part]
    return node


_JSON_TYPES = {"BOOL": "boolean", "REAL": "number", "LREAL": "number"}


def json_type(iec_type: str) -> dict[str, Any]:
    upper = iec_type.upper()
    if upper.startswith("ARRAY"):
        return {"type": "array"}
    if upper.startswith(("STRING", "WSTRING", "CHAR", "WCHAR")):
        return {"type": "string"}
    if is_reference_type(upper):  # the path it refers to, null for NULL
        return {"type": ["string", "null"]}
    # non-finite REALs are written as text, as strict JSON has no NaN
    if upper in ("REAL", "LREAL"):
        return {"type": ["number", "string"]}
    return {"type": _JSON_TYPES.get(upper, "integer")}


def values_schema(variables: list[tuple[str, str]]) -> dict[str, Any]:
    """The JSON schema of a values message: the nesting of `nest`, with each type."""
    tree: dict[str, Any] = {"type": "object", "properties": {}}
    for path, iec_type in variables:
        node = tree
        *parents, leaf = path.split(".")
        for part in parents:
            node = node["properties"].setdefault(part, {"type": "object", "properties": {}})
        node["properties"][leaf] = {**json_type(iec_type), "description": iec_type}
    return {
        "type": "object",
        "properties": {"cycle": {"type": "integer"}, "values": tree},
    }


INPUTS_JSON_SCHEMA: dict[str, Any] = {
    "type": "object",
    "properties": {
        "cycle": {"type": "integer"},
        "begin_ns": {"type": "integer"},
        "wall_ns": {"type": "integer"},
        "before": {"type": "array", "description": "[path, value] set before the programs"},
        "after": {"type": "array", "description": "[path, value] set after the programs"},
        "system": {"type": "object"},
        "programs": {"type": "object"},
        "cut": {"type": "array"},
    },
}


@dataclass(frozen=True)
class LoggedHit:
    """A logpoint hit that the debugger logged (one within the logpoint's rate), as it
    hands it to the recordings running; each writes it as a message on `/<resource>/log`
    (`message`)."""

    logpoint: int  # its id (`ArmedBreakpoint.id`)
    program: str
    file: str
    line: int
    values: dict[str, str]  # expression -> its value as text, as the "log" event shows it
    errors: dict[str, str]  # expression -> why it has no value here
    unlogged: int  # hits of this logpoint over its rate since the one logged before
    cycle: int  # the CPU cycle it ran in, numbered as the values messages number it
    clock_ns: int  # the resource clock at the hit

    def message(self, time_ns: int, dropped: int) -> dict[str, Any]:
        """The message of a recording: `time_ns` the hit in its calendar time (the
        message's log time), `dropped` this recording's logpoint messages lost to a full
        queue since the one before."""
        return {
            "cycle": self.cycle,
            "time_ns": time_ns,
            "logpoint": self.logpoint,
            "program": self.program,
            "file": self.file,
            "line": self.line,
            "values": self.values,
            "errors": self.errors,
            "unlogged": self.unlogged,
            "dropped": dropped,
        }


LOG_JSON_SCHEMA: dict[str, Any] = {
    "type": "object",
    "properties": {
        "cycle": {"type": "integer"},
        "time_ns": {"type": "integer", "description": "the hit, Unix ns (the log time)"},
        "logpoint": {"type": "integer", "description": "the logpoint's id"},
        "program": {"type": "string"},
        "file": {"type": "string"},
        "line": {"type": "integer"},
        "values": {
            "type": "object",
            "additionalProperties": {"type": "string"},
            "description": "expression -> its value as text",
        },
        "errors": {
            "type": "object",
            "additionalProperties": {"type": "string"},
            "description": "expression -> why it has no value",
        },
        "unlogged": {"type": "integer", "description": "hits over the rate since the last"},
        "dropped": {"type": "integer", "description": "messages lost to a full queue"},
    },
}


class RecordingUnreadable(ValueError):
    """Not a recording of ours, or damaged before its first whole chunk."""


@dataclass
class Recording:
    """A recording file read back. `complete` is False when the file was cut short (the
    process writing it was killed): everything up to its last whole chunk is here."""

    header: RecordingHeader
    cycles: list[int] = field(default_factory=list)
    times_ns: list[int] = field(default_factory=list)  # log time of each values message
    rows: list[list[Any]] = field(default_factory=list)  # per cycle, in header.variables order
    inputs: list[CycleInputs] = field(default_factory=list)
    artifact: str | None = None  # the configuration's artifact text (with all inputs)
    start: StartState | None = None
    complete: bool = True
    problem: str = ""  # what ended the reading early

    def column(self, path: str) -> list[Any]:
        index = [p for p, _ in self.header.variables].index(path)
        return [row[index] for row in self.rows]


def read_recording(source: Path | BinaryIO) -> Recording:
    """Read one recording file; raises RecordingUnreadable when it is not one of ours."""
    if isinstance(source, Path):
        with source.open("rb") as stream:
            return read_recording(stream)
    header: RecordingHeader | None = None
    recording: Recording | None = None
    channels: dict[int, str] = {}  # channel id -> schema kind
    pending: list[Any] = []  # records met before the header (none in our files)
    complete, problem = True, ""
    try:
        for record in _records(source):
            if isinstance(record, Metadata) and record.name == METADATA:
                header = RecordingHeader.from_metadata(dict(record.metadata))
                recording = Recording(header)
                for early in pending:
                    _take(recording, early, channels)
                pending.clear()
            elif isinstance(record, Channel):
                channels[record.id] = record.topic.rsplit("/", 1)[-1]
            elif recording is None:
                pending.append(record)
            else:
                _take(recording, record, channels)
    except RecordLengthLimitExceeded as exc:  # a cut file ends in EOF, never in this
        raise RecordingUnreadable(f"a record larger than the limit ({exc})") from None
    # a cut inside a record's fixed fields ends in struct.error (not a ValueError)
    except (McapError, EOFError, ValueError, KeyError, TypeError, OSError, struct.error) as exc:
        if isinstance(exc, RecordingUnreadable):
            raise
        complete, problem = False, f"{type(exc).__name__}: {exc}".strip()
    if recording is None:
        raise RecordingUnreadable(
            "no padt recording header found" + (f" ({problem})" if problem else "")
        )
    recording.complete, recording.problem = complete, problem
    return recording


def _records(source: BinaryIO) -> Iterator[Any]:
    # chunks are unpacked here, not by mcap: it unpacks a zstd chunk to the size its frame
    # claims and an lz4 chunk to whatever it holds, a gigabyte from a few kilobytes
    reader = StreamReader(source, emit_chunks=True, record_size_limit=MAX_RECORD_BYTES)
    for record in reader.records:
        if isinstance(record, Chunk):
            yield from breakup_chunk(replace(record, compression="", data=_unpacked(record)))
        else:
            yield record


def _unpacked(chunk: Chunk) -> bytes:
    """A chunk's records, unpacked to the size it declares and never one byte further;
    RecordingUnreadable when it declares too much or holds more or less than it says."""
    declared = chunk.uncompressed_size
    if declared > MAX_CHUNK_BYTES:
        raise RecordingUnreadable(
            f"a chunk declares {declared:,} bytes unpacked, more than the limit of "
            f"{MAX_CHUNK_BYTES:,}"
        )
    try:
        if chunk.compression == "":
            data = chunk.data
        elif chunk.compression == "zstd":
            with zstandard.ZstdDecompressor().stream_reader(
                chunk.data, read_across_frames=True
            ) as unpacking:
                pieces, wanted = [], declared + 1  # read() may stop at a frame's end
                while wanted > 0 and (piece := unpacking.read(wanted)):
                    pieces.append(piece)
                    wanted -= len(piece)
                data = b"".join(pieces)
        elif chunk.compression == "lz4":
            data = lz4.frame.LZ4FrameDecompressor().decompress(chunk.data, max_length=declared + 1)
        else:
            raise RecordingUnreadable(f"a chunk compressed with unknown {chunk.compression!r}")
    except (zstandard.ZstdError, RuntimeError) as exc:  # lz4 raises RuntimeError
        raise RecordingUnreadable(f"a chunk does not unpack ({exc})") from None
    if len(data) != declared:
        more = "more" if len(data) > declared else "less"
        raise RecordingUnreadable(
            f"a chunk unpacks to {more} than the {declared:,} bytes it declares"
        )
    return data


def _take(recording: Recording, record: Any, channels: dict[int, str]) -> None:
    if isinstance(record, Message):
        kind = channels.get(record.channel_id)
        if kind not in ("values", "inputs"):
            return  # the logpoints' messages: not needed for trends or a replay
        where = f"the {kind} message of log time {record.log_time}"
        data = _outside(record.data, where)
        if kind == "values":
            cycle, nested = int(data["cycle"]), data["values"]
            row = []
            for path, _ in recording.header.variables:
                try:
                    row.append(pick(nested, path))
                except (KeyError, TypeError):
                    raise RecordingUnreadable(f"{where} has no value of {path}") from None
            # all three or none: a row for every cycle, whatever comes next
            recording.cycles.append(cycle)
            recording.times_ns.append(record.log_time)
            recording.rows.append(row)
        else:
            recording.inputs.append(CycleInputs.from_json(data))
    elif isinstance(record, Attachment):
        if record.name == ARTIFACT_ATTACHMENT:
            recording.artifact = record.data.decode("utf-8")
        elif record.name == START_ATTACHMENT:
            recording.start = StartState(**_outside(record.data, START_ATTACHMENT))


def _outside(data: bytes, where: str) -> Any:
    """A message or attachment of the file, within the limits of outside JSON: refused as
    a whole (not read as a file cut short, which ends in a broken record, not in this)."""
    try:
        return read_json(data, where, MAX_CHUNK_BYTES)
    except JsonRefused as exc:
        raise RecordingUnreadable(str(exc)) from None
