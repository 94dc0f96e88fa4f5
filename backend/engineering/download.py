"""Download (spec section 8): a whole configuration into a resource in STOP, a cold start
follows, and the PADT keeps a backup of exactly what was loaded.

An artifact is larger than one command may be, so it travels as `transfer_begin` (size
and CRC of the whole text), `transfer_chunk`s in order, and then the one command that
takes it (`load`, `reload_preview` or `reload`); each of those consumes the transfer. The
runtime takes nothing until the text is whole and both CRCs agree.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TypeVar

from backend.engineering.backup import BackupError, BackupInfo, write_backup
from backend.engineering.compile_gate import CheckedCompile
from backend.engineering.resource_client import ResourceClient, ResourceUnreachable
from runtime.contract.artifact import Artifact, ResourceConfig, crc32_hex
from runtime.contract.protocol import (
    MAX_CHUNK,
    Command,
    Load,
    ResourceState,
    Status,
    TransferBegin,
    TransferChunk,
    pieces,
)
from runtime.contract.refusal import Refusal

# The runtime answers `load` and `reload` only when the new configuration is in place: it
# first turns the artifact into code and instances (for a reload on a worker thread while
# the cycles go on), which takes far longer than an ordinary command may.
TAKE_TIMEOUT_S = 120.0
R = TypeVar("R")


@dataclass(frozen=True)
class Kept:
    """The backup of a configuration a resource took: its file, or why there is none (the
    resource has the configuration all the same)."""

    path: Path | None
    error: str | None = None


@dataclass(frozen=True)
class DownloadPlan:
    """What a download would do, asked before it is sent: the resource, the configuration
    it runs now and the one compiled twice, and in words what follows or why it cannot."""

    resource: str
    project: str
    running_crc: str | None  # None: the resource has no configuration yet
    new_crc: str
    check_crcs: tuple[str, str]  # of the two check compiles
    effects: tuple[str, ...]  # what the download does, in words
    refusals: tuple[str, ...]  # why it cannot be done now, in words

    @property
    def possible(self) -> bool:
        return not self.refusals


@dataclass(frozen=True)
class Downloaded:
    status: Status
    warnings: tuple[str, ...]  # of the compile
    backup: Kept


def taking(client: ResourceClient, command: Command[R]) -> R:
    """A `load` or `reload`, waiting for its answer as long as the runtime may need."""
    try:
        return client.ask(command, timeout_s=TAKE_TIMEOUT_S)
    except ResourceUnreachable:
        # the request may have arrived and be carried out: say so, never "refused"
        raise ResourceUnreachable(
            f"resource '{client.resource}' did not answer '{command.NAME}' within "
            f"{TAKE_TIMEOUT_S:.0f} s; whether it took the configuration is unknown (see its "
            "status)"
        ) from None


def send_artifact(client: ResourceClient, artifact: Artifact) -> None:
    """Transfer an artifact; the next load / reload_preview / reload takes it."""
    text = artifact.to_json()
    begun = client.ask(TransferBegin(len(text), crc32_hex(text)))
    for offset, data in pieces(text, min(MAX_CHUNK, begun.max_chunk)):
        client.ask(TransferChunk(offset, data))


def download(client: ResourceClient, artifact: Artifact) -> Status:
    """Load `artifact` into a resource in STOP (a cold start follows): its new status.
    Raises the resource's Refusal when it does not take it."""
    if artifact.resource.name != client.resource:
        # the runtime refuses it too; saying so before sending names the project
        raise Refusal(
            "resource",
            f"the project is for resource {artifact.resource.name}, not {client.resource}",
        )
    send_artifact(client, artifact)
    return taking(client, Load()).status


def plan_download(
    checked: CheckedCompile,
    status: Status,
    parameters: ResourceConfig | None,
    level_refusal: str | None = None,
) -> DownloadPlan:
    """The download of `checked` into the resource whose status is `status`, in words: the
    preconditions the resource checks again (STOP, Load Allowed, the project's resource),
    the caller's level on it (`level_refusal`: why the caller may not, if so), and what
    follows: every value from its initial value, the programs stopped until started."""
    refusals = [level_refusal] if level_refusal else []
    wanted = checked.artifact.resource.name
    if wanted != status.resource:
        refusals.append(f"the project is for resource {wanted}, not {status.resource}")
    if status.state == ResourceState.ERROR_STOP:
        refusals.append("the resource is in ERROR STOP: reset it (INIT) first")
    elif status.state not in (ResourceState.STOP_VALID, ResourceState.STOP_INVALID):
        refusals.append(
            f"the resource is in {status.state}: a download replaces the whole "
            "configuration and needs it in STOP (stop it first, or make an online change)"
        )
    if status.crc is not None and parameters is not None and not parameters.load_allowed:
        refusals.append("Load Allowed of the running configuration is OFF")
    effects = (
        f"configuration {status.crc or '(none)'} is replaced by {checked.artifact.crc}",
        "every variable starts from its initial value (cold start); forcing ends",
        "the resource stays in STOP until it is started",
        "the PADT keeps a backup of what was loaded",
    )
    return DownloadPlan(
        status.resource,
        checked.project.name,
        status.crc,
        checked.artifact.crc,
        checked.check_crcs,
        effects,
        tuple(refusals),
    )


def keep_backup(
    checked: CheckedCompile, folder: Path, resource: str, action: str, how: str
) -> Kept:
    """Keep the backup archive of a configuration the resource has just taken; `how`
    records how it was loaded (a command line, or the API request and its user)."""
    info = BackupInfo(
        project=checked.project.name,
        version=checked.project.version,
        resource=resource,
        action=action,
        command=how,
    )
    # the tests too: a project rebuilt from its backup keeps them
    sources = {source.name: source.text for source in checked.project.sources} | checked.tests
    try:
        path = write_backup(folder, info, checked.artifact.to_json(), sources, checked.config_text)
    except BackupError as exc:
        return Kept(None, str(exc))
    return Kept(path)


def download_checked(
    client: ResourceClient, checked: CheckedCompile, backups: Path, how: str
) -> Downloaded:
    """Download a project that passed the compile-twice gate and keep its backup: `padt
    load` and `POST .../load`."""
    status = download(client, checked.artifact)
    backup = keep_backup(checked, backups, client.resource, "load", how)
    return Downloaded(status, checked.diagnostics, backup)
