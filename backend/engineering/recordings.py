"""Recordings of a running resource (docs/recording.md): start one, stop it, list them,
fetch their MCAP files and delete them. The resource records into its own state folder
(runtime/recorder.py); this service only asks it over the bus, so `padt record`, the REST
API and the Trends screen record and download the same way.

A trigger is typed as a person writes a condition in ST: `Main.level > 80`, `Main.alarm`
(= TRUE), `NOT Main.alarm` (= FALSE); `parse_trigger` turns it into the protocol's
`Trigger`."""

from __future__ import annotations

import base64
import binascii
import re
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass

from backend.engineering.literals import LiteralError, parse_literal
from backend.engineering.resource_client import ResourceClient, ResourceUnreachable
from runtime.contract.protocol import (
    MAX_RECORDING_READ,
    RecordDelete,
    RecordingChunk,
    RecordingInfo,
    RecordList,
    RecordRead,
    RecordStart,
    RecordStop,
    Trigger,
)
from runtime.contract.refusal import Refusal

ENDED = ("done", "failed")
POLL_S = 0.25  # how often a recording's progress is asked for while it is awaited
PATIENCE_S = 60.0  # how long a resource may not answer while a recording is awaited


class TriggerError(ValueError):
    """Text that is no trigger condition; the message says what one looks like."""


@dataclass(frozen=True)
class RecordingSpec:
    """What to record, as a user chooses it (the arguments of `record_start`, with the
    trigger as text)."""

    variables: Sequence[str] = ()  # paths, or `Prefix*` for every path starting so
    all_inputs: bool = False  # also everything the programs take from outside (replay)
    trigger: str | None = None  # `Main.level > 80`, `Main.alarm`, `NOT Main.alarm`
    pre_cycles: int = 0  # with a trigger: cycles kept from before it
    cycles: int | None = None  # ends after this many CPU cycles ...
    seconds: int | None = None  # ... or seconds (from the trigger when there is one)
    rotate_mb: int = 256  # a new file every this many megabytes
    rotate_s: int | None = None  # ... or seconds
    id: str | None = None  # chosen by the resource when not given

    def command(self) -> RecordStart:
        """The protocol's command; raises TriggerError for a trigger that is no condition."""
        trigger = parse_trigger(self.trigger) if self.trigger else None
        return RecordStart(
            variables=list(self.variables),
            all_inputs=self.all_inputs,
            trigger=trigger,
            pre_cycles=self.pre_cycles,
            cycles=self.cycles,
            seconds=self.seconds,
            rotate_mb=self.rotate_mb,
            rotate_s=self.rotate_s,
            id=self.id,
        )


# ---- triggers

_PATH = r"[A-Za-z_][A-Za-z0-9_]*(?:\[[0-9, ]+\])*(?:\.[A-Za-z_][A-Za-z0-9_]*(?:\[[0-9, ]+\])*)*"
_NOT = re.compile(rf"NOT\s+({_PATH})", re.IGNORECASE)
_ALONE = re.compile(_PATH)
# the longer operators first, so that `<=` is not read as `<` and a value `= 5`
_COMPARISON = re.compile(rf"({_PATH})\s*(<>|<=|>=|=|<|>)\s*(.+)", re.DOTALL)
_TRUE_FALSE = re.compile(r"(?:BOOL#)?(TRUE|FALSE)", re.IGNORECASE)
# the types a literal can be of, tried in this order: the first that takes it decides
# (BOOL only by TRUE/FALSE above, as `1` is a number here)
_LITERAL_TYPES = ("LINT", "LREAL", "LTIME", "DATE", "TOD", "DT", "STRING", "WSTRING")
_FORM = (
    "a trigger is VARIABLE (= TRUE), NOT VARIABLE (= FALSE) or VARIABLE OP VALUE, "
    "with OP one of = <> < <= > >= and VALUE an ST literal (TRUE, 80, -2.5, T#5s, 'text')"
)


def parse_trigger(text: str) -> Trigger:
    """`Main.level > 80`, `Main.alarm`, `NOT Main.alarm` as the protocol's Trigger; the value
    is an ST literal (TRUE, 16#FF, 2.5, T#5s, 'text'), which the resource compares with
    the variable's value when the variable's type allows the comparison."""
    condition = text.strip()
    negated = _NOT.fullmatch(condition)
    if negated is not None:
        return Trigger(negated[1], "=", False)
    if _ALONE.fullmatch(condition) and condition.upper() not in ("NOT", "TRUE", "FALSE"):
        return Trigger(condition, "=", True)
    compared = _COMPARISON.fullmatch(condition)
    if compared is None:
        raise TriggerError(f"'{text}' is not a trigger: {_FORM}")
    variable, op, literal = compared[1], compared[2], compared[3].strip()
    value = _literal(literal)
    if value is None:
        raise TriggerError(f"'{text}': {literal} is not an ST literal; {_FORM}")
    return Trigger(variable, op, value)  # type: ignore[arg-type]  # op is one of the six


def _literal(text: str) -> bool | int | float | str | None:
    """The value of an ST literal whose type the literal itself says."""
    boolean = _TRUE_FALSE.fullmatch(text)
    if boolean is not None:
        return boolean[1].upper() == "TRUE"
    for type_name in _LITERAL_TYPES:
        try:
            value: bool | int | float | str = parse_literal(text, type_name)
        except LiteralError:
            continue
        return value
    return None


# ---- recordings


