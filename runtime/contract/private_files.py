"""Files that hold secrets (verifiers, keys) are written whole or not at all, and readable
by their owner only, wherever they are written: the resource's stored configuration and key,
backups, project copies, the PADT's accounts."""

from __future__ import annotations

import contextlib
import os
import tempfile
from pathlib import Path


def staged_private(path: Path, data: bytes) -> Path:
    """`data` in a new owner-only file beside `path`, synced; its name, for `os.replace`
    onto `path` (a crash leaves the old file or the new one). Raises OSError."""
    path.parent.mkdir(parents=True, exist_ok=True)
    handle, temporary = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.")  # 0600
    try:
        with os.fdopen(handle, "wb") as file:
            file.write(data)
            file.flush()
            os.fsync(file.fileno())
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(temporary)
        raise
    return Path(temporary)


def write_private(path: Path, data: bytes) -> None:
    """`data` as the owner-only file `path`, written whole or not at all. Raises OSError."""
    temporary = staged_private(path, data)
    try:
        os.replace(temporary, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(temporary)
        raise
