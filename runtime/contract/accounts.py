"""Accounts and sessions as the contract has them (spec section 13): the access levels of
a resource, the form of user names and passwords, the salted slow hash that is all a
project, an artifact or an accounts file ever holds of a password, and the session table
(login to a token with an expiry, the level check, the lock after failed logins). The PES
uses it with its four levels; the PADT with its own three (backend/engineering/padt_accounts.py).

Levels include the ones before: Read (view everything), Operator (start and stop, reset
statistics, force), Read+Write (load, reload, write, single step, parameters), Administrator
(Allow Online Settings). A configuration without accounts runs open: every command is
allowed (for simulation and tests; `status` says so).
"""

from __future__ import annotations

import base64
import hashlib
import hmac
import re
import secrets
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Literal

from runtime.contract.artifact import UserAccount
from runtime.contract.refusal import Refusal

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


FAILURES_BEFORE_LOCK = 5
LOCK_NS = 60 * 10**9


@dataclass
class Session:
    user: str
    level: str
    expires_ns: int


@dataclass
class _Failures:
    count: int = 0
    locked_until_ns: int = 0


@dataclass
class AccessControl:
    """Accounts, sessions and failed logins."""

    users: tuple[UserAccount, ...]
    now_ns: Callable[[], int]
    levels: tuple[str, ...] = LEVELS  # lowest first; each includes the ones before
    sessions: dict[str, Session] = field(default_factory=dict)
    failures: dict[str, _Failures] = field(default_factory=dict)

    @property
    def open(self) -> bool:
        return not self.users

    def login(self, name: str, password: str) -> tuple[str, Session]:
        """A token for a valid name and password; Refusal otherwise (the same answer
        for an unknown name and a wrong password), and for a while after repeated
        failures."""
        now = self.now_ns()
        failures = self.failures.setdefault(name, _Failures())
        if failures.locked_until_ns > now:
            raise Refusal("locked", f"too many failed logins for '{name}': wait")
        account = next((u for u in self.users if u.name == name), None)
        if account is None or not verify_password(password, account.password_hash):
            failures.count += 1
            if failures.count >= FAILURES_BEFORE_LOCK:
                failures.count, failures.locked_until_ns = 0, now + LOCK_NS
            raise Refusal("login_failed", "unknown user or wrong password")
        self.failures.pop(name, None)
        token = secrets.token_urlsafe(32)
        session = Session(account.name, account.level, now + SESSION_NS)
        self.sessions[token] = session
        return token, session

    def logout(self, token: str) -> None:
        self.sessions.pop(token, None)

    def check(self, token: object, needed: str) -> Session | None:
        """The caller's session if its level suffices; None when access is open."""
        if self.open:
            return None
        if not isinstance(token, str) or token not in self.sessions:
            raise Refusal("unauthenticated", "log in first (no valid session token)")
        session = self.sessions[token]
        if session.expires_ns <= self.now_ns():
            del self.sessions[token]
            raise Refusal("unauthenticated", "the session has expired: log in again")
        if self.levels.index(session.level) < self.levels.index(needed):
            raise Refusal(
                "forbidden", f"{session.user} ({session.level}) may not do this: needs {needed}"
            )
        return session

    def valid(self, token: str) -> bool:
        """Whether a session is still there: not logged out, not expired, its account
        unchanged."""
        session = self.sessions.get(token)
        return session is not None and session.expires_ns > self.now_ns()

    def replace_users(self, users: tuple[UserAccount, ...]) -> None:
        """New accounts (download or reload): sessions of users gone or changed end."""
        self.users = users
        kept = {(u.name, u.level) for u in users}
        for token, session in list(self.sessions.items()):
            if (session.user, session.level) not in kept:
                del self.sessions[token]
