"""Logging in without a password on the bus, both ends authenticated (spec section 13):
a challenge-response over the stored verifier in the manner of SCRAM (RFC 5802 and 7677),
with scrypt as the key derivation and SHA-256 for the rest.

A verifier (`scram$N$r$p$salt$StoredKey$ServerKey`, base64) is all that a project, an
artifact or an accounts file holds of a password:

    SaltedPassword = scrypt(password, salt, N, r, p)
    ClientKey      = HMAC(SaltedPassword, "Client Key")      StoredKey = SHA-256(ClientKey)
    ServerKey      = HMAC(SaltedPassword, "Server Key")

The exchange: the client sends its user name and a nonce (`login_begin`); the resource
answers with the salt, the cost parameters and the nonce extended by its own part, signed
with its Ed25519 key (`challenge_message`). The client derives nothing from the password
before it has checked that signature against the key it knows for the resource, and that
the cost is no weaker than what `padt passwd` makes (`cost_problem`): a party that answers
in the resource's place with a cheap challenge would get a proof it could crack. The
client proves that it knows ClientKey (`login`: ClientProof = ClientKey XOR
HMAC(StoredKey, AuthMessage)); the resource proves that it holds the verifier
(ServerSignature = HMAC(ServerKey, AuthMessage | publication key)). Neither message helps
anyone who listens, or who answers in the resource's place, to log in. Both ends then
share a session key that an eavesdropper cannot compute; every later request of the
session carries a MAC with it (`request_mac`), so a session token alone is worth nothing.
Older verifiers (`scrypt$N$r$p$salt$SaltedPassword`) are read too.
"""

from __future__ import annotations

import base64
import hashlib
import hmac
import secrets
from dataclasses import dataclass

from runtime.contract.refusal import Refusal

# scrypt cost: about 50 ms per derivation here; the client pays it, the resource never does
SCRYPT_N, SCRYPT_R, SCRYPT_P = 2**14, 8, 1
NONCE_BYTES = 18  # 24 characters of base64
# the most a challenge may ask of a client: scrypt holds 128 * r * N bytes (64 MiB here)
MAX_SCRYPT_N, MAX_SCRYPT_R, MAX_SCRYPT_P = 2**17, 16, 4
MAX_SCRYPT_MEMORY = 64 * 2**20


@dataclass(frozen=True)
class Verifier:
    n: int
    r: int
    p: int
    salt: bytes
    stored_key: bytes
    server_key: bytes


def b64(data: bytes) -> str:
    return base64.b64encode(data).decode("ascii")


def unb64(text: str) -> bytes:
    try:
        return base64.b64decode(text, validate=True)
    except (ValueError, TypeError):
        raise Refusal("bad_request", "not base64") from None


def cost_problem(n: int, r: int, p: int) -> str | None:
    """Why a client does not derive a key at this cost (None: it does): weaker than the
    verifiers `padt passwd` makes, which would make a captured proof cheap to crack, more
    than a client gives, or no scrypt cost at all."""
    asked = f"scrypt N={n}, r={r}, p={p}"
    if n < 2 or n & (n - 1):
        return f"{asked}: N is not a power of 2"
    if n < SCRYPT_N or r < SCRYPT_R or p < SCRYPT_P:
        return f"{asked} is weaker than N={SCRYPT_N}, r={SCRYPT_R}, p={SCRYPT_P}"
    if n > MAX_SCRYPT_N or r > MAX_SCRYPT_R or p > MAX_SCRYPT_P or 128 * r * n > MAX_SCRYPT_MEMORY:
        return (
            f"{asked} asks for more than a client gives (N <= {MAX_SCRYPT_N}, r <= "
            f"{MAX_SCRYPT_R}, p <= {MAX_SCRYPT_P}, {MAX_SCRYPT_MEMORY >> 20} MiB)"
        )
    return None


def _memory(n: int, r: int, p: int) -> int:
    """What scrypt holds (OpenSSL's count: 128 r (N + 2) + 128 r p bytes)."""
    return 128 * r * (n + 2 + p)


def salted_password(password: str, salt: bytes, n: int, r: int, p: int) -> bytes:
    # the memory the cost needs, said: hashlib's default (32 MiB) refuses N=2**15, r=8
    maxmem = _memory(n, r, p) + 2**20
    return hashlib.scrypt(password.encode(), salt=salt, n=n, r=r, p=p, maxmem=maxmem, dklen=32)


def _hmac(key: bytes, message: bytes) -> bytes:
    return hmac.new(key, message, hashlib.sha256).digest()


def client_key(salted: bytes) -> bytes:
    return _hmac(salted, b"Client Key")


