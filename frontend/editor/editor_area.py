"""The code editor in the centre of a logged-in browser: CodeMirror over the area of
viser's canvas (the page script, scripts/codemirror/src/editor.js), fed and heard by this
class.

For the workspace (its Python API):

    area = EditorArea(client, shelf, Editor(user, level), hooks)
    area.open_file(project, path)   # a tab in the editor, in front
    area.refresh(feed, allowed)     # at each UI tick: files changed on disk, live values,
                                    # the debug state (`allowed`: may the user debug)
    area.wanted()                   # the variables the live values need watched
    area.show_coverage(project, files)  # the lines a test run with coverage ran, shaded
    area.remove()                   # the workspace goes

`EditorHooks` are the toolbar's Compile, Download and Online change, supplied by the
workspace (their dialogs are its screens'); each is called with the project of the open
files after they were handed to the language services.

Files are read and saved only through the project's files service
(`backend/engineering/project_files.py`): a save names the hash of the text it started
from, so a file changed since (another browser, another tool) is a conflict offered to
the user, never overwritten. The language services (`backend/engineering/language_service`)
run on a thread of this browser's own, the newest question of each kind winning, so that
viser's event thread never waits for the compiler."""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import viser

from backend.engineering import project_files
from backend.engineering.language_service import LanguageError, ProjectLanguage
from backend.engineering.padt_levels import PADT_LEVELS
from backend.engineering.project_access import WRITE, Editor
from backend.engineering.project_shelf import ProjectShelf
from frontend.editor import answers, page_push
from frontend.editor.debugging import EditorDebugging, Target
from frontend.editor.document import BadChange, Document, utf16_col
from frontend.editor.latest_work import LatestWork
from frontend.editor.live_lines import LiveLines
from frontend.editor.messages import (
    INPUT_LABEL,
    BadMessage,
    Breakpoints,
    Button,
    Change,
    Close,
    DebugAction,
    DiskChoice,
    Message,
    Open,
    Question,
    Rename,
    Save,
    View,
    read_batch,
)
from frontend.permissions import Allowed
from frontend.resource_feed import ResourceFeed
from runtime.contract.refusal import Refusal

log = logging.getLogger("padt.ui")

DISK_POLL_S = 1.0  # how often the open files are compared with the disk
MAX_PROBLEMS = 500  # rows of the problems list (the first by file and place)


@dataclass(frozen=True)
class EditorHooks:
    """The toolbar's actions beyond the editor's own, each called with the project's
    name (from viser's thread: a hook that waits starts its own)."""

    compile: Callable[[str], None]
    download: Callable[[str], None]
    online_change: Callable[[str], None]


