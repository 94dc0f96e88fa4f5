"""Which controls a user may use, so that the UI can disable the others and say why. The
resource checks every command itself all the same: this only saves the user a refusal."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from backend.engineering.resource_client import ResourceLogin
from runtime.contract.accounts import LEVELS
from runtime.contract.protocol import Command

PADT_ACTORS = ("read-write", "security-administrator")  # PADT levels that may act


@dataclass(frozen=True)
class Allowed:
    ok: bool
    reason: str = ""  # why not: shown on the disabled control


def allowed(
    padt_level: str,
    login: ResourceLogin | None,
    command: type[Command[Any]] | Command[Any],
    open_access: bool,
) -> Allowed:
    """For a command class, the level the command needs; for a request (an instance), the
    level its arguments need (`set_parameter allow_online_settings`: administrator)."""
    needed = command.level() if isinstance(command, Command) else command.LEVEL
    if needed is None or needed == "read":
        return Allowed(True)
    if padt_level not in PADT_ACTORS:
        return Allowed(False, f"your PADT account is {padt_level}: it may only look")
    if open_access:
        return Allowed(True)
    if login is None:
        return Allowed(False, "log in to the resource first")
    if LEVELS.index(login.level) < LEVELS.index(needed):
        return Allowed(False, f"needs {needed} at the resource; {login.user} is {login.level}")
    return Allowed(True)
