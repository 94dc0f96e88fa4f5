"""The hash chain of a long-term event log (docs/event-log.md): the one byte form of an
entry and the digest its successor carries as `prev`. The runtime writes its file with
these; a client that reads the long-term log over the bus checks the chain with them."""

from __future__ import annotations

import hashlib
import json
from typing import Any

from runtime.contract.protocol import Event
from runtime.contract.wire import encode

GENESIS = "0" * 64  # the `prev` of the first entry ever


def canonical(value: Any) -> bytes:
    """The one byte form of a value that the chain hashes: sorted keys, no spaces, ASCII."""
    text = json.dumps(
        value, sort_keys=True, separators=(",", ":"), ensure_ascii=True, allow_nan=False
    )
    return text.encode("ascii")


def line_digest(line: bytes) -> str:
    """What the next entry's `prev` holds: SHA-256 of a line without its newline."""
    return hashlib.sha256(line).hexdigest()


def entry_line(event: Event, prev: str) -> bytes:
    """The long-term line of an event that follows the line with digest `prev`."""
    return canonical({**encode(event), "prev": prev})
