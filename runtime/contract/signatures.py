"""Publications a client can trust (spec section 13): a resource signs every message it
publishes (status, events, watch values) with its Ed25519 key, as the message's Zenoh
attachment; the client learns the public key in the reply of a login, under the
resource's server signature (`scram.server_signature`), and drops what does not verify.
A message from anyone else on the bus, or changed on its way, never shows as the
resource's."""

from __future__ import annotations

import base64
import binascii

from cryptography.exceptions import InvalidSignature
from cryptography.hazmat.primitives.asymmetric.ed25519 import Ed25519PublicKey


def verifies(public_key: str, payload: bytes, signature: bytes | None) -> bool:
    if signature is None:
        return False
    try:
        key = Ed25519PublicKey.from_public_bytes(base64.b64decode(public_key, validate=True))
        key.verify(signature, payload)
    except (InvalidSignature, ValueError, binascii.Error):
        return False
    return True
