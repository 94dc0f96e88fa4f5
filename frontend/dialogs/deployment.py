"""What the Compile, Download and Online change dialogs need of a browser session, and
Compile itself: the compile-twice gate on a thread of its own, told in a notification."""

from __future__ import annotations

import html
import threading
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import viser

from backend.engineering.compile_gate import CheckedCompile, compile_checked
from backend.engineering.project import ProjectError
from backend.engineering.resource_client import ResourceClient, ResourceUnreachable
from frontend.permissions import Allowed
from frontend.screen_registry import Work
from runtime.contract import protocol as p
from runtime.contract.refusal import Refusal

MUTED = "color:#868e96"
RED = "#c92a2a"
GREEN = "#2b8a3e"
# A dialog wide enough for a source diff and the table of every value (viser's modal is
# narrow), above the code editor's layer (viser puts modals at z-index 100 + n) and within
# the window: its first part (the plan, the diff, the table) gives way and scrolls inside
# itself, so that the choices and the buttons under it are always in view. Only while the
# dialog is open, as the style is part of its content (the body is the modal's first
# element, its container a column of viser's, three levels below the modal's body).
_COLUMN = "display:flex!important;flex-direction:column;min-height:0"
WIDE_MODAL = (
    "<style>.mantine-Modal-content{flex:0 0 min(1080px,94vw)!important;"
    f"max-width:94vw!important;{_COLUMN}}}"
    f".mantine-Modal-body,.mantine-Modal-body>div,.mantine-Modal-body>div>div{{{_COLUMN};"
    "flex:1 1 auto}"
    ".mantine-Modal-body>div>div>*{flex:0 0 auto}"
    ".mantine-Modal-body>div>div>:first-child{flex:0 1 auto;min-height:4em;overflow-y:auto}"
    ".mantine-Modal-overlay,.mantine-Modal-inner{z-index:300!important}</style>"
)


@dataclass(frozen=True)
class Deployment:
    """What the dialogs need of the browser session they are opened in."""

    client: viser.ClientHandle  # for the modals and the notifications
    projects: Mapping[str, Path]
    backup_dir: Path
    user: str
    selected: Callable[[], str | None]  # the resource chosen in the workspace
    client_of: Callable[[str], ResourceClient]
    allowed: Callable[[type[p.Command[Any]]], Allowed]


def deployment_of(work: Work) -> Deployment:
    """What the dialogs need, from what the workspace offers every screen."""
    context = work.context
    return Deployment(
        work.client,
        context.projects,
        context.backup_dir,
        work.user,
        work.selected,
        work.client_of,
        work.allowed,
    )


@dataclass(frozen=True)
class Failure:
    """Why a compile or a command did not come: the refusal and the compiler's findings."""

    code: str
    message: str
    diagnostics: tuple[str, ...] = ()


def failure_of(error: Exception) -> Failure:
    if isinstance(error, Refusal):
        return Failure(
            error.code, error.message, tuple(map(str, error.details.get("diagnostics", [])))
        )
    if isinstance(error, ProjectError):
        return Failure("project", str(error))
    if isinstance(error, ResourceUnreachable):
        return Failure("unreachable", str(error))
    raise error


KNOWN_FAILURES = (Refusal, ProjectError, ResourceUnreachable)


def in_background(name: str, work: Callable[[], None]) -> None:
    """Compiles and transfers take seconds: never on viser's callback thread."""
    threading.Thread(target=work, name=name, daemon=True).start()


def start_compile(
    deployment: Deployment,
    project: str,
    done: Callable[[CheckedCompile | Failure], None] | None = None,
) -> None:
    """Compile `project` twice in two processes (the gate of every download and online
    change); the CRCs, or why not, in a notification, and to `done` if given."""
    folder = deployment.projects.get(project)
    client = deployment.client
    if folder is None:
        client.add_notification("Compile", f"no project {project}", color="red")
        return
    note = client.add_notification(
        f"Compile {project}", "compiling twice, in two processes ...", loading=True,
        with_close_button=False, auto_close_seconds=None,
    )  # fmt: skip

    def run() -> None:
        outcome: CheckedCompile | Failure
        try:
            outcome = compile_checked([folder])
        except KNOWN_FAILURES as error:
            outcome = failure_of(error)
        note.loading = False
        note.with_close_button = True
        if isinstance(outcome, Failure):
            first = outcome.diagnostics[0] if outcome.diagnostics else ""
            note.title = f"Compile {project}: refused ({outcome.code})"
            note.body = f"{outcome.message}. {first}".strip()
            note.color = "red"
        else:
            first_crc, second_crc = outcome.check_crcs
            warnings = len(outcome.diagnostics)
            note.title = f"Compile {project}: configuration CRC {outcome.artifact.crc}"
            note.body = (
                f"Compiled twice: {first_crc} and {second_crc}, equal. "
                f"{warnings} warning{'s' if warnings != 1 else ''}."
            )
            note.color = "green"
            note.auto_close_seconds = 8
        if done is not None:
            done(outcome)

    in_background("padt-compile", run)


def failure_html(failure: Failure, what: str) -> str:
    """A refusal and each compile diagnostic, one a line."""
    rows = "".join(
        f'<div data-testid="diagnostic" style="font-family:monospace;font-size:0.85em">'
        f"{html.escape(line)}</div>"
        for line in failure.diagnostics
    )
    return (
        f'<div data-testid="dialog-refused" style="color:{RED};margin:4px 0">'
        f"{html.escape(what)} refused ({html.escape(failure.code)}): "
        f"{html.escape(failure.message)}</div>{rows}"
    )


def note_html(testid: str, text: str) -> str:
    return f'<div data-testid="{testid}" style="{MUTED}">{html.escape(text)}</div>'
