"""The PADT's own accounts (spec section 13), separate from the PES accounts that each
resource enforces: Read-only views, Read+Write builds and acts on resources, Security
Administrator also manages these accounts.

They live in one JSON file (hashes only, mode 0600), made and changed with `padt
api-user` or by a Security Administrator through the API. There is no default account:
`padt api` refuses to start without one.
"""

from __future__ import annotations

import json
import threading
from collections.abc import Callable
from dataclasses import asdict
from pathlib import Path

from backend.engineering.padt_levels import ADMINISTRATOR, PADT_LEVELS
from backend.engineering.resource_client import ResourceLogin
from runtime.contract.accounts import AccessControl, Session, account_problems, hash_password
from runtime.contract.artifact import UserAccount
from runtime.contract.outside_json import MIB, read_json_file
from runtime.contract.private_files import write_private
from runtime.contract.refusal import Refusal

FORMAT = "padt-accounts"
VERSION = 1
MAX_FILE_BYTES = MIB  # thousands of accounts


class AccountsError(ValueError):
    """The accounts file cannot be read, or a change would break a rule."""


def read_accounts(path: Path) -> tuple[UserAccount, ...]:
    """The accounts of the file; none when it does not exist."""
    if not path.exists():
        return ()
    try:
        data = read_json_file(path, MAX_FILE_BYTES)
        if data.get("format") != FORMAT or data.get("version") != VERSION:
            raise AccountsError(f"{path}: not a {FORMAT} file of version {VERSION}")
        accounts = tuple(UserAccount(**entry) for entry in data["accounts"])
    except (OSError, ValueError, TypeError, KeyError, AttributeError) as exc:
        raise AccountsError(f"{path}: cannot read the accounts: {exc}") from None
    for account in accounts:
        problems = account_problems(account.name, account.level, account.password_hash, PADT_LEVELS)
        if problems:
            raise AccountsError(f"{path}: {problems[0]}")
    return accounts


def write_accounts(path: Path, accounts: tuple[UserAccount, ...]) -> None:
    """Write atomically (a crash leaves the old file or the new one), readable by the
    owner only."""
    entries = [asdict(a) for a in sorted(accounts, key=lambda a: a.name)]
    text = json.dumps({"format": FORMAT, "version": VERSION, "accounts": entries}, indent=2)
    write_private(path, (text + "\n").encode("utf-8"))


def with_account(
    accounts: tuple[UserAccount, ...], name: str, level: str, password: str | None
) -> tuple[UserAccount, ...]:
    """The accounts with `name` added or changed (its password kept when None)."""
    existing = next((a for a in accounts if a.name == name), None)
    if password is not None:
        try:
            hashed = hash_password(password)
        except ValueError as exc:
            raise AccountsError(str(exc)) from None
    elif existing is not None:
        hashed = existing.password_hash
    else:
        raise AccountsError(f"a new account ('{name}') needs a password")
    problems = account_problems(name, level, hashed, PADT_LEVELS)
    if problems:
        raise AccountsError(problems[0])
    changed = (*[a for a in accounts if a.name != name], UserAccount(name, level, hashed))
    _keep_an_administrator(changed)
    return tuple(sorted(changed, key=lambda a: a.name))


def without_account(accounts: tuple[UserAccount, ...], name: str) -> tuple[UserAccount, ...]:
    if not any(a.name == name for a in accounts):
        raise AccountsError(f"there is no account '{name}'")
    kept = tuple(a for a in accounts if a.name != name)
    _keep_an_administrator(kept)
    return kept


def _keep_an_administrator(accounts: tuple[UserAccount, ...]) -> None:
    # without one, nobody could manage the accounts again except on the machine itself
    if not any(a.level == ADMINISTRATOR for a in accounts):
        raise AccountsError(f"at least one account must stay {ADMINISTRATOR}")


class PadtAccounts:
    """The accounts of the file and the API's sessions, shared by the request threads.

    Each API session also holds the resource logins its user made: a resource checks its
    own accounts, the PADT only carries the session (and signs its requests)."""

    def __init__(self, path: Path, now_ns: Callable[[], int]) -> None:
        self.path = path
        self._lock = threading.Lock()
        self._access = AccessControl(read_accounts(path), now_ns, PADT_LEVELS)
        # the resource logins of each API session: (API token, resource) -> login
        self._resource_logins: dict[tuple[str, str], ResourceLogin] = {}

    @property
    def empty(self) -> bool:
        return self._access.open

    def login(self, name: str, password: str, source: str) -> tuple[str, Session]:
        """`source`: the caller's address; repeated failures lock the name for it only."""
        with self._lock:
            return self._access.login(name, password, source)

    def logout(self, token: str) -> None:
        with self._lock:
            self._access.logout(token)
            self._forget_resources(token)

    def check(self, token: str | None, needed: str) -> Session:
        """The caller's session; Refusal when it is missing, expired or too low."""
        with self._lock:
            try:
                session = self._access.check(token, needed)
            except Refusal:
                if token is not None and token not in self._access.sessions:
                    self._forget_resources(token)
                raise
        if session is None:  # no accounts at all: `padt api` does not start like that
            raise Refusal("unauthenticated", "the PADT has no accounts")
        return session

    def time_left_ns(self, token: str) -> int:
        """How long the session `token` has before it expires (0 when it has)."""
        with self._lock:
            session = self._access.sessions.get(token)
            return max(0, session.expires_ns - self._access.now_ns()) if session else 0

    def accounts(self) -> tuple[UserAccount, ...]:
        with self._lock:
            return self._access.users

    def put(self, name: str, level: str, password: str | None) -> None:
        with self._lock:
            changed = with_account(self._access.users, name, level, password)
            write_accounts(self.path, changed)
            self._access.replace_users(changed)

    def delete(self, name: str) -> None:
        with self._lock:
            kept = without_account(self._access.users, name)
            write_accounts(self.path, kept)
            self._access.replace_users(kept)

    def resource_login(self, token: str, resource: str) -> ResourceLogin | None:
        with self._lock:
            return self._resource_logins.get((token, resource))

    def set_resource_login(self, token: str, resource: str, login: ResourceLogin | None) -> None:
        with self._lock:
            if login is None:
                self._resource_logins.pop((token, resource), None)
            else:
                self._resource_logins[(token, resource)] = login

    def _forget_resources(self, token: str) -> None:
        for key in [k for k in self._resource_logins if k[0] == token]:
            del self._resource_logins[key]
