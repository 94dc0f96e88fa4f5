"""The resources this PADT knows by their signing keys, as ssh knows hosts: the key a
resource signs its login challenges and publications with (runtime/identity.py), pinned
at the first login that proved it (trust on first use) and checked at every later one.

A party that answers on a resource's command key with another key is refused before the
client derives anything from a password (`ResourceClient.login`). The file is plain text,
one `resource key` line each, owner-only (0600): `PADT_KNOWN_RESOURCES` names it, else
`$XDG_CONFIG_HOME/padt/known_resources` (`~/.config/...`). When a resource's key changes
for a good reason (its state folder was lost, it moved to another host), delete its line.
"""

from __future__ import annotations

import base64
import binascii
import hashlib
import logging
import os
import threading
from dataclasses import dataclass, field
from pathlib import Path

from runtime.contract.private_files import write_private
from runtime.contract.refusal import Refusal

ENVIRONMENT = "PADT_KNOWN_RESOURCES"
MAX_FILE_BYTES = 1 << 20  # far more than any PADT's resources need
log = logging.getLogger("padt.known_resources")


def default_path() -> Path:
    named = os.environ.get(ENVIRONMENT)
    if named:
        return Path(named)
    config = os.environ.get("XDG_CONFIG_HOME") or str(Path.home() / ".config")
    return Path(config) / "padt" / "known_resources"


def fingerprint(key: str) -> str:
    """What people compare of a key: SHA256 of its raw bytes, as ssh shows it."""
    try:
        raw = base64.b64decode(key, validate=True)
    except (ValueError, binascii.Error):
        raw = key.encode()
    digest = base64.b64encode(hashlib.sha256(raw).digest()).decode().rstrip("=")
    return f"SHA256:{digest}"


@dataclass
class KnownResources:
    path: Path = field(default_factory=default_path)
    _lock: threading.Lock = field(default_factory=threading.Lock, repr=False)

    def key_of(self, resource: str) -> str | None:
        return self._read().get(resource)

    def check(self, resource: str, key: str) -> None:
        """Refusal `impostor` when `resource` is known by another key."""
        known = self.key_of(resource)
        if known is not None and known != key:
            raise Refusal(
                "impostor",
                f"resource {resource} answers with key {fingerprint(key)}, but it is known "
                f"by {fingerprint(known)} ({self.path}): another party answers in its "
                f"place, or its key changed (if you know why, delete its line there)",
            )

    def remember(self, resource: str, key: str) -> None:
        """Pin `key` for `resource` (a login proved it); a key already known stays."""
        with self._lock:
            known = self._read()
            if resource in known:
                return
            known[resource] = key
            text = "".join(f"{name} {value}\n" for name, value in sorted(known.items()))
            try:
                write_private(self.path, text.encode())
            except OSError as exc:  # the login holds; the next one tries to pin again
                log.warning("cannot keep the key of %s in %s: %s", resource, self.path, exc)

    def _read(self) -> dict[str, str]:
        try:
            with self.path.open("rb") as file:
                data = file.read(MAX_FILE_BYTES + 1)
        except FileNotFoundError:
            return {}
        except OSError as exc:
            raise Refusal("known_resources", f"cannot read {self.path}: {exc}") from None
        if len(data) > MAX_FILE_BYTES:
            raise Refusal("known_resources", f"{self.path} is larger than {MAX_FILE_BYTES} bytes")
        known: dict[str, str] = {}
        for line in data.decode("utf-8", "replace").splitlines():
            parts = line.split()
            if len(parts) == 2 and not line.startswith("#"):
                known.setdefault(parts[0], parts[1])
        return known
