"""Commissioning: how a runtime without a configuration takes its first one from its owner
and from no one else on the bus (docs/zenoh-security.md#commissioning).

A runtime that powers up without a configuration has no accounts of its own yet. Instead
of running open, it has one account, `setup` (administrator), whose password is a setup
secret: made at the first start, kept owner-only in the state folder and shown once, or
read from a file given on the command line. The first download logs in with it by the
ordinary challenge and response, so the secret never crosses the bus; the configuration
it loads brings the real accounts, the setup account and its session end, and a secret
made here is deleted. Until then only `status` (and the login) is answered anonymously.
"""

from __future__ import annotations

import logging
import secrets
from dataclasses import dataclass
from pathlib import Path

from runtime.contract.accounts import hash_password
from runtime.contract.artifact import UserAccount
from runtime.contract.private_files import write_private
from runtime.contract.refusal import Refusal
from runtime.contract.setup_secret import SETUP_USER, SetupSecretError, read_secret
from runtime.contract.state_folder import setup_secret_path

log = logging.getLogger("padt.runtime")


@dataclass(frozen=True)
class SetupSecret:
    text: str
    path: Path
    made: bool  # made at this start: shown now, once
    ours: bool  # made by the runtime in its state folder: deleted once spent

    def account(self) -> UserAccount:
        return UserAccount(SETUP_USER, "administrator", hash_password(self.text))

    def spend(self) -> None:
        """The first configuration is loaded: a secret made here is of no use any more."""
        if self.ours:
            try:
                self.path.unlink(missing_ok=True)
            except OSError as exc:
                log.warning("setup secret %s could not be deleted: %s", self.path, exc)


def setup_secret(state_dir: Path, given: Path | None) -> SetupSecret:
    """The secret of a runtime without a configuration: from `given`, else from its state
    folder, else a new one written there (owner-only). Raises SetupSecretError."""
    if given is not None:
        return SetupSecret(read_secret(given), given, made=False, ours=False)
    path = setup_secret_path(state_dir)
    if path.exists():
        return SetupSecret(read_secret(path), path, made=False, ours=True)
    text = secrets.token_urlsafe(24)  # 32 characters of the alphabet, 192 bits
    try:
        write_private(path, (text + "\n").encode("ascii"))
    except OSError as exc:
        raise SetupSecretError(f"cannot write the setup secret {path}: {exc}") from None
    return SetupSecret(text, path, made=True, ours=True)


def not_commissioned(refusal: Refusal) -> Refusal:
    """The refusal of a request without the setup session, saying how to commission."""
    if refusal.code != "unauthenticated":
        return refusal
    return Refusal(
        "unauthenticated",
        f"this resource has no configuration yet: the first download logs in as "
        f"'{SETUP_USER}' with the runtime's setup secret (the file setup-secret in its "
        f"state folder; padt load --setup-secret-file FILE)",
    )
