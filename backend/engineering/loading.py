"""Putting a configuration into a running resource: download (in STOP, cold start) and
reload (online change, values carried over), and the compile-twice gate before either.

An artifact is larger than one command may be, so it travels as `transfer_begin` (size
and CRC of the whole text), `transfer_chunk`s in order, and then the one command that
takes it (`load`, `reload_preview` or `reload`); each of those consumes the transfer. The
runtime takes nothing until the text is whole and both CRCs agree.
"""

from __future__ import annotations

import json
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from backend.engineering.backup import BackupInfo, write_backup
from backend.engineering.check_twice import check_twice
from backend.engineering.project import PROJECT_FILE, Project, compile_project, load_project
from backend.engineering.resource_client import ResourceClient, ResourceUnreachable
from runtime.contract.artifact import Artifact, crc32_hex
from runtime.transfer import MAX_CHUNK, pieces

BUSY_PAUSE_S = 0.05  # a program mid-cycle finishes it within a few CPU cycles
# The runtime answers `load` and `reload` only when the new configuration is in place: it
# first turns the artifact into code and instances (for a reload on a worker thread while
# the cycles go on), which takes far longer than an ordinary command may.
TAKE_TIMEOUT_S = 120.0


class LoadRefused(Exception):
    """The configuration was not taken: by the runtime (its error code and message) or by
    the PADT before sending (codes `compile`, `check_twice`, `resource`)."""

    def __init__(self, code: str, message: str) -> None:
        super().__init__(f"refused ({code}): {message}")
        self.code = code
        self.message = message


class CompileFailed(LoadRefused):
    """The project does not compile; `diagnostics` are the rendered findings."""

    def __init__(self, message: str, diagnostics: Sequence[str]) -> None:
        super().__init__("compile", message)
        self.diagnostics = tuple(diagnostics)


def checked_reply(reply: dict[str, Any]) -> dict[str, Any]:
    """The reply when it is a success; LoadRefused with the runtime's code otherwise."""
    if reply.get("ok") is True:
        return reply
    error = reply.get("error")
    if isinstance(error, dict):
        raise LoadRefused(str(error.get("code", "unknown")), str(error.get("message", "")))
    raise LoadRefused("unknown", f"unexpected reply {json.dumps(reply, sort_keys=True)}")


def _taking(client: ResourceClient, cmd: str, **args: Any) -> dict[str, Any]:
    """A `load` or `reload`, waiting for its answer as long as the runtime may need."""
    try:
        return client.command(cmd, timeout_s=TAKE_TIMEOUT_S, **args)
    except ResourceUnreachable:
        # the request may have arrived and be carried out: say so, never "refused"
        raise ResourceUnreachable(
            f"resource '{client.resource}' did not answer '{cmd}' within "
            f"{TAKE_TIMEOUT_S:.0f} s; whether it took the configuration is unknown (see its "
            "status)"
        ) from None


def send_artifact(client: ResourceClient, text: str) -> None:
    """Transfer an artifact text; the next load / reload_preview / reload takes it."""
    begun = checked_reply(client.command("transfer_begin", size=len(text), crc=crc32_hex(text)))
    # a chunk escaped into its request may double (quotes, backslashes): MAX_CHUNK keeps
    # even that within the request limit
    for offset, data in pieces(text, min(MAX_CHUNK, int(begun.get("max_chunk", MAX_CHUNK)))):
        checked_reply(client.command("transfer_chunk", offset=offset, data=data))


def _same_resource(client: ResourceClient, artifact: Artifact) -> None:
    # the runtime refuses it too; saying so before sending names the project
    if artifact.resource.name != client.resource:
        raise LoadRefused(
            "resource",
            f"the project is for resource {artifact.resource.name}, not {client.resource}",
        )


def download(client: ResourceClient, artifact: Artifact) -> dict[str, Any]:
    """Load `artifact` into a resource in STOP (cold start follows); the reply has the new
    `status`. Raises LoadRefused when the resource does not take it."""
    _same_resource(client, artifact)
    send_artifact(client, artifact.to_json())
    return checked_reply(_taking(client, "load"))


def preview_reload(
    client: ResourceClient, artifact: Artifact, renames: Mapping[str, str]
) -> dict[str, Any]:
    """The reload plan against the running state (`renames`: NEW name -> OLD name)."""
    send_artifact(client, artifact.to_json())
    plan: dict[str, Any] = checked_reply(_taking(client, "reload_preview", renames=dict(renames)))[
        "plan"
    ]
    return plan