def stored_key(key: bytes) -> bytes:
    return hashlib.sha256(key).digest()


def server_key(salted: bytes) -> bytes:
    return _hmac(salted, b"Server Key")


def make_verifier(password: str, salt: bytes | None = None) -> str:
    """The verifier of a password, as `padt passwd` prints it."""
    salt = salt if salt is not None else secrets.token_bytes(16)
    salted = salted_password(password, salt, SCRYPT_N, SCRYPT_R, SCRYPT_P)
    parts = (b64(salt), b64(stored_key(client_key(salted))), b64(server_key(salted)))
    return f"scram${SCRYPT_N}${SCRYPT_R}${SCRYPT_P}${'$'.join(parts)}"


def parse_verifier(text: str) -> Verifier | None:
    """A verifier, from either form; None when `text` is neither."""
    try:
        kind, n, r, p, salt, *keys = text.split("$")
        if kind == "scram" and len(keys) == 2:
            stored, server = (base64.b64decode(key, validate=True) for key in keys)
        elif kind == "scrypt" and len(keys) == 1:
            salted = base64.b64decode(keys[0], validate=True)
            stored, server = stored_key(client_key(salted)), server_key(salted)
        else:
            return None
        return Verifier(
            int(n), int(r), int(p), base64.b64decode(salt, validate=True), stored, server
        )
    except ValueError:
        return None


def password_matches(password: str, verifier: Verifier) -> bool:
    """For a password given where it may be (the PADT's own login over HTTPS)."""
    salted = salted_password(password, verifier.salt, verifier.n, verifier.r, verifier.p)
    return hmac.compare_digest(stored_key(client_key(salted)), verifier.stored_key)


def new_nonce() -> str:
    return base64.urlsafe_b64encode(secrets.token_bytes(NONCE_BYTES)).decode("ascii")


def auth_message(
    realm: str, user: str, client_nonce: str, nonce: str, salt: bytes, n: int, r: int, p: int
) -> bytes:
    """What both ends sign: the resource (`realm`) too, so that a proof made for one
    resource is worth nothing at another."""
    fields = (realm, user, client_nonce, nonce, b64(salt), n, r, p)
    return "|".join(str(field) for field in fields).encode()


def challenge_message(auth: bytes) -> bytes:
    """What the resource signs of its challenge: the AuthMessage, which holds the client's
    own nonce, so that a signed challenge cannot be replayed to another login."""
    return b"padt login challenge|" + auth


def client_proof(key: bytes, auth: bytes) -> bytes:
    signature = _hmac(stored_key(key), auth)
    return bytes(a ^ b for a, b in zip(key, signature, strict=True))


def proof_holds(proof: bytes, verifier: Verifier, auth: bytes) -> bool:
    """Whether `proof` was made with the ClientKey behind the verifier."""
    signature = _hmac(verifier.stored_key, auth)
    if len(proof) != len(signature):
        return False
    key = bytes(a ^ b for a, b in zip(proof, signature, strict=True))
    return hmac.compare_digest(stored_key(key), verifier.stored_key)


def server_signature(server: bytes, auth: bytes, publication_key: str) -> bytes:
    return _hmac(server, auth + b"|" + publication_key.encode())


def session_key(stored: bytes, auth: bytes) -> bytes:
    return _hmac(stored, b"Session Key|" + auth)


def request_mac(key: bytes, payload: bytes) -> bytes:
    return _hmac(key, payload)


def mac_holds(key: bytes, payload: bytes, mac: bytes) -> bool:
    return hmac.compare_digest(request_mac(key, payload), mac)


@dataclass(frozen=True)
class ClientExchange:
    """The client's side of a login, from the challenge on: the proof to send, the check
    of the resource's answer, and the session key."""

    salted: bytes
    auth: bytes

    @classmethod
    def answer(
        cls,
        realm: str,
        user: str,
        password: str,
        client_nonce: str,
        nonce: str,
        salt: bytes,
        n: int,
        r: int,
        p: int,
    ) -> ClientExchange:
        salted = salted_password(password, salt, n, r, p)
        return cls(salted, auth_message(realm, user, client_nonce, nonce, salt, n, r, p))

    @property
    def proof(self) -> str:
        return b64(client_proof(client_key(self.salted), self.auth))

    def server_proven(self, signature: str, publication_key: str) -> bool:
        expected = server_signature(server_key(self.salted), self.auth, publication_key)
        return hmac.compare_digest(expected, unb64(signature))

    @property
    def session_key(self) -> bytes:
        return session_key(stored_key(client_key(self.salted)), self.auth)
