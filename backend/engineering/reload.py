"""Reload (online change, spec section 9) from the engineering side: the preview of what it
would do to every value, the confirmation it needs, the reload itself (tried again while a
program is in the middle of its cycle), and the backup of what was loaded."""

from __future__ import annotations

import time
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path

from backend.engineering.compile_gate import CheckedCompile
from backend.engineering.download import Kept, keep_backup, send_artifact, taking
from backend.engineering.resource_client import ResourceClient
from runtime.contract.artifact import Artifact
from runtime.contract.protocol import Reload, ReloadPlanInfo, ReloadPreview, ReloadReply
from runtime.contract.refusal import Refusal

BUSY_PAUSE_S = 0.05  # a program mid-cycle finishes it within a few CPU cycles


@dataclass(frozen=True)
class ReloadOptions:
    renames: dict[str, str]  # NEW name -> OLD name, as the runtime's rename map has it
    expected_crc: str | None = None  # the `old_crc` of the preview the user confirmed
    watchdog_ms: int | None = None
    target_cycle_ms: int | None = None


@dataclass(frozen=True)
class Reloaded:
    reply: ReloadReply
    backup: Kept


def rename_map(pairs: Iterable[tuple[str, str]]) -> dict[str, str]:
    """(NEW, OLD) pairs -> the rename map NEW -> OLD the runtime takes; a new name given
    twice (in any case: ST names are case-insensitive) is refused."""
    renames: dict[str, str] = {}
    for new, old in pairs:
        if new.upper() in (known.upper() for known in renames):
            raise Refusal("bad_request", f"the rename map gives {new} twice")
        renames[new] = old
    return renames


def preview_reload(
    client: ResourceClient, artifact: Artifact, renames: Mapping[str, str]
) -> ReloadPlanInfo:
    """The reload plan against the running state (`renames`: NEW name -> OLD name)."""
    send_artifact(client, artifact)
    return taking(client, ReloadPreview(dict(renames))).plan


def needs_confirmation(plan: ReloadPlanInfo) -> list[str]:
    """What a reload would lose or risk; empty when every value is kept, converted or new."""
    found = [
        counted(plan.summary[action], "value") + f" {action}"
        for action in ("initialised", "deleted")
        if plan.summary.get(action)
    ]
    if plan.hazards:
        found.append(counted(len(plan.hazards), "hazard"))
    return found


def counted(number: int, noun: str) -> str:
    return f"{number} {noun}" if number == 1 else f"{number} {noun}s"


def reload(
    client: ResourceClient,
    artifact: Artifact,
    options: ReloadOptions,
    retries_when_busy: int = 20,
) -> ReloadReply:
    """Replace the running configuration by `artifact`, values carried over. A program in
    the middle of its program cycle makes the runtime refuse (`busy`): it is tried again,
    with the artifact sent again each time, because every attempt consumes the transfer.

    With `expected_crc` (the configuration the user saw the plan for) the runtime refuses
    with `changed` when it runs another one by now: the plan no longer says what would
    happen."""
    command = Reload(
        dict(options.renames), options.watchdog_ms, options.target_cycle_ms, options.expected_crc
    )
    attempt = 0
    while True:
        send_artifact(client, artifact)
        try:
            return taking(client, command)
        except Refusal as refused:
            if refused.code != "busy" or attempt >= retries_when_busy:
                raise
        attempt += 1
        time.sleep(BUSY_PAUSE_S)


def reload_checked(
    client: ResourceClient,
    checked: CheckedCompile,
    options: ReloadOptions,
    backups: Path,
    how: str,
) -> Reloaded:
    """Reload a project that passed the compile-twice gate and keep its backup: `padt
    reload --yes` and `POST .../reload`."""
    reply = reload(client, checked.artifact, options)
    return Reloaded(reply, keep_backup(checked, backups, client.resource, "reload", how))
