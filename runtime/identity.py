"""The resource's signing key (runtime/contract/signatures.py): kept in its state folder
(mode 0600) so that it stays the same across restarts, or made fresh for a resource
without one (simulation, tests)."""

from __future__ import annotations

import base64
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
    def __init__(self, key: Ed25519PrivateKey) -> None:
        self._key = key
        raw = key.public_key().public_bytes(Encoding.Raw, PublicFormat.Raw)
        self.public_key = base64.b64encode(raw).decode("ascii")

    @classmethod
    def fresh(cls) -> Identity:
        return cls(Ed25519PrivateKey.generate())

    @classmethod
    def kept_in(cls, path: Path) -> Identity:
        """The key stored at `path`, or a new one stored there first (owner-only)."""
        try:
            return cls(Ed25519PrivateKey.from_private_bytes(path.read_bytes()))
        except (FileNotFoundError, ValueError):
            identity = cls.fresh()
            write_private(path, identity._raw())
            return identity

    def _raw(self) -> bytes:
        return self._key.private_bytes(Encoding.Raw, PrivateFormat.Raw, NoEncryption())

    def sign(self, payload: bytes) -> bytes:
        return self._key.sign(payload)
