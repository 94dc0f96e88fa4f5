"""Accounts and sessions as the contract has them (spec section 13): the access levels of
a resource, the form of user names and passwords, and the session table: login to a token
with an expiry, the level check, the lock after failed logins. The PES uses it with its
four levels and the challenge-response login of `scram.py`, so that no password crosses
the bus; the PADT with its own three levels and a password login over HTTP
(backend/engineering/padt_accounts.py).

Levels include the ones before: Read (view everything), Operator (start and stop, reset
statistics, force), Read+Write (load, reload, write, single step, parameters), Administrator
(Allow Online Settings). A configuration without accounts runs open: every command is
allowed (for simulation and tests; `status` says so).
"""

from __future__ import annotations

import re
import secrets
from collections import OrderedDict
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Literal

from runtime.contract import scram
from runtime.contract.artifact import UserAccount
from runtime.contract.refusal import Refusal

Level = Literal["read", "operator", "read-write", "administrator"]
LEVELS: tuple[Level, ...] = ("read", "operator", "read-write", "administrator")
NAME_PATTERN = r"[A-Za-z0-9_-]{1,32}"
NAME = re.compile(f"^{NAME_PATTERN}$")
SESSION_NS = 8 * 3600 * 10**9
MAX_FAILURE_RECORDS = 10_000  # (name, source) pairs remembered; the oldest are forgotten
CHALLENGE_NS = 30 * 10**9  # how long a login challenge may wait for its answer
MAX_CHALLENGES = 1000
REPLAY_WINDOW = 64  # a request's sequence number may come this far out of order
ANONYMOUS = "anonymous"  # the source of a request that names none
ANY_SOURCE = "*"  # the failures of a name on the bus, whatever source the requests named


@dataclass(frozen=True)
class LockPolicy:
    """When failed logins lock a name, and for how long: `free` failures lock nothing,
    each further one locks for `first_ns`, doubled every time up to `last_ns`; failures
    are forgotten `forgotten_ns` after the last one (None: only at a successful login)."""

    free: int
    first_ns: int
    last_ns: int
    forgotten_ns: int | None


# the PADT's own login over HTTP: the caller's address is the TCP peer's, which the caller
# cannot choose, so a name locks for that address only
ADDRESS_LOCK = LockPolicy(4, 10**9, 60 * 10**9, None)
# the bus: the source a request names is the sender's claim (Zenoh's source_info), so it
# can neither be the key of a lock (a rogue would lock out the client it names) nor let a
# guesser escape one (by naming a new source for each guess). A name is throttled for
# every source alike; a success does not clear it (a guesser would get `free` guesses
# more with every login of the real user), time does.
NAME_THROTTLE = LockPolicy(10, 10**9, 30 * 10**9, 15 * 60 * 10**9)


def account_problems(
    name: str, level: str, password_hash: str, levels: tuple[str, ...] = LEVELS
) -> list[str]:
    problems = []
    if not NAME.match(name):
        problems.append(f"user name '{name}' must be 1 to 32 of A-Z a-z 0-9 _ -")
    if level not in levels:
        problems.append(f"level of '{name}' must be one of {', '.join(levels)}")
    if scram.parse_verifier(password_hash) is None:
        problems.append(f"password of '{name}' is not a verifier from `padt passwd`")
    return problems


def hash_password(password: str, salt: bytes | None = None) -> str:
    """The verifier of a password: what a project or an accounts file holds of it."""
    if not NAME.match(password):
        raise ValueError("a password is 1 to 32 of A-Z a-z 0-9 _ -")
    return scram.make_verifier(password, salt)


def verify_password(password: str, hashed: str) -> bool:
    verifier = scram.parse_verifier(hashed)
    return verifier is not None and scram.password_matches(password, verifier)


@dataclass
class Session:
    user: str
    level: str
    expires_ns: int
    key: bytes | None = None  # the key of the login exchange: every request carries its MAC
    highest_seq: int = 0
    seen: set[int] = field(default_factory=set)  # sequence numbers in the replay window

    def fresh(self, seq: int) -> bool:
        """Whether a request's sequence number is new (requests may overtake each other
        a little, but none is taken twice)."""
        if seq <= self.highest_seq - REPLAY_WINDOW or seq in self.seen:
            return False
        self.seen.add(seq)
        if seq > self.highest_seq:
            self.highest_seq = seq
            self.seen = {s for s in self.seen if s > seq - REPLAY_WINDOW}
        return True


