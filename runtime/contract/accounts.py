"""Accounts and sessions as the contract has them: the access levels of a resource, the
form of user names and passwords (spec section 13), and the salted slow hash that is all a
project, an artifact or an accounts file ever holds of a password.
"""

from __future__ import annotations

import base64
import hashlib
import hmac
import re
import secrets
from typing import Literal

Level = Literal["read", "operator", "read-write", "administrator"]
LEVELS: tuple[Level, ...] = ("read", "operator", "read-write", "administrator")
NAME_PATTERN = r"[A-Za-z0-9_-]{1,32}"
NAME = re.compile(f"^{NAME_PATTERN}$")
SESSION_NS = 8 * 3600 * 10**9
# scrypt cost: about 50 ms per check here, so guessing is slow and a login still quick
SCRYPT_N, SCRYPT_R, SCRYPT_P = 2**14, 8, 1


def account_problems(
    name: str, level: str, password_hash: str, levels: tuple[str, ...] = LEVELS
) -> list[str]:
    problems = []
    if not NAME.match(name):
        problems.append(f"user name '{name}' must be 1 to 32 of A-Z a-z 0-9 _ -")
    if level not in levels:
        problems.append(f"level of '{name}' must be one of {', '.join(levels)}")
    if not password_hash.startswith("scrypt$") or password_hash.count("$") != 5:
        problems.append(f"password of '{name}' is not a hash from `padt passwd`")
    return problems


def hash_password(password: str, salt: bytes | None = None) -> str:
    if not NAME.match(password):
        raise ValueError("a password is 1 to 32 of A-Z a-z 0-9 _ -")
    salt = salt if salt is not None else secrets.token_bytes(16)
    digest = hashlib.scrypt(
        password.encode(), salt=salt, n=SCRYPT_N, r=SCRYPT_R, p=SCRYPT_P, dklen=32
    )
    encode = base64.b64encode
    return (
        f"scrypt${SCRYPT_N}${SCRYPT_R}${SCRYPT_P}${encode(salt).decode()}${encode(digest).decode()}"
    )


def verify_password(password: str, hashed: str) -> bool:
    try:
        _, n, r, p, salt, digest = hashed.split("$")
        expected = base64.b64decode(digest)
        actual = hashlib.scrypt(
            password.encode(),
            salt=base64.b64decode(salt),
            n=int(n),
            r=int(r),
            p=int(p),
            dklen=len(expected),
        )
    except (ValueError, TypeError):
        return False
    return hmac.compare_digest(actual, expected)