def start(client: ResourceClient, spec: RecordingSpec) -> RecordingInfo:
    """Start a recording; the resource's refusal (the level, an unknown variable, too many
    running) as a Refusal, a trigger that is no condition as TriggerError."""
    return client.ask(spec.command()).recording


def stop(client: ResourceClient, recording_id: str) -> RecordingInfo:
    return client.ask(RecordStop(recording_id)).recording


def list_recordings(client: ResourceClient) -> list[RecordingInfo]:
    """The recordings in the resource's state folder, the running ones first."""
    return client.ask(RecordList()).recordings


def find(client: ResourceClient, recording_id: str) -> RecordingInfo:
    for recording in list_recordings(client):
        if recording.id == recording_id:
            return recording
    raise Refusal(
        "unknown_recording", f"resource {client.resource} has no recording '{recording_id}'"
    )


def wait_until_ended(
    client: ResourceClient,
    recording_id: str,
    stop_asked: Callable[[], bool] = lambda: False,
    poll_s: float = POLL_S,
    patience_s: float = PATIENCE_S,
) -> RecordingInfo:
    """Wait until the recording has ended by itself (its cycles or seconds reached, or it
    failed), or until `stop_asked()`: then it is stopped and its files closed. The
    resource may stop answering for up to `patience_s` (a network hiccup, a restart of
    the runtime) without ending the wait: the recording goes on there."""
    stopping = False
    unanswered_since: float | None = None
    while True:
        try:
            current = find(client, recording_id)
        except ResourceUnreachable:
            now = time.monotonic()
            unanswered_since = unanswered_since or now
            if now - unanswered_since > patience_s or stop_asked():
                raise  # Ctrl-C now: the resource could not be told to stop
            time.sleep(poll_s)
            continue
        unanswered_since = None
        if current.state in ENDED:
            return current
        if stop_asked() and not stopping:
            stopping = True  # the writer thread closes the file: wait for it to be done
            try:
                stopped = stop(client, recording_id)
            except Refusal:
                stopped = find(client, recording_id)  # it may have ended meanwhile
                if stopped.state not in ENDED:
                    raise
            if stopped.state in ENDED:
                return stopped
            continue
        time.sleep(poll_s)


def delete(client: ResourceClient, recording_id: str) -> list[RecordingInfo]:
    """Delete a recording that has ended, with its files; the recordings left."""
    return client.ask(RecordDelete(recording_id)).recordings


def download_chunks(client: ResourceClient, file_name: str) -> tuple[int, Iterator[bytes]]:
    """A recording file in pieces as the resource reads them out: its size now, and the
    pieces up to that size. The first piece is asked for at once, so that a file the
    resource does not have is refused here; the others as the iterator is consumed. A
    file still being written is fetched as far as it was when the first piece came."""
    first = client.ask(RecordRead(file_name, 0, MAX_RECORDING_READ))
    size = first.size
    if size < 0:
        raise _bad_reply(client, file_name, f"a size of {size} bytes")

    def pieces() -> Iterator[bytes]:
        reply, offset = first, 0
        while True:
            data = _checked(client, file_name, reply, offset, size)
            if data:
                yield data
            offset += len(data)
            if offset >= size:
                return
            length = min(MAX_RECORDING_READ, size - offset)
            reply = client.ask(RecordRead(file_name, offset, length))

    return size, pieces()


def download(client: ResourceClient, file_name: str, max_bytes: int | None = None) -> bytes:
    """A recording file (a name from `list_recordings`), whole, as far as it is written;
    refused `too_large`, after its first piece, when the resource says it holds more than
    `max_bytes` (what the list said is no promise: the caller keeps all of it in memory)."""
    size, pieces = download_chunks(client, file_name)
    if max_bytes is not None and size > max_bytes:
        raise Refusal(
            "too_large",
            f"resource {client.resource} says {file_name} has {size:,} bytes, "
            f"more than the {max_bytes:,} taken here",
        )
    return b"".join(pieces)


def file_names(client: ResourceClient, recording_id: str) -> list[str]:
    """The files of a recording, in order (its parts as the files rotated)."""
    return sorted((f.name for f in find(client, recording_id).files), key=part_number)


def download_recording(client: ResourceClient, recording_id: str) -> list[tuple[str, bytes]]:
    """Every file of a recording, in order (its parts as the files rotated)."""
    return [(name, download(client, name)) for name in file_names(client, recording_id)]


def part_number(file_name: str) -> int:
    """`<id>-<n>.mcap` -> n (1 for the first file of a recording)."""
    return int(file_name.rsplit("-", 1)[1].removesuffix(".mcap"))


def _checked(
    client: ResourceClient, file_name: str, reply: RecordingChunk, offset: int, size: int
) -> bytes:
    """The bytes of one record_read reply, if they are the ones asked for."""
    if reply.offset != offset:
        raise _bad_reply(client, file_name, f"bytes from {reply.offset} instead of {offset}")
    if reply.size < size:
        raise _bad_reply(client, file_name, f"the file shrank from {size} to {reply.size} bytes")
    try:
        data = base64.b64decode(reply.data, validate=True)
    except (binascii.Error, ValueError):
        raise _bad_reply(client, file_name, "data that is not base64") from None
    if not data and offset < size:
        raise _bad_reply(client, file_name, f"no bytes at {offset} of {size}")
    if len(data) > size - offset:
        data = data[: size - offset]  # grown since: only what the first reply promised
    return data


def _bad_reply(client: ResourceClient, file_name: str, what: str) -> Refusal:
    return Refusal("bad_reply", f"resource {client.resource} sent {what} while reading {file_name}")
