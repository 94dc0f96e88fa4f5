"""Publications a client can trust (spec section 13): a resource signs every message it
publishes (status, events, watch values) with its Ed25519 key; the client learns the
public key in the reply of a login, under the resource's server signature
(`scram.server_signature`), and drops what does not verify. A message from anyone else on
the bus, or changed on its way, never shows as the resource's.

A signed message put again later (a replay) would verify too: so every publication is
stamped with the resource's boot number (it grows with every start of the runtime) and
its number in that boot (it grows with every publication), inside what is signed. The
Zenoh attachment of a publication is the stamp (16 bytes: boot, number, big-endian)
followed by the signature of the stamp and the payload. A client keeps the highest stamp
it took per key (`Freshness`) and drops what is not newer: a replay of this boot or of
an earlier one."""

from __future__ import annotations

import base64
import binascii
import struct
import threading
from dataclasses import dataclass, field

from cryptography.exceptions import InvalidSignature
from cryptography.hazmat.primitives.asymmetric.ed25519 import Ed25519PublicKey

_STAMP = struct.Struct(">QQ")
Stamp = tuple[int, int]  # (boot, number): ordered as tuples are


def verifies(public_key: str, payload: bytes, signature: bytes | None) -> bool:
    if signature is None:
        return False
    try:
        key = Ed25519PublicKey.from_public_bytes(base64.b64decode(public_key, validate=True))
        key.verify(signature, payload)
    except (InvalidSignature, ValueError, binascii.Error):
        return False
    return True


def stamp_bytes(boot: int, number: int) -> bytes:
    return _STAMP.pack(boot, number)


def stamped(stamp: bytes, payload: bytes) -> bytes:
    """What the resource signs of a publication: its stamp and its bytes."""
    return stamp + payload


def verified_stamp(public_key: str, payload: bytes, attachment: bytes | None) -> Stamp | None:
    """The stamp of a publication signed with `public_key`; None when it is not."""
    if attachment is None or len(attachment) <= _STAMP.size:
        return None
    stamp, signature = attachment[: _STAMP.size], attachment[_STAMP.size :]
    if not verifies(public_key, stamped(stamp, payload), signature):
        return None
    boot, number = _STAMP.unpack(stamp)
    return boot, number


@dataclass
class Freshness:
    """The highest stamp taken per key: a publication is taken only when it is newer (a
    new boot of the runtime is; a message of an earlier boot, or one already taken, is
    not). Zenoh calls back on several threads, hence the lock."""

    _highest: dict[str, Stamp] = field(default_factory=dict)
    _lock: threading.Lock = field(default_factory=threading.Lock)

    def newer(self, key: str, stamp: Stamp) -> bool:
        with self._lock:
            highest = self._highest.get(key)
            if highest is not None and stamp <= highest:
                return False
            self._highest[key] = stamp
            return True
