"""The saved context of a resource, for a warm start (docs/context.md): what it holds, and
its file. `save_context` writes it atomically with a checksum; `load_context` says why a
context cannot be used instead of raising. The values in it are snapshots of the program
instances (`context_snapshot.py`). Whether to warm or cold start is the resource's
decision; this module only makes the data trustworthy.
"""

from __future__ import annotations

import hashlib
import json
import os
import secrets
from contextlib import suppress
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from runtime.context_snapshot import Deferred, Records
from runtime.contract.outside_json import JsonRefused, read_json

CONTEXT_FORMAT = "padt-context"
CONTEXT_VERSION = 1

# A header longer than this is not one of ours (it is about 140 bytes).
_HEADER_MAX = 1024
_BODY_KEYS = frozenset({"globals", "programs", "resource", "saved_ns", "signature"})


@dataclass(frozen=True)
class Context:
    signature: str  # configuration CRC of the artifact it belongs to
    saved_ns: int  # wall-clock time of saving (Unix ns), given by the caller
    resource: dict[str, Any]  # resource-level data (JSON-able), opaque here
    # per user program: {"state", "time_ns", "values": snapshot tree, ...}, opaque here
    programs: dict[str, dict[str, Any]]
    globals: Any  # snapshot tree of the GLOBALS instance, or None
    # (the trees may hold `Records` when the cycle thread took them with `capture`, or be
    # `Deferred` when it copied a memory image)


@dataclass(frozen=True)
class ContextInvalid:
    """Why a saved context cannot be used (the resource then cold starts)."""

    reason: str


def _canonical(value: Any) -> bytes:
    """Canonical JSON of `value`, in which `Records` stand for their record nodes. Those
    are encoded a batch at a time, each batch one short C call: the encoder holds the
    GIL the cycle thread needs while it runs, a whole context of 100,000 values for
    about 20 ms."""
    deferred: list[Records] = []
    marker = f"\x00records-{secrets.token_hex(8)}-"  # no saved string can hold it by chance

    def later(item: Any) -> Any:
        if type(item) is Deferred:
            return item.build()  # a tree, which the encoder then writes in its place
        if type(item) is not Records:
            raise TypeError(f"cannot save a value of type {type(item).__qualname__}")
        deferred.append(item)
        return f"{marker}{len(deferred) - 1}"

    text = _dumps(value, later)
    if deferred:
        quoted = _dumps(marker, None)[:-1]  # as the encoder writes it, less the closing quote
        pieces = text.split(quoted)
        parts = [pieces[0]]
        for piece in pieces[1:]:
            number, rest = piece.split('"', 1)
            parts += ["[", _records_json(deferred[int(number)]), "]", rest]
        text = "".join(parts)
    return text.encode("ascii")


def _dumps(value: Any, default: Any) -> str:
    # ASCII: a WSTRING's lone surrogate is written as \\udxxx, which UTF-8 could not hold
    return json.dumps(
        value,
        sort_keys=True,
        separators=(",", ":"),
        ensure_ascii=True,
        allow_nan=False,
        default=default,
    )


_RECORDS_BATCH = 1_000


def _records_json(records: Records) -> str:
    """The record nodes of `records` as JSON array items, a batch per encoder call."""
    batches = []
    for start in range(0, len(records.rows), _RECORDS_BATCH):
        batch = _dumps(records.nodes(start, start + _RECORDS_BATCH), None)
        batches.append(batch[1:-1])
    return ",".join(batches)


def encode_context(context: Context) -> bytes:
    """The file content: a header line (format, version, body length, SHA-256 of the body),
    then the body, canonical JSON of the context."""
    body = _canonical(
        {
            "globals": context.globals,
            "programs": context.programs,
            "resource": context.resource,
            "saved_ns": context.saved_ns,
            "signature": context.signature,
        }
    )
    header = {
        "body_bytes": len(body),
        "format": CONTEXT_FORMAT,
        "sha256": hashlib.sha256(body).hexdigest(),
        "version": CONTEXT_VERSION,
    }
    return _canonical(header) + b"\n" + body


