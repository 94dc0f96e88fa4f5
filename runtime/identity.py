"""The resource's signing key (runtime/contract/signatures.py): kept in its state folder
(mode 0600) so that it stays the same across restarts, or made fresh for a resource
without one (simulation, tests). With it, the boot number that stamps every publication:
higher at every start, so that a client takes nothing of an earlier boot for news."""

from __future__ import annotations

import base64
import time
from pathlib import Path

from cryptography.hazmat.primitives.asymmetric.ed25519 import Ed25519PrivateKey
from cryptography.hazmat.primitives.serialization import (
    Encoding,
    NoEncryption,
    PrivateFormat,
    PublicFormat,
)

from runtime.contract.private_files import write_private


class Identity:
    def __init__(self, key: Ed25519PrivateKey, boot: int | None = None) -> None:
        self._key = key
        raw = key.public_key().public_bytes(Encoding.Raw, PublicFormat.Raw)
        self.public_key = base64.b64encode(raw).decode("ascii")
        # a fresh key has no earlier boot: the wall clock will do
        self.boot = boot if boot is not None else time.time_ns()

    @classmethod
    def fresh(cls) -> Identity:
        return cls(Ed25519PrivateKey.generate())

    @classmethod
    def kept_in(cls, path: Path) -> Identity:
        """The key stored at `path`, or a new one stored there first (owner-only), with
        the next boot number (kept beside it)."""
        try:
            key = Ed25519PrivateKey.from_private_bytes(path.read_bytes())
        except (FileNotFoundError, ValueError):
            key = Ed25519PrivateKey.generate()
            write_private(path, key.private_bytes(Encoding.Raw, PrivateFormat.Raw, NoEncryption()))
        return cls(key, _next_boot(path.with_name(path.name + ".boot")))

    def sign(self, payload: bytes) -> bytes:
        return self._key.sign(payload)


def _next_boot(path: Path) -> int:
    """The wall clock, or one more than the last boot when the clock is behind it (set
    back, or a start within the same nanosecond): the boot number never goes down."""
    try:
        last = int(path.read_text().strip())
    except (FileNotFoundError, ValueError):
        last = 0
    boot = max(time.time_ns(), last + 1)
    write_private(path, str(boot).encode())
    return boot