def reload(
    client: ResourceClient,
    artifact: Artifact,
    renames: Mapping[str, str],
    watchdog_ms: int | None = None,
    target_cycle_ms: int | None = None,
    retries_when_busy: int = 20,
    expected_crc: str | None = None,
) -> dict[str, Any]:
    """Replace the running configuration by `artifact`, values carried over; the reply has
    `reload` (old_crc, new_crc, pause_us, carried) and `status`. A program in the middle
    of its program cycle makes the runtime refuse (`busy`): it is tried again, with the
    artifact sent again each time, because every attempt consumes the transfer.

    `expected_crc`: the configuration the user saw the plan for (its `old_crc`). When the
    resource runs another one (someone else loaded meanwhile), the plan no longer says
    what would happen: the runtime refuses with code `changed` at the switch-over."""
    text = artifact.to_json()
    arguments: dict[str, Any] = {"renames": dict(renames)}
    if watchdog_ms is not None:
        arguments["watchdog_ms"] = watchdog_ms
    if target_cycle_ms is not None:
        arguments["target_cycle_ms"] = target_cycle_ms
    if expected_crc is not None:
        arguments["expected_crc"] = expected_crc
    attempt = 0
    while True:
        send_artifact(client, text)
        try:
            return checked_reply(_taking(client, "reload", **arguments))
        except LoadRefused as refused:
            if refused.code != "busy" or attempt >= retries_when_busy:
                raise
        attempt += 1
        time.sleep(BUSY_PAUSE_S)


@dataclass(frozen=True)
class CheckedCompile:
    """A project compiled in this process, with the same CRCs as two separate compiles."""

    project: Project
    artifact: Artifact
    diagnostics: tuple[str, ...]  # warnings of the in-process compile
    config_text: str | None  # the project's padt.toml as read for this compile, if any


def compile_checked(paths: Sequence[Path]) -> CheckedCompile:
    """Compile-twice gate, then the in-process compile whose artifact is sent.

    The two processes prove that the compile is deterministic; the in-process compile
    must then give the very configuration CRC they agreed on, or what is sent would not
    be what was checked (a source edited in between, or an order that differs here).
    Raises ProjectError when the project cannot be read, LoadRefused otherwise."""
    project = load_project(list(paths))  # an unreadable project fails fast, before two
    # kept for the backup: the project model holds the sources but not padt.toml's text
    folder = Path(paths[0]) if len(paths) == 1 and Path(paths[0]).is_dir() else None
    config = folder / PROJECT_FILE if folder is not None else None
    config_text = config.read_text(encoding="utf-8") if config and config.is_file() else None
    check = check_twice(paths)
    if not check.compiled:
        failures = [run.failure for run in (check.first, check.second) if run.failure]
        first = check.first if check.first.failure is None else check.second
        if failures and not first.diagnostics:
            raise CompileFailed(f"the check compile failed: {failures[0]}", ())
        raise CompileFailed("the project does not compile", first.diagnostics)
    if check.mismatches:
        raise LoadRefused("check_twice", "the two compiles differ: " + "; ".join(check.mismatches))
    result = compile_project(project)
    diagnostics = tuple(str(d) for d in result.diagnostics)
    if result.artifact is None:
        raise CompileFailed("the project does not compile", diagnostics)
    agreed = check.first.configuration
    if result.artifact.crc != agreed:
        raise LoadRefused(
            "check_twice",
            f"this compile gives configuration CRC {result.artifact.crc}, the two check "
            f"compiles gave {agreed} (was a source changed meanwhile?)",
        )
    return CheckedCompile(project, result.artifact, diagnostics, config_text)


def compiled_twice(paths: Sequence[Path]) -> Artifact:
    """The artifact of `paths`, only when two compiles and this one agree on every CRC."""
    return compile_checked(paths).artifact


def backup_of(
    checked: CheckedCompile, folder: Path, resource: str, action: str, command: str
) -> Path:
    """Keep the backup archive of a configuration the resource has just taken; `command`
    records how (a command line, or the API request and its user)."""
    info = BackupInfo(
        project=checked.project.name,
        version=checked.project.version,
        resource=resource,
        action=action,
        command=command,
    )
    sources = {source.name: source.text for source in checked.project.sources}
    return write_backup(folder, info, checked.artifact.to_json(), sources, checked.config_text)


def needs_confirmation(plan: dict[str, Any]) -> list[str]:
    """What a reload would lose or risk; empty when every value is kept, converted or new."""
    summary = plan.get("summary", {})
    found = [
        counted(summary[action], "value") + f" {action}"
        for action in ("initialised", "deleted")
        if summary.get(action)
    ]
    if plan.get("hazards"):
        found.append(counted(len(plan["hazards"]), "hazard"))
    return found


def counted(number: int, noun: str) -> str:
    return f"{number} {noun}" if number == 1 else f"{number} {noun}s"
