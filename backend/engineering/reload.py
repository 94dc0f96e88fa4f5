"""Reload (online change, spec section 9) from the engineering side: the preview of what it
would do to every value, the confirmation it needs, the reload itself (tried again while a
program is in the middle of its cycle), and the backup of what was loaded."""

from __future__ import annotations

import re
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

_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*(?:\.[A-Za-z_][A-Za-z0-9_]*)*")
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


def rename_pair(text: str) -> tuple[str, str]:
    """`OLD=NEW`, as the user writes a rename everywhere (`padt reload --rename`, the
    browser's rename map) -> (NEW, OLD) as the runtime's rename map has it."""
    old, sep, new = text.partition("=")
    old, new = old.strip(), new.strip()
    if not sep or "=" in new or not _NAME.fullmatch(old) or not _NAME.fullmatch(new):
        raise Refusal("bad_request", f"'{text.strip()[:80]}' is not OLD=NEW")
    if old.upper() == new.upper():
        raise Refusal("bad_request", f"{old} is renamed to itself")
    return new, old


def parse_renames(text: str) -> tuple[dict[str, str], list[str]]:
    """One `OLD=NEW` a line (blank lines and `#` comments skipped) -> the rename map NEW ->
    OLD, and what is wrong with each line that is not such a pair."""
    pairs: list[tuple[str, str]] = []
    errors: list[str] = []
    for number, line in enumerate(text.splitlines(), start=1):
        if not line.strip() or line.strip().startswith("#"):
            continue
        try:
            pairs.append(rename_pair(line))
        except Refusal as refused:
            errors.append(f"line {number}: {refused.message}")
    try:
        renames = rename_map(pairs)
    except Refusal as refused:
        errors.append(refused.message)
        renames = {}
    return renames, errors


def preview_reload(
    client: ResourceClient, artifact: Artifact, renames: Mapping[str, str]
) -> ReloadPlanInfo:
    """The reload plan against the running state (`renames`: NEW name -> OLD name)."""
    send_artifact(client, artifact)
    return taking(client, ReloadPreview(dict(renames))).plan


@dataclass(frozen=True)
class Risk:
    """Something a reload would lose or risk, which the user accepts before it."""

    label: str  # of its checkbox
    title: str
    detail: str


def risks(plan: ReloadPlanInfo) -> list[Risk]:
    """What a reload would lose or risk, one by one: values that start from their initial
    value, values that are lost, and each hazard the plan names; empty when every value
    is kept, converted or new."""
    found: list[Risk] = []
    for action, what in (
        ("initialised", "start from their initial value"),
        ("deleted", "are lost"),
    ):
        names = [change.path for change in plan.changes if change.action == action]
        if names:
            title = counted(len(names), "value") + f" {action}"
            found.append(Risk(f"Accept: {title}", title, f"These {what}: {', '.join(names)}"))
    for number, hazard in enumerate(plan.hazards, start=1):
        found.append(
            Risk(
                f"Accept hazard {number}: {hazard.kind}",
                f"Hazard {number}: {hazard.kind} in {hazard.instance}",
                hazard.message,
            )
        )
    return found


def needs_confirmation(plan: ReloadPlanInfo) -> list[str]:
    """The risks of `risks` counted: what `padt reload` and the REST API say needs --yes."""
    found = [risk.title for risk in risks(plan) if not risk.title.startswith("Hazard ")]
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
