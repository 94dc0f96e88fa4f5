"""The setup secret of a runtime without a configuration, as both ends know it: the account
the first download logs in as, and how a secret is read from its file (the runtime's side
is runtime/commissioning.py)."""

from __future__ import annotations

import re
from pathlib import Path

SETUP_USER = "setup"
# a password of the accounts' alphabet, long enough not to be guessed (it is the only
# account there is): 16 to 32 of A-Z a-z 0-9 _ -
_SECRET = re.compile(r"^[A-Za-z0-9_-]{16,32}$")


class SetupSecretError(Exception):
    """A setup secret file that cannot be read or holds no valid secret."""


def valid_secret(text: str) -> bool:
    return _SECRET.match(text) is not None


def read_secret(path: Path) -> str:
    """The secret a file holds (surrounding white space left out); SetupSecretError."""
    try:
        text = path.read_text(encoding="utf-8", errors="strict").strip()
    except (OSError, UnicodeError) as exc:
        raise SetupSecretError(f"cannot read the setup secret file {path}: {exc}") from None
    if not valid_secret(text):
        raise SetupSecretError(f"the setup secret in {path} must be 16 to 32 of A-Z a-z 0-9 _ -")
    return text
