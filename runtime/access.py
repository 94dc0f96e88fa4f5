"""Access control in the PES itself (spec section 13): user accounts from the loaded
configuration, login to a session token with an expiry, and the level every command needs,
checked for every request whoever sends it.

Levels include the ones before: Read (view everything), Operator (start and stop, reset
statistics, force), Read+Write (load, reload, write, single step, parameters), Administrator
(Allow Online Settings). Passwords exist only as salted scrypt hashes, in the project and
the artifact alike. A configuration without accounts runs open: every command is allowed
(for simulation and tests; `status` says so).
"""

from __future__ import annotations

import secrets
from collections.abc import Callable
from dataclasses import dataclass, field

from runtime.contract.accounts import LEVELS, SESSION_NS, verify_password
from runtime.contract.artifact import UserAccount

FAILURES_BEFORE_LOCK = 5
LOCK_NS = 60 * 10**9

COMMAND_LEVELS: dict[str, str] = {
    **dict.fromkeys(
        ("status", "values", "variables", "parameters", "forcing", "events", "watches",
         "watch", "unwatch"),
        "read",
    ),
    **dict.fromkeys(
        ("start", "stop", "start_program", "stop_program", "reset_stats", "force", "unforce",
         "start_forcing", "stop_forcing"),
        "operator",
    ),
    **dict.fromkeys(
        ("step", "init", "cold_start", "freeze", "unfreeze", "step_program", "write",
         "set_parameter", "transfer_begin", "transfer_chunk", "load", "reload_preview",
         "reload"),
        "read-write",
    ),
}  # fmt: skip
ADMINISTRATOR_PARAMETERS = ("allow_online_settings",)


class AccessDenied(Exception):
    def __init__(self, code: str, message: str) -> None:
        super().__init__(message)
        self.code = code
        self.message = message


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
    """Accounts, sessions and failed logins. The PES uses it with its four levels; the
    PADT's REST API with its own three (backend/api/accounts.py)."""

    users: tuple[UserAccount, ...]
    now_ns: Callable[[], int]
    levels: tuple[str, ...] = LEVELS  # lowest first; each includes the ones before
    sessions: dict[str, Session] = field(default_factory=dict)
    failures: dict[str, _Failures] = field(default_factory=dict)

    @property
    def open(self) -> bool:
        return not self.users

    def login(self, name: str, password: str) -> tuple[str, Session]:
        """A token for a valid name and password; AccessDenied otherwise (the same answer
        for an unknown name and a wrong password), and for a while after repeated
        failures."""
        now = self.now_ns()
        failures = self.failures.setdefault(name, _Failures())
        if failures.locked_until_ns > now:
            raise AccessDenied("locked", f"too many failed logins for '{name}': wait")
        account = next((u for u in self.users if u.name == name), None)
        if account is None or not verify_password(password, account.password_hash):
            failures.count += 1
            if failures.count >= FAILURES_BEFORE_LOCK:
                failures.count, failures.locked_until_ns = 0, now + LOCK_NS
            raise AccessDenied("login_failed", "unknown user or wrong password")
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
            raise AccessDenied("unauthenticated", "log in first (no valid session token)")
        session = self.sessions[token]
        if session.expires_ns <= self.now_ns():
            del self.sessions[token]
            raise AccessDenied("unauthenticated", "the session has expired: log in again")
        if self.levels.index(session.level) < self.levels.index(needed):
            raise AccessDenied(
                "forbidden", f"{session.user} ({session.level}) may not do this: needs {needed}"
            )
        return session

    def replace_users(self, users: tuple[UserAccount, ...]) -> None:
        """New accounts (download or reload): sessions of users gone or changed end."""
        self.users = users
        kept = {(u.name, u.level) for u in users}
        for token, session in list(self.sessions.items()):
            if (session.user, session.level) not in kept:
                del self.sessions[token]
