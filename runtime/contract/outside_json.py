"""JSON from outside the process, read within limits: the one reader for every file and
message padt did not just make itself (artifacts, recordings, backups and their manifests,
WebSocket messages, account, watch-list and context files).

`json.loads` alone would take any size, raise RecursionError (not a ValueError) on text
nested a few thousand deep, and hand over values nested a thousand deep to code that walks
them by recursion. Here the size is checked before parsing, the parser's recursion is
caught, and the nesting of the result is checked without recursion (`wire.depth`), so that
every such input ends in one error with a reason: `JsonRefused`.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from runtime.contract.wire import depth

# Files hold values of nested STRUCTs and ARRAYs (a start state, an artifact's initial
# values) a few levels below their own structure: far below this, and far above what a
# recursive walk of the result can survive.
FILE_DEPTH = 64
MIB = 1 << 20


class JsonRefused(ValueError):
    """JSON from outside that is not read: not JSON, too large or nested too deep."""


def read_json(
    text: str | bytes, what: str, max_bytes: int, max_depth: int | None = FILE_DEPTH
) -> Any:
    """`text` parsed, when it is at most `max_bytes` long and nested at most `max_depth`
    deep; JsonRefused naming `what` (a file, an entry, a message) otherwise. `max_depth`
    None: the caller checks the depth of what it takes (`wire.decode` does, value by value:
    a walk of the whole of a 100,000-value reply would cost it tens of milliseconds)."""
    if len(text) > max_bytes:
        raise JsonRefused(f"{what} is larger than {max_bytes:,} bytes")
    try:
        data = json.loads(text)
    except RecursionError:
        raise JsonRefused(f"{what} is nested far too deep") from None
    except ValueError as exc:  # UnicodeDecodeError too
        raise JsonRefused(f"{what} is not valid JSON ({exc})") from None
    if max_depth is not None and depth(data, max_depth) > max_depth:
        raise JsonRefused(f"{what} is nested deeper than {max_depth}")
    return data


def read_json_file(path: Path, max_bytes: int, max_depth: int = FILE_DEPTH) -> Any:
    """The JSON file at `path`, its size checked before it is read (OSError when it cannot
    be read); JsonRefused naming it otherwise."""
    if path.stat().st_size > max_bytes:
        raise JsonRefused(f"{path} is larger than {max_bytes:,} bytes")
    return read_json(path.read_bytes(), str(path), max_bytes, max_depth)
