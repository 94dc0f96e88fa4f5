"""The public keys of the resources whose publications this resource takes, pinned at the
first message taken from each (trust on first use) and kept in the state folder
(`exchange-peers`, owner-only; one `resource key` line each). A message signed with any
other key is refused from then on, also after a restart; delete the resource's line once
you know why its key changed (its state folder was made anew).

Written on Zenoh's threads, never on the cycle thread.
"""

from __future__ import annotations

import logging
import threading
from pathlib import Path

from runtime.contract.private_files import write_private

MAX_FILE_BYTES = 64 * 1024
log = logging.getLogger(__name__)


class PeerKeys:
    def __init__(self, path: Path | None) -> None:
        """`path` None: pinned in memory only (a resource without a state folder)."""
        self._path = path
        self._lock = threading.Lock()
        self._keys: dict[str, str] = {}
        if path is not None and path.is_file() and path.stat().st_size <= MAX_FILE_BYTES:
            for line in path.read_text(errors="replace").splitlines():
                parts = line.split()
                if len(parts) == 2:
                    self._keys[parts[0].upper()] = parts[1]

    def problem(self, resource: str, key: str) -> str | None:
        """Why a message of `resource` signed with `key` is not taken (None: it is; a
        resource seen for the first time has its key pinned now)."""
        with self._lock:
            pinned = self._keys.get(resource.upper())
            if pinned == key:
                return None
            if pinned is not None:
                return (
                    f"signed by another key than the one pinned for {resource} "
                    f"({key[:12]}..., pinned {pinned[:12]}...)"
                )
            self._keys[resource.upper()] = key
            if self._path is not None:
                text = "".join(f"{name} {k}\n" for name, k in sorted(self._keys.items()))
                try:
                    write_private(self._path, text.encode())
                except OSError as exc:  # pinned for this run; said in the log
                    log.warning("exchange: cannot keep the key of %s: %s", resource, exc)
            return None