def decode_context(data: bytes, signature: str) -> Context | ContextInvalid:
    """The context in `data` if it is intact and belongs to the configuration `signature`."""
    if not data:
        return ContextInvalid("truncated: the file is empty")
    newline = data.find(b"\n", 0, _HEADER_MAX)
    if newline < 0:
        if len(data) < _HEADER_MAX:
            return ContextInvalid("truncated: no complete header line")
        return ContextInvalid("not a padt context: no header line")
    try:
        header = read_json(data[:newline], "the header", _HEADER_MAX)
    except JsonRefused:
        return ContextInvalid("not a padt context: the header is not JSON")
    if not isinstance(header, dict) or header.get("format") != CONTEXT_FORMAT:
        found = header.get("format") if isinstance(header, dict) else None
        return ContextInvalid(f"not a padt context (format {found!r})")
    version = header.get("version")
    if type(version) is not int or version != CONTEXT_VERSION:
        return ContextInvalid(f"format version {version} unknown")
    length, digest = header.get("body_bytes"), header.get("sha256")
    if type(length) is not int or length < 0 or not isinstance(digest, str):
        return ContextInvalid("malformed header: body_bytes or sha256 missing")
    body = data[newline + 1 :]
    if len(body) < length:
        return ContextInvalid(f"truncated: the body has {len(body)} of {length} bytes")
    if len(body) > length:
        return ContextInvalid(f"{len(body) - length} bytes after the body")
    if hashlib.sha256(body).hexdigest() != digest:
        return ContextInvalid("checksum mismatch: the body's SHA-256 differs from the header's")
    try:
        fields = read_json(body, "the body", len(body))  # its size is the header's, checked
    except JsonRefused as exc:
        return ContextInvalid(f"malformed body: {exc}")
    problem = _body_problem(fields)
    if problem is not None:
        return ContextInvalid(f"malformed body: {problem}")
    if fields["signature"] != signature:
        return ContextInvalid(
            f"signature {fields['signature']} is not the loaded configuration's {signature}"
        )
    return Context(
        signature=fields["signature"],
        saved_ns=fields["saved_ns"],
        resource=fields["resource"],
        programs=fields["programs"],
        globals=fields["globals"],
    )


def _body_problem(fields: Any) -> str | None:
    if not isinstance(fields, dict) or fields.keys() != _BODY_KEYS:
        return f"expected the fields {sorted(_BODY_KEYS)}"
    if not isinstance(fields["signature"], str):
        return "signature is not a string"
    if type(fields["saved_ns"]) is not int:
        return "saved_ns is not an integer"
    if not isinstance(fields["resource"], dict):
        return "resource is not an object"
    programs = fields["programs"]
    if not isinstance(programs, dict) or not all(isinstance(p, dict) for p in programs.values()):
        return "programs is not an object of objects"
    return None


def save_context(path: Path, context: Context) -> None:
    """Write `context` to `path` atomically: after a crash at any point, `path` holds either
    the previous context or this one, complete. Raises OSError when it cannot write."""
    data = encode_context(context)
    temp = path.with_name(path.name + ".tmp")
    # a temp file left by a crash is removed, and O_EXCL then never writes through a link
    with suppress(FileNotFoundError):
        os.unlink(temp)
    fd = os.open(temp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
    try:
        with os.fdopen(fd, "wb") as file:
            file.write(data)
            file.flush()
            os.fsync(file.fileno())  # the data is on disk before the rename can be
        os.replace(temp, path)
    except BaseException:
        with suppress(OSError):
            os.unlink(temp)
        raise
    _fsync_directory(path.parent)  # the rename itself is on disk


def _fsync_directory(directory: Path) -> None:
    flag = getattr(os, "O_DIRECTORY", None)
    if flag is None:
        return  # Windows cannot open a directory; its renames are journaled by NTFS
    fd = os.open(directory, os.O_RDONLY | flag)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def load_context(path: Path, signature: str) -> Context | ContextInvalid:
    """The context saved at `path`, or why there is none to use; never raises for a bad or
    missing file."""
    try:
        data = path.read_bytes()
    except FileNotFoundError:
        return ContextInvalid("no saved context")
    except OSError as exc:
        return ContextInvalid(f"cannot read the context: {exc.strerror or exc}")
    return decode_context(data, signature)