@dataclass(frozen=True)
class Challenge:
    """What `login_begin` answers: the nonce, and how the client derives its keys."""

    nonce: str
    salt: str
    n: int
    r: int
    p: int


@dataclass(frozen=True)
class Proven:
    """A login that succeeded: the token, the session, and the resource's proof."""

    token: str
    session: Session
    server_signature: str


@dataclass
class _Pending:
    user: str
    client_nonce: str
    verifier: scram.Verifier
    account: UserAccount | None
    expires_ns: int


@dataclass
class _Failures:
    next_lock_ns: int
    count: int = 0
    locked_until_ns: int = 0
    last_ns: int = 0


@dataclass
class AccessControl:
    """Accounts, sessions and failed logins. Repeated failures of the password login lock
    a name for the address they come from only (`ADDRESS_LOCK`); failures of the login on
    the bus throttle the name for all, as their source is only claimed (`NAME_THROTTLE`).
    Either lock doubles with every further failure, up to a cap."""

    users: tuple[UserAccount, ...]
    now_ns: Callable[[], int]
    levels: tuple[str, ...] = LEVELS  # lowest first; each includes the ones before
    realm: str = ""  # the resource whose accounts these are: part of every login proof
    sessions: dict[str, Session] = field(default_factory=dict)
    failures: OrderedDict[tuple[str, str], _Failures] = field(default_factory=OrderedDict)
    # the bus failures of the accounts, apart: made-up names cannot push them out
    account_failures: dict[str, _Failures] = field(default_factory=dict)
    _pending: OrderedDict[str, _Pending] = field(default_factory=OrderedDict)
    _secret: bytes = field(default_factory=lambda: secrets.token_bytes(32))

    @property
    def open(self) -> bool:
        return not self.users

    # ---- login with a password (the PADT's own accounts, over HTTP)
    def login(self, name: str, password: str, source: str = ANONYMOUS) -> tuple[str, Session]:
        """A token for a valid name and password; Refusal otherwise (the same answer
        for an unknown name and a wrong password), and for a while after repeated
        failures from the same source."""
        key = (name, source)
        self._not_locked(name, self._failures(key))
        account = self._account(name)
        if account is None or not verify_password(password, account.password_hash):
            raise self._failed(name, key, ADDRESS_LOCK)
        self.failures.pop(key, None)
        return self._open_session(account, None)

    # ---- login by challenge and response (the resource's accounts, over the bus)
    def begin(self, name: str, client_nonce: str, source: str = ANONYMOUS) -> Challenge:
        """The challenge for a login: an unknown name gets one that looks the same (its
        salt derived from a secret of this process), so that it cannot be told apart.
        `source` is what the request claims: not used for the throttle."""
        self._not_locked(name, self._bus_failures(name))
        account = self._account(name)
        verifier = (
            scram.parse_verifier(account.password_hash) if account is not None else None
        ) or self._decoy(name)
        now = self.now_ns()
        nonce = client_nonce + scram.new_nonce()
        for stale in [k for k, c in self._pending.items() if c.expires_ns <= now]:
            del self._pending[stale]
        self._pending[nonce] = _Pending(name, client_nonce, verifier, account, now + CHALLENGE_NS)
        while len(self._pending) > MAX_CHALLENGES:
            self._pending.popitem(last=False)
        return Challenge(nonce, scram.b64(verifier.salt), verifier.n, verifier.r, verifier.p)

    def finish(
        self, name: str, nonce: str, proof: bytes, publication_key: str, source: str = ANONYMOUS
    ) -> Proven:
        """A session for a proof that holds; Refusal `login_failed` otherwise."""
        self._not_locked(name, self._bus_failures(name))
        pending = self._pending.pop(nonce, None)
        if pending is None or pending.user != name or pending.expires_ns <= self.now_ns():
            raise self._failed(name, (name, ANY_SOURCE), NAME_THROTTLE)
        verifier = pending.verifier
        auth = scram.auth_message(
            self.realm, name, pending.client_nonce, nonce, verifier.salt, verifier.n,
            verifier.r, verifier.p,
        )  # fmt: skip
        if pending.account is None or not scram.proof_holds(proof, verifier, auth):
            raise self._failed(name, (name, ANY_SOURCE), NAME_THROTTLE)
        key = scram.session_key(verifier.stored_key, auth)
        token, session = self._open_session(pending.account, key)
        signature = scram.server_signature(verifier.server_key, auth, publication_key)
        return Proven(token, session, scram.b64(signature))

    def _decoy(self, name: str) -> scram.Verifier:
        keyed = scram.request_mac(self._secret, name.encode())
        return scram.Verifier(
            scram.SCRYPT_N, scram.SCRYPT_R, scram.SCRYPT_P, keyed[:16], keyed, keyed
        )

    # ---- sessions
    def logout(self, token: str) -> None:
        self.sessions.pop(token, None)

    def check(
        self,
        token: object,
        needed: str,
        signed: bytes = b"",
        mac: bytes | None = None,
        seq: int | None = None,
    ) -> Session | None:
        """The caller's session if its level suffices, and if the request (`signed`: its
        bytes) carries the session's MAC and a sequence number not seen before; None when
        access is open."""
        if self.open:
            return None
        if not isinstance(token, str) or token not in self.sessions:
            raise Refusal("unauthenticated", "log in first (no valid session token)")
        session = self.sessions[token]
        if session.expires_ns <= self.now_ns():
            del self.sessions[token]
            raise Refusal("unauthenticated", "the session has expired: log in again")
        if session.key is not None:
            if mac is None or seq is None or not scram.mac_holds(session.key, signed, mac):
                raise Refusal("unauthenticated", "the request is not signed with the session key")
            if not session.fresh(seq):
                raise Refusal("unauthenticated", "a request of this session was sent again")
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

    # ---- failures
    def _account(self, name: str) -> UserAccount | None:
        return next((u for u in self.users if u.name == name), None)

    def _open_session(self, account: UserAccount, key: bytes | None) -> tuple[str, Session]:
        token = scram.new_nonce() + scram.new_nonce()
        session = Session(account.name, account.level, self.now_ns() + SESSION_NS, key)
        self.sessions[token] = session
        return token, session

    def _failures(self, key: tuple[str, str]) -> _Failures | None:
        return self.failures.get(key)

    def _bus_failures(self, name: str) -> _Failures | None:
        if self._account(name) is not None:
            return self.account_failures.get(name)
        return self.failures.get((name, ANY_SOURCE))

    def _not_locked(self, name: str, failures: _Failures | None) -> None:
        now = self.now_ns()
        if failures is not None and failures.locked_until_ns > now:
            wait_s = max(1, round((failures.locked_until_ns - now) / 1e9))
            raise Refusal("locked", f"too many failed logins for '{name}': wait {wait_s} s")

    def _failed(self, name: str, key: tuple[str, str], policy: LockPolicy) -> Refusal:
        now = self.now_ns()
        failures = self._bus_failures(name) if key[1] == ANY_SOURCE else self._failures(key)
        forgotten = policy.forgotten_ns
        if failures is not None and forgotten is not None and now - failures.last_ns > forgotten:
            failures.count, failures.next_lock_ns = 0, policy.first_ns
        if failures is None:
            failures = _Failures(policy.first_ns)
            if key[1] == ANY_SOURCE and self._account(name) is not None:
                self.account_failures[name] = failures
            else:
                self.failures[key] = failures
                while len(self.failures) > MAX_FAILURE_RECORDS:
                    self.failures.popitem(last=False)
        failures.count += 1
        failures.last_ns = now
        if failures.count > policy.free:
            failures.locked_until_ns = now + failures.next_lock_ns
            failures.next_lock_ns = min(2 * failures.next_lock_ns, policy.last_ns)
        return Refusal("login_failed", "unknown user or wrong password")
