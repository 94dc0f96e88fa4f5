"""The Documentation screen: download the printable documentation (PDF or HTML) of a
project the PADT knows, or of the configuration the selected resource runs (from its
backup, or the known project that compiles to its CRC), optionally compared with another
version: a project or a backup. The document is made on a thread of its own; the browser
gets it as a download."""

from __future__ import annotations

import html
import logging
import threading
import time
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import viser

from backend.engineering.documentation.export import (
    DocumentError,
    backups_of,
    document,
    running_version,
    version_path,
)
from backend.engineering.padt_levels import PADT_LEVELS
from frontend.gui_value import set_value
from frontend.screen_registry import Now, Screen, Work
from runtime.contract import protocol as p

RUNNING = "the configuration the resource runs"
NOTHING = "(nothing)"
FORMATS = ("PDF", "HTML")
LIST_EVERY_NS = 3_000_000_000  # the backup folder, read again at most this often
log = logging.getLogger("padt.ui")


@dataclass
class DocumentationScreen:
    client: viser.ClientHandle
    projects: Mapping[str, Path]
    backup_dir: Path
    subject: viser.GuiDropdownHandle[str]
    compare: viser.GuiDropdownHandle[str]
    format: viser.GuiDropdownHandle[str]
    make: viser.GuiButtonHandle
    note: viser.GuiHtmlHandle
    allowed: bool
    running: tuple[str, str] | None = None  # (resource, CRC) of the selected resource
    busy: bool = False
    backups: tuple[str, ...] = ()
    backups_listed_ns: int | None = None  # when the backup folder was last listed


def build(
    gui: viser.GuiApi,
    client: viser.ClientHandle,
    projects: Mapping[str, Path],
    backup_dir: Path,
    level: str,
) -> DocumentationScreen:
    gui.add_html(
        '<div style="color:#495057;font-size:0.9em">Printable documentation for acceptance: '
        "cover with the CRCs, parameters, users, I/O, signal list, interfaces, the logic, "
        "SFC charts, the cross-reference; with a previous version, what changed. Every page "
        "carries the project, the configuration CRC and its page number.</div>"
    )
    subject = gui.add_dropdown("Document of", _subjects(projects, None))
    compare = gui.add_dropdown("Compare with", (NOTHING,))
    format_ = gui.add_dropdown("Format", FORMATS)
    allowed = PADT_LEVELS.index(level) >= PADT_LEVELS.index("read-write")
    make = gui.add_button("Download document", color="blue", disabled=not allowed)
    note = gui.add_html(
        ""
        if allowed
        else '<div data-testid="docs-note" style="color:#868e96">Making documents needs '
        "Read+Write on the PADT.</div>"
    )
    screen = DocumentationScreen(
        client, projects, backup_dir, subject, compare, format_, make, note, allowed
    )
    make.on_click(lambda _: _start(screen))
    return screen


def _subjects(projects: Mapping[str, Path], running: tuple[str, str] | None) -> tuple[str, ...]:
    found = [f"project {name}" for name in sorted(projects)]
    if running is not None:
        found.insert(0, f"{RUNNING} ({running[0]}, CRC {running[1]})")
    return tuple(found) or ("(no project)",)


def refresh(screen: DocumentationScreen, resource: str | None, status: p.Status | None) -> None:
    """Keep the choices current: the selected resource's configuration, the backups."""
    running = (resource, status.crc) if resource and status is not None and status.crc else None
    subjects = _subjects(screen.projects, running)
    if tuple(screen.subject.options) != subjects:
        chosen = screen.subject.value
        screen.subject.options = subjects
        if chosen in subjects:
            set_value(screen.subject, chosen)
    screen.running = running
    now = time.monotonic_ns()
    if screen.backups_listed_ns is None or now - screen.backups_listed_ns > LIST_EVERY_NS:
        screen.backups = tuple(backups_of(screen.backup_dir))  # not ten times a second
        screen.backups_listed_ns = now
    versions = (NOTHING, *(f"project {n}" for n in sorted(screen.projects)))
    versions += tuple(f"backup {name}" for name in screen.backups)
    if tuple(screen.compare.options) != versions:
        chosen = screen.compare.value
        screen.compare.options = versions
        if chosen in versions:
            set_value(screen.compare, chosen)


def _start(screen: DocumentationScreen) -> None:
    if screen.busy or not screen.allowed:
        return
    screen.busy = True
    screen.make.disabled = True
    screen.note.content = '<div data-testid="docs-note">making the document ...</div>'
    chosen = (screen.subject.value, screen.compare.value, screen.format.value, screen.running)
    threading.Thread(target=_make, args=(screen, *chosen), daemon=True).start()


def _make(
    screen: DocumentationScreen,
    subject: str,
    compare: str,
    format_: str,
    running: tuple[str, str] | None,
) -> None:
    try:
        path = _path_of(screen, subject, running)
        previous = None
        if compare != NOTHING:
            previous = version_path(compare.split(" ", 1)[1], screen.projects, screen.backup_dir)
        made = document([path], previous)
        extension = format_.lower()
        data = made.pdf if extension == "pdf" else made.html.encode("utf-8")
        filename = f"{made.name}.{extension}"
        screen.client.send_file_download(filename, data, save_immediately=True)
        _say(screen, f"{filename}: configuration CRC {made.crc}, {len(data) // 1024} KiB", "")
    except DocumentError as exc:
        _say(screen, str(exc), "#c92a2a")
    except Exception:  # the screen stays usable whatever went wrong
        log.exception("making a document failed")
        _say(screen, "the document could not be made (see the PADT's log)", "#c92a2a")
    finally:
        screen.busy = False
        screen.make.disabled = False


def _path_of(screen: DocumentationScreen, subject: str, running: tuple[str, str] | None) -> Path:
    if subject.startswith(RUNNING):
        if running is None:
            raise DocumentError("no resource is selected")
        found = running_version(running[1], screen.projects, screen.backup_dir)
        if found is None:
            raise DocumentError(
                f"configuration {running[1]} of {running[0]}: no backup of it and no known "
                "project that compiles to it"
            )
        return found
    name = subject.removeprefix("project ")
    if name not in screen.projects:
        raise DocumentError("no project chosen")
    return screen.projects[name]


def _say(screen: DocumentationScreen, text: str, color: str) -> None:
    style = f' style="color:{color}"' if color else ""
    screen.note.content = f'<div data-testid="docs-note"{style}>{html.escape(text)}</div>'


class Documentation(Screen):
    name = "Documentation"
    icon = viser.Icon.FILE_TEXT

    def __init__(self, work: Work) -> None:
        super().__init__(work)
        context = work.context
        self.screen = build(work.gui, work.client, context.projects, context.backup_dir, work.level)

    def refresh(self, now: Now) -> None:
        refresh(self.screen, now.resource, now.status)