class EditorArea:
    def __init__(
        self,
        client: viser.ClientHandle,
        shelf: ProjectShelf,
        editor: Editor,
        hooks: EditorHooks,
    ) -> None:
        self.client, self.shelf, self.editor, self.hooks = client, shelf, editor, hooks
        self._lock = threading.RLock()  # viser's thread, the worker and the refresher
        self.project: str | None = None
        self.language: ProjectLanguage | None = None
        self.documents: dict[str, Document] = {}
        self._seq = 0  # the last message of the page handled
        self._work = LatestWork("padt-editor")
        self._polled = 0.0
        self.live = LiveLines()
        self._events: list[dict[str, object]] = []  # as the page was sent them last
        # the last run with coverage: its project and per file its lines' hits and branches
        self._coverage: tuple[str | None, dict[str, Any]] = (None, {})
        self.box = client.gui.add_text(INPUT_LABEL, "")
        self.box.on_update(lambda _: self._heard(self.box.value))
        self.missing = page_push.install(client)
        self.debugging = EditorDebugging(
            lambda message: page_push.send(client, "debug", message), self._notice
        )
        self._show(True)

    # ---- the workspace's calls
    def open_file(
        self, project: str, path: str, line: int = 0, keyboard: bool = True, col: int = 1
    ) -> None:
        """Open `path` of `project` in a tab in front, at `line` (and `col`) if given (another
        project's files are closed first: the language services see one project);
        `keyboard`: the editor takes the keyboard (not when the workspace reopens files by
        itself: what the user is typing elsewhere, a password, must not land in the code)."""
        with self._lock:
            try:
                if project != self.project:
                    self._switch_project(project)
                self._open(path, focus=True, keyboard=keyboard)
                if line > 0:
                    goto = {"k": "goto", "file": path, "line": line, "col": col}
                    goto["keyboard"] = keyboard
                    page_push.send(self.client, "goto", goto)
            except (Refusal, LanguageError) as exc:
                self._notice(f"{path} cannot be opened: {_reason(exc)}")

    def refresh(self, feed: ResourceFeed | None, debug: Allowed) -> None:
        """At each tick of the UI: the open files compared with the disk now and then; the
        live values of the lines in view; what the Debug panel shows (`debug`: whether the
        user may debug the feed's resource, else why not)."""
        now = time.monotonic()
        if now - self._polled >= DISK_POLL_S:
            self._polled = now
            self._work.submit("disk", self._check_disk)
        with self._lock:
            shown = self.live.refresh(feed, self.project, self.shelf, self.documents)
            target = self._debug_target(feed, debug)
        if shown is not None:
            file, items = shown
            page_push.send(self.client, "live", {"k": "live", "file": file, "items": items})
        self.debugging.follow(target)

    def _debug_target(self, feed: ResourceFeed | None, debug: Allowed) -> Target | None:
        """The feed's resource, and why the open project cannot be debugged there (its
        breakpoints name the files of the configuration the resource runs)."""
        if feed is None:
            return None
        resource = feed.client.resource
        with feed.latest.lock:
            status = feed.latest.status
        runs = ""
        if status is None or not status.crc:
            runs = f"{resource} runs no configuration."
        elif self.project is None:
            runs = "Open a file of the project the resource runs."
        else:
            self.live.lookup.ask(status.crc, self.shelf)
            done, sources = self.live.lookup.answer()
            if not done:
                runs = f"Looking for the project {resource} runs..."
            elif sources is None:
                runs = (
                    f"{resource} runs configuration {status.crc}: no project here compiles to it."
                )
            elif sources.project != self.project:
                runs = f"{resource} runs project {sources.project}, not {self.project}."
        return Target(resource, feed.client, debug, runs, status)

    def show_events(self, rows: list[dict[str, object]]) -> None:
        """The selected resource's newest events in the bottom panel (sent when changed)."""
        if rows != self._events:
            self._events = rows
            page_push.send(self.client, "events", {"k": "events", "items": rows})

    def show_coverage(self, project: str, files: dict[str, Any]) -> None:
        """Shade the lines of the project's files as a test run with coverage ran them
        (`files` as `Coverage.as_json()` has them; empty: no shading), in the files open
        and in those opened later; another project's files are not shaded."""
        with self._lock:
            self._coverage = (project, files)
            self._push_coverage()

    def _push_coverage(self) -> None:
        project, files = self._coverage
        shown = files if project == self.project else {}
        page_push.send(self.client, "coverage", {"k": "coverage", "files": shown})

    def wanted(self) -> list[str]:
        """The variables the live values beside the lines need."""
        with self._lock:
            return self.live.wanted()

    def show(self, on: bool) -> None:
        """The editor in the centre, or not (while another screen owns it)."""
        self._show(on)

    def remove(self) -> None:
        self._work.stop()
        self.debugging.close()
        self._show(False)
        self.box.remove()

    # ---- from the page
    def _heard(self, text: str) -> None:
        try:
            batch = read_batch(text)
        except BadMessage as exc:
            log.warning("an editor message was refused: %s", exc)
            return
        with self._lock:
            newest = self._seq
            for seq, reason in batch.refused:
                if seq > self._seq:
                    self._notice(f"The editor sent a message the server does not read: {reason}")
            for seq, message in batch.messages:
                if seq > self._seq:
                    self._handle(message)
            newest = max([newest, *(seq for seq, _ in batch.messages)])
            newest = max([newest, *(seq for seq, _ in batch.refused)])
            self._seq = newest
        page_push.send(self.client, "ack", {"k": "ack", "seq": newest})

    def _handle(self, message: Message) -> None:
        try:
            if isinstance(message, Change):
                self._change(message)
            elif isinstance(message, Question):
                self._question(message)
            elif isinstance(message, Open):
                if self.project is not None:
                    self._open(message.file, focus=True)
            elif isinstance(message, Close):
                self._close(message.file)
            elif isinstance(message, Save):
                self._save(message)
            elif isinstance(message, Rename):
                self._rename(message)
            elif isinstance(message, DiskChoice):
                self._disk_choice(message)
            elif isinstance(message, View):
                self.live.view(message.file, message.first, message.last)
            elif isinstance(message, Button):
                self._button(message.name)
            elif isinstance(message, Breakpoints):
                self.debugging.set_breakpoints(message.file, message.items)
            elif isinstance(message, DebugAction):
                self.debugging.act(message)
        except (Refusal, LanguageError) as exc:
            self._notice(_reason(exc))

    # ---- documents
    def _switch_project(self, project: str) -> None:
        folder = self.shelf.folder(project)
        for file in list(self.documents):
            self._close(file)
        self.project = project
        self.language = ProjectLanguage(folder)
        self._push_coverage()

    def _open(self, path: str, focus: bool, keyboard: bool = True) -> None:
        assert self.project is not None and self.language is not None
        known = self.documents.get(path)
        if known is not None:  # its tab comes to the front, with the user's edits
            goto = {"k": "goto", "file": path, "line": 0, "col": 0, "keyboard": keyboard}
            page_push.send(self.client, "goto", goto)
            return
        read = project_files.read_file(self.shelf, self.project, path, self.editor)
        document = Document.of(self.project, read.path, read.text, read.hash)
        self.documents[read.path] = document
        self.language.open(read.path, read.text)
        self._push_open(document, focus, keyboard)
        self._diagnose()

    def _push_open(self, document: Document, focus: bool, keyboard: bool = True) -> None:
        readonly, reason = self._read_only()
        page_push.send(
            self.client,
            f"open:{document.file}",
            {
                "k": "open",
                "file": document.file,
                "label": document.file.rsplit("/", 1)[-1],
                "text": document.text(),
                "version": document.version,
                "readonly": readonly,
                "reason": reason,
                "focus": focus,
                "keyboard": keyboard,
            },
        )

    def _read_only(self) -> tuple[bool, str]:
        if PADT_LEVELS.index(self.editor.level) >= PADT_LEVELS.index(WRITE):
            return False, ""
        return True, (
            f"Read-only: {self.editor.user} is {self.editor.level} on this PADT; saving needs "
            f"{WRITE}."
        )

    def _close(self, file: str) -> None:
        if self.documents.pop(file, None) is not None and self.language is not None:
            self.language.close(file)
            self._diagnose()

    def _change(self, message: Change) -> None:
        document = self.documents.get(message.file)
        if document is None or self.language is None:
            return
        try:
            document.apply(message.version, message.changes)
        except BadChange as exc:
            # the browser and the server disagree: the server's text is shown again
            log.warning("editor changes of %s refused: %s", message.file, exc)
            document.version = 0
            self._push_open(document, True)
            self._notice(f"{message.file}: the last edit did not arrive whole ({exc}).")
            return
        self.language.open(document.file, document.text())
        self._diagnose()

    def _diagnose(self) -> None:
        self._work.submit("diagnostics", self._diagnostics_job)

    def _diagnostics_job(self) -> None:
        with self._lock:
            language = self.language
            versions = {file: d.version for file, d in self.documents.items()}
            lines = {file: list(d.lines) for file, d in self.documents.items()}
        if language is None:
            return
        found = language.problems()
        files: dict[str, list[dict[str, Any]]] = {file: [] for file in versions}
        problems: list[dict[str, Any]] = []
        for d in found:
            if d.file.startswith("stdlib/"):
                continue
            col = d.col
            if d.file in lines and 1 <= d.line <= len(lines[d.file]):
                col = utf16_col(lines[d.file][d.line - 1], d.col - 1) + 1
            item = {
                "file": d.file,
                "line": d.line,
                "col": col,
                "severity": d.severity,
                "code": d.code,
                "message": d.message,
            }
            if d.file in files:
                files[d.file].append(item)
            if len(problems) < MAX_PROBLEMS:
                problems.append(item)
        page_push.send(
            self.client,
            "diagnostics",
            {"k": "diagnostics", "files": files, "versions": versions, "problems": problems},
        )

    # ---- the language services
    def _question(self, message: Question) -> None:
        document = self.documents.get(message.file)
        if document is None or self.language is None:
            return
        language = self.language
        line_text = document.line(message.line)

        def job() -> None:
            answer = answers.answer(language, message, line_text, self._live_value)
            answer.update(k="answer", id=message.id)
            page_push.send(self.client, f"answer:{message.kind}", answer)

        self._work.submit(f"question:{message.kind}", job)

    def _live_value(self, name: str) -> str | None:
        with self._lock:
            return self.live.value_of(name)

    def _rename(self, message: Rename) -> None:
        document = self.documents.get(message.file)
        if document is None or self.language is None or self.project is None:
            return
        readonly, reason = self._read_only()
        if readonly:
            self._notice(reason)
            return
        language, project = self.language, self.project
        line_text = document.line(message.line)

        def job() -> None:
            result = answers.rename(language, message, line_text)
            if isinstance(result, str):
                self._notice(result)
                return
            with self._lock:
                try:
                    self._apply_rename(project, result)
                except Refusal as refused:
                    self._notice(f"The rename stopped: {refused.message}")

        self._work.submit("rename", job)

    def _apply_rename(self, project: str, edits: answers.RenameEdits) -> None:
        """The edits of an open file go to its tab (as if typed, so undo takes them back);
        a file not open is changed on disk through the project's files service."""
        done = 0
        for file, changes in edits.per_file:
            document = self.documents.get(file)
            if document is not None:
                page_push.send(
                    self.client, f"edits:{file}", {"k": "edits", "file": file, "changes": changes}
                )
            elif self.language is not None:
                # the edits were made for the text the services read: saved on that base,
                # so a file changed on disk since is a conflict, not a wrong edit
                before = self.language.text(file)
                base = project_files.content_hash(before.encode("utf-8"))
                text = answers.apply_edits(before, changes)
                project_files.save_file(self.shelf, project, file, text, base, self.editor)
            done += len(changes)
        if self.language is not None:
            self.language.reread()
        files = len(edits.per_file)
        self._notice(
            f"Renamed {edits.old} to {edits.new}: {done} edit{'s' * (done != 1)} in "
            f"{files} file{'s' * (files != 1)}."
        )

    # ---- saving, and the disk
    def _save(self, message: Save) -> None:
        document = self.documents.get(message.file)
        if document is None or self.project is None or self.language is None:
            return
        if message.version != document.version:
            return  # the page sends its changes first: a later save follows them
        try:
            saved = project_files.save_file(
                self.shelf,
                self.project,
                document.file,
                document.text(),
                document.base_hash,
                self.editor,
            )
        except Refusal as refused:
            if refused.code == "conflict":
                document.disk_changed = True
                self._push_disk(document)
            self._notice(f"{document.file} was not saved: {refused.message}")
            return
        document.base_hash = saved.hash
        document.saved_version = document.version
        document.disk_changed = False
        self.language.reread()
        page_push.send(
            self.client,
            f"saved:{document.file}",
            {"k": "saved", "file": document.file, "version": document.version},
        )
        self._push_disk(document)
        self._notice(f"Saved {document.file}.")

    def _check_disk(self) -> None:
        with self._lock:
            project = self.project
            known = {file: d.base_hash for file, d in self.documents.items()}
        if project is None:
            return
        for file, base in known.items():
            try:
                state = project_files.changed_on_disk(self.shelf, project, file, base, self.editor)
            except Refusal:
                continue
            with self._lock:
                document = self.documents.get(file)
                if document is None or document.base_hash != base:
                    continue
                if state.changed != document.disk_changed:
                    document.disk_changed = state.changed
                    self._push_disk(document)

    def _push_disk(self, document: Document) -> None:
        page_push.send(
            self.client,
            f"disk:{document.file}",
            {"k": "disk", "file": document.file, "changed": document.disk_changed},
        )

    def _disk_choice(self, message: DiskChoice) -> None:
        document = self.documents.get(message.file)
        if document is None or self.project is None or self.language is None:
            return
        read = project_files.read_file(self.shelf, self.project, document.file, self.editor)
        if message.keep_mine:
            # the user's text stays; their next save replaces what is on disk, knowingly
            document.base_hash = read.hash
        else:
            fresh = Document.of(self.project, read.path, read.text, read.hash)
            self.documents[document.file] = document = fresh
            self.language.open(read.path, read.text)
            self._push_open(document, True)
            self._diagnose()
        document.disk_changed = False
        self.language.reread()
        self._push_disk(document)

    # ---- the toolbar
    def _button(self, name: str) -> None:
        if self.project is None:
            self._notice("Open a file of a project first.")
            return
        hook = {
            "compile": self.hooks.compile,
            "download": self.hooks.download,
            "online_change": self.hooks.online_change,
        }[name]
        hook(self.project)

    def _show(self, on: bool) -> None:
        message = self.missing or "Open a file of a project from the tree."
        page_push.send(self.client, "show", {"k": "show", "on": on, "message": message})
        if self.missing and on:
            page_push.run(self.client, "missing", _missing_script(self.missing))

    def _notice(self, text: str) -> None:
        page_push.send(self.client, "notice", {"k": "notice", "text": text})


def _reason(exc: Exception) -> str:
    return exc.message if isinstance(exc, Refusal) else str(exc)


def _missing_script(message: str) -> str:
    """Without the editor's code, the centre says why (a plain element, no CodeMirror)."""
    return (
        "var d=document.getElementById('padt-editor-missing');if(!d){d=document.createElement"
        "('div');d.id='padt-editor-missing';d.style.cssText='position:fixed;left:50%;top:40%;"
        "transform:translate(-50%,-50%);z-index:90;background:#fff9db;border:1px solid "
        "#ffe066;padding:16px 20px;border-radius:6px;font:14px system-ui,sans-serif;max-width:"
        "520px';document.body.append(d)}"
        f"d.textContent={page_push.script_json(message)};"
    )
