"""The PADT's audit log: who changed which project file, and from what to what.

One JSON object per line, appended and never rewritten, in a file readable by its owner
only (it names users and projects). Each entry: the time (Unix ns, from the clock the log
is given), the user, the project, the action (`save`, `create`, `rename`, `delete`,
`new-project`), the file (and the new name of a rename), and the SHA-256 of the file's
content before and after (empty when there was none). docs/audit-log.md describes it.
"""

from __future__ import annotations

import json
import os
import threading
from collections.abc import Callable
from dataclasses import asdict, dataclass
from pathlib import Path

from runtime.contract.outside_json import MIB

MAX_READ_BYTES = 16 * MIB  # what `entries` reads back at most: the newest part


@dataclass(frozen=True)
class AuditEntry:
    time_ns: int
    user: str
    project: str
    action: str  # save, create, rename, delete, new-project
    file: str
    old_hash: str  # "" when the file did not exist before
    new_hash: str  # "" when the file no longer exists
    new_file: str = ""  # the file's new name, for a rename


class PadtAuditLog:
    """Appends entries under a lock, so that lines of two threads never interleave."""

    def __init__(self, path: Path, wall_ns: Callable[[], int]) -> None:
        self.path = path
        self._wall_ns = wall_ns
        self._lock = threading.Lock()

    def record(
        self,
        user: str,
        project: str,
        action: str,
        file: str,
        old_hash: str,
        new_hash: str,
        new_file: str = "",
    ) -> AuditEntry:
        """Append one entry, synced to disk before returning. Raises OSError."""
        with self._lock:
            entry = AuditEntry(
                self._wall_ns(), user, project, action, file, old_hash, new_hash, new_file
            )
            line = json.dumps(asdict(entry), sort_keys=True, ensure_ascii=True) + "\n"
            self.path.parent.mkdir(parents=True, exist_ok=True)
            handle = os.open(self.path, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o600)
            try:
                os.write(handle, line.encode("ascii"))
                os.fsync(handle)
            finally:
                os.close(handle)
            return entry

    def entries(self) -> list[AuditEntry]:
        """The entries, oldest first (of a log larger than MAX_READ_BYTES the newest);
        a line that is no entry (a torn last line after a crash) is skipped."""
        with self._lock:
            try:
                with self.path.open("rb") as handle:
                    size = handle.seek(0, os.SEEK_END)
                    handle.seek(max(0, size - MAX_READ_BYTES))
                    data = handle.read()
            except FileNotFoundError:
                return []
        found = []
        for raw in data.decode("utf-8", "replace").splitlines():
            try:
                found.append(AuditEntry(**json.loads(raw)))
            except (ValueError, TypeError):
                continue
        return found
