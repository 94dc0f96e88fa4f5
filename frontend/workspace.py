"""The workspace of a logged-in browser, laid out as an IDE: on the left the navigation
(who is logged in, the project and its tree, the resource to work on, the login to it, the
status bar); on the right the work panel with a tab per screen, collapsible and resizable;
in between, the viewport draws the selected resource and its programs in the colours of
their states. The screens are the ones `frontend/screens/__init__.py` lists; the workspace
is what `frontend/screen_registry.py` calls `Work`: the actions every screen asks of it."""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Sequence
from dataclasses import replace
from typing import Any, Protocol, TypeVar

import viser

from backend.engineering.project_access import Editor
from backend.engineering.project_tree import ProjectTree
from backend.engineering.resource_client import ResourceClient, ResourceLogin
from backend.engineering.user_layouts import MAX_OPEN_FILES, Layout, LayoutError
from frontend import (
    new_project_panel,
    page_clicks,
    panel_layout,
    plant_view,
    project_edit_panel,
    project_tree_view,
    screens,
    status_bar,
)
from frontend.confirm import attempt, confirm
from frontend.dialogs.deployment import deployment_of, start_compile
from frontend.dialogs.download import ask_download
from frontend.dialogs.online_change import ask_online_change
from frontend.editor.editor_area import EditorArea, EditorHooks
from frontend.forcing_feed import ForcingFeed, Target
from frontend.gui_value import set_value
from frontend.permissions import Allowed, allowed
from frontend.resource_feed import ResourceFeed
from frontend.screen_registry import Now, Screen
from frontend.screens import events, forcing
from frontend.ui_context import UiContext
from frontend.viser_lockdown import PASSWORD_LABEL
from runtime.contract import protocol as p

S = TypeVar("S", bound=Screen)


class WorkspaceSession(Protocol):
    """What the workspace needs of the browser session that owns it (a `BrowserSession`);
    named here so that the workspace does not import its owner."""

    client: viser.ClientHandle
    context: UiContext
    user: str
    level: str

    def log_out(self) -> None: ...
    def time_left_ns(self) -> int: ...
    def news(self) -> None: ...
    def resource_login(self, resource: str) -> ResourceLogin | None: ...
    def client_of(self, resource: str) -> ResourceClient: ...
    def log_in_to(self, resource: str, user: str, password: str) -> ResourceLogin: ...
    def feed_of(self, resource: str) -> ResourceFeed: ...


EVENTS = 20  # the newest events below the editor (the Events screen has them all)
NAVIGATION_WIDTH = 300
NAVIGATION_NARROW = 260  # in a window narrower than WIDE_WINDOW: the editor needs it more
WIDE_WINDOW = 1600
WORK_WIDTH = 780  # the work panel where the window is wide enough
# The editor is the main work: by default it keeps some 80 columns of code (at 1400 px the
# work panel then gets ~440 px); a screen that wants room (Trends) or the width the user
# dragged the panel to may take it down to some 60 columns.
EDITOR_WIDTH = 700
EDITOR_LEAST = 540
ASSUMED_WINDOW = 1920  # until the page said its width
NONE = "(none online)"
NO_PROJECT = "(no project)"


class Workspace:
    def __init__(self, session: WorkspaceSession) -> None:
        self.session = session
        self.client = client = session.client
        self.context, self.user, self.level = session.context, session.user, session.level
        self.gui = gui = client.gui
        self.layout = self.context.user_layouts.of(self.user)  # as the user left it
        self.window_width = ASSUMED_WINDOW
        gui.main_panel.dock_left()
        gui.main_panel.set_width(self._navigation_width())
        self._handles: list[Any] = []
        self.shelf = self.context.shelf
        # Every attribute a callback reads is set before the first widget that can call
        # back exists: viser calls from its own thread, as soon as a browser acts.
        self.tree_reader: project_tree_view.TreeReader | None = None
        self.tree_shown: tuple[int, project_tree_view.Entry | None] = (-1, None)
        self.tree_entry: project_tree_view.Entry | None = None
        self.drawing_wanted = False  # the drawing costs the page: only when asked for
        # the first PROGRAM is opened once the tree is read, unless the user left files open
        self.first_program_wanted = not (
            self.layout.open_files and self.layout.project in self.shelf
        )
        self.editor_area = EditorArea(
            client, self.shelf, Editor(self.user, self.level), _hooks(self)
        )
        keep = self._handles.append
        self.forcing_feed = ForcingFeed()
        self.forcing_banner = forcing.build_banner(gui)  # on top, seen from every tab
        keep(self.forcing_banner.handle)
        self.reach_banner = gui.add_html("", visible=False)  # the resource out of reach
        keep(self.reach_banner)
        keep(gui.add_html(_header(session.user, session.level)))
        self.session_note = gui.add_html("")
        keep(self.session_note)
        logout = gui.add_button("Log out")
        logout.on_click(lambda _: session.log_out())
        keep(logout)
        names = tuple(self.shelf) or (NO_PROJECT,)
        with gui.add_folder("Project") as project_folder:
            self.project_choice = gui.add_dropdown("Project", names)
            self.tree = gui.add_html("")
            self.edit_target = project_edit_panel.EditTarget(
                client,
                self.shelf,
                Editor(self.user, self.level),
                self.project,
                lambda: self.tree_entry,
                self._edited,
            )
            self.edits = project_edit_panel.build(gui, self.edit_target)
            maker = new_project_panel.Maker(self.shelf, Editor(self.user, self.level), self._made)
            new_project_panel.build(gui, maker)
        keep(project_folder)
        self.project_choice.on_update(lambda _: self._open_project())
        self._open_project()
        self.resource = gui.add_dropdown("Resource", (NONE,))
        keep(self.resource)
        with gui.add_folder("Login to the resource") as folder:
            self.resource_user = gui.add_text("User", session.user)
            self.resource_password = gui.add_text(PASSWORD_LABEL, "")
            button = gui.add_button("Log in to resource", color="blue")
            self.resource_login = gui.add_html("")
        button.on_click(lambda _: self._log_in_to_resource())
        keep(folder)
        with gui.add_folder("Status") as status_folder:
            self.status = gui.add_html("")
        keep(status_folder)
        self.panel = gui.add_panel()
        self.screens: list[Screen] = []  # the tabs, in their order
        for kind in screens.SCREENS:  # the one list
            with self.panel.add_tab(kind.name, kind.icon):
                self.screens.append(kind(self))
        self.shown = self.screens[0]  # the tab group opens on its first tab
        self.events = self.screen(events.Events)  # its log is below the editor too
        self.panel.dock_right()
        self.panel.set_width(self._work_width())
        panel_layout.put_back(gui, self.panel, self.layout)
        self.drawing = plant_view.PlantView(client)
        if self.layout.project in self.shelf:  # the files the user left open
            for path in self.layout.open_files:
                self.editor_area.open_file(self.layout.project, path, keyboard=False)
        # last: the page then reports the window's size, and clicks, to a whole workspace
        self.page_clicks = page_clicks.build(gui, self._clicked)

    def screen(self, kind: type[S]) -> S | None:
        """The screen of that kind in this workspace (a screen that reads another's)."""
        return next((s for s in self.screens if isinstance(s, kind)), None)

    def open_in_editor(self, project: str, file: str, line: int, col: int) -> None:
        self.editor_area.open_file(project, file, line, col=col)

    def show_coverage(self, project: str, files: dict[str, Any]) -> None:
        self.editor_area.show_coverage(project, files)

    def _navigation_width(self) -> int:
        """As the user dragged it, else narrower in a narrow window."""
        if self.layout.navigation_width is not None:
            return self.layout.navigation_width
        return NAVIGATION_WIDTH if self.window_width >= WIDE_WINDOW else NAVIGATION_NARROW

    def _work_width(self) -> int:
        """The work panel's width: as wide as the shown screen or the user wants, but
        leaving the navigation and the editor their room in this window (viser scales both
        docked panels down when they exceed it, and clips what they hold)."""
        asked = self.shown.width or self.layout.work_width
        editor = EDITOR_LEAST if asked else EDITOR_WIDTH
        room = self.window_width - self._navigation_width() - editor
        return max(360, min(asked or WORK_WIDTH, room))

    def _clicked(self, click: page_clicks.Click) -> None:
        if click.kind == "tab":
            chosen = next((s for s in self.screens if s.name == click.name), None)
            if chosen is not None:
                before = self._work_width()
                self.shown = chosen
                if self._work_width() != before:
                    self.panel.set_width(self._work_width())
                self.session.news()  # drawn at once, not at the next tick
        elif click.kind == "window":
            width, _, height = click.name.partition("x")
            if width.isdigit() and height.isdigit() and 0 < int(width) < 100_000:
                self.window_width = int(width)
                self.gui.main_panel.set_width(self._navigation_width())
                self.panel.set_width(self._work_width())
        elif click.kind == "drawing":
            self.drawing_wanted = click.name == "on"
            self.session.news()
        elif click.kind == "layout":
            seen = panel_layout.read(click.name)
            if seen is not None:
                self._keep(panel_layout.kept(self.layout, seen))
        elif click.kind == "tree":
            entry = project_tree_view.entry_of(click.name)
            if entry is not None:
                self.tree_entry = entry
                if entry.kind == "file":
                    self.editor_area.open_file(self.project_choice.value, entry.file, entry.line)
                self.session.news()
        else:
            for screen in self.screens:
                screen.clicked(click)

    def _keep(self, layout: Layout) -> None:
        """The user's layout, kept for their next login (one the store refuses is used
        in this browser only)."""
        self.layout = layout
        with contextlib.suppress(LayoutError):
            self.context.user_layouts.put(self.user, layout)

    def _open_project(self) -> None:
        if self.tree_reader is not None:
            self.tree_reader.close()
            self.tree_reader = None
        name = self.project_choice.value
        if name in self.shelf:
            editor = Editor(self.user, self.level)
            self.tree_reader = project_tree_view.TreeReader(self.shelf, name, editor)
        self.tree_entry = None
        self.tree_shown = (-1, None)
        self.tree.content = project_tree_view.render(None, None) if self.tree_reader else ""

    def _made(self, name: str) -> None:
        """A project made from a template: chosen, so that its tree is read and shown."""
        self.project_choice.options = tuple(self.shelf)
        set_value(self.project_choice, name)  # opens it (the chooser's update)

    def project(self) -> str | None:
        name = self.project_choice.value
        return name if name in self.shelf else None

    def _edited(self, path: str | None) -> None:
        """After an add, rename or delete from the tree: the tree at once, the new file in
        the editor."""
        if self.tree_reader is not None:
            self.tree_reader.read_again()
        project = self.project()
        if path is not None and project is not None:
            self.editor_area.open_file(project, path, 1)
        self.session.news()

    def selected(self) -> str | None:
        value = self.resource.value
        return None if value == NONE else value

    # ---- actions
    def _log_in_to_resource(self) -> None:
        resource = self.selected()
        if resource is None:  # said, not silently ignored: the user may wonder why
            self.session.client.add_notification(
                "Login to a resource refused",
                "no resource is online on this PADT's Zenoh yet: it is listed once it is",
                color="red",
                auto_close_seconds=8,
            )
            return
        user, password = self.resource_user.value.strip(), self.resource_password.value
        set_value(self.resource_password, "")  # not kept in the browser either
        attempt(
            self.session.client,
            f"Login to {resource}",
            lambda: self.session.log_in_to(resource, user, password),
        )

    def confirm(self, label: str, command: p.Command[p.StatusReply], what: str) -> None:
        resource = self.selected()
        if resource is None:
            return
        client = self.session.client
        confirm(
            client,
            f"{label}: {resource}",
            self._naming_crc(resource, f"{what[0].upper()}{what[1:]}."),
            lambda: self._send(f"{label} {resource}", resource, command),
        )

    def act(
        self,
        label: str,
        make: Callable[[], p.Command[p.StatusReply]],
        question: str | None,
        times: int,
    ) -> None:
        resource = self.selected()
        if resource is None:
            return

        def send() -> None:
            client = self.session.client_of(resource)
            for _ in range(times):
                client.ask(make())

        if question is None:
            attempt(self.session.client, f"{label} ({resource})", send)
        else:
            confirm(
                self.session.client,
                f"{label}: {resource}",
                self._naming_crc(resource, f"{question[0].upper()}{question[1:]}."),
                lambda: attempt(self.session.client, f"{label} ({resource})", send),
            )

    def send_all(
        self,
        label: str,
        commands: Sequence[p.Command[p.StatusReply]],
        question: str,
        note: str | None,
    ) -> None:
        """Ask `question`; then send the commands in order to the selected resource (the
        first refusal ends it) and ask the forcing state again; `note` when all were done."""
        resource = self.selected()
        if resource is None:
            return
        client = self.session.client

        def send() -> None:
            try:
                target = self.session.client_of(resource)
                for command in commands:
                    target.ask(command)
            finally:
                self.forcing_feed.nudge()

        def yes() -> None:
            if attempt(client, f"{label} ({resource})", send) and note:
                client.add_notification(label, note, color="yellow", auto_close_seconds=12)

        confirm(client, f"{label}: {resource}", self._naming_crc(resource, question), yes)

    def change(
        self,
        title: str,
        question: str,
        command: p.Command[p.StatusReply],
        then: Callable[[], None],
    ) -> None:
        """Ask, send `command` to the selected resource, then `then()` whatever came back
        (a screen reads again what the command may have changed)."""
        resource = self.selected()
        if resource is None:
            return

        def send() -> None:
            self._send(f"{title} ({resource})", resource, command)
            then()

        confirm(self.session.client, f"{title}: {resource}", question, send)

    def _naming_crc(self, resource: str, question: str) -> str:
        """A confirmation names the configuration it changes: the user sees what runs
        before changing it (docs/browser-ui.md)."""
        return f"{question} Resource {resource} runs configuration {self._crc(resource)}."

    def client_of(self, resource: str) -> ResourceClient:
        return self.session.client_of(resource)

    def _send(self, what: str, resource: str, command: p.Command[p.StatusReply]) -> None:
        attempt(self.session.client, what, lambda: self.session.client_of(resource).ask(command))

    def _crc(self, resource: str) -> str:
        status = self._status(resource)
        return status.crc or "-" if status is not None else "(unknown)"

    def _status(self, resource: str | None) -> p.Status | None:
        if resource is None:
            return None
        latest = self.session.feed_of(resource).latest
        with latest.lock:
            return latest.status

    def allowed(self, command: type[p.Command[Any]] | p.Command[Any]) -> Allowed:
        resource = self.selected()
        status = self._status(resource)
        open_access = status is not None and status.access == "open"
        login_there = self.session.resource_login(resource) if resource is not None else None
        return allowed(self.session.level, login_there, command, open_access)

    # ---- ten times a second
    def refresh(self) -> None:
        note = _session_note(self.session.time_left_ns())
        if self.session_note.content != note:
            self.session_note.content = note
        self._refresh_tree()
        project_edit_panel.refresh(self.edits, self.edit_target)
        online = self.context.directory.online()
        names = tuple(name for name, _ in online)
        chosen = self.selected()
        if chosen is not None and chosen not in names:
            # out of reach (its host cut off, its process gone): kept chosen, so that the
            # status bar says since when, and it is there again when it comes back
            names = (*names, chosen)
        names = names or (NONE,)
        if tuple(self.resource.options) != names:
            self.resource.options = names
        resource = self.selected()
        status = self._status(resource)
        reach = self.session.feed_of(resource).latest.reach if resource is not None else None
        self.status.content = status_bar.render(
            self.context.router, self.user, self.level, resource, status, reach
        )
        banner = status_bar.reach_banner(resource, reach)
        if banner != self.reach_banner.content:
            self.reach_banner.content = banner
            self.reach_banner.visible = bool(banner)
        login_there = self.session.resource_login(resource) if resource is not None else None
        self.resource_login.content = _login_note(resource, login_there)
        feed = self.session.feed_of(resource) if resource is not None else None
        self._follow_forcing(resource, status, login_there)  # its banner is on every tab
        snapshot = self.forcing_feed.snapshot()
        now = Now(resource, status, feed, login_there, list(online), snapshot)
        for screen in self.screens:
            screen.follow(now)
        self.shown.refresh(now)  # the others wait until they are opened
        self.editor_area.refresh(feed, self.allowed(p.DebugStep))
        if self.events is not None:
            self.editor_area.show_events(events.newest(self.events.screen, resource, EVENTS))
        if feed is not None:  # only what some screen shows is watched, seen or not: a
            # tab opened shows its values at once
            paths = [path for screen in self.screens for path in screen.watches()]
            feed.show(paths + self.editor_area.wanted())
        if self.drawing_wanted:
            self.drawing.show(resource, status)
        else:
            self.drawing.show(None, None)  # nothing drawn behind the editor

    def _refresh_tree(self) -> None:
        if self.tree_reader is None:
            return
        version, tree = self.tree_reader.latest()
        if (version, self.tree_entry) != self.tree_shown and tree is not None:
            self.tree.content = project_tree_view.render(tree, self.tree_entry)
            self.tree_shown = (version, self.tree_entry)
        if self.first_program_wanted and isinstance(tree, ProjectTree):
            self.first_program_wanted = False  # once: a file closed stays closed
            first = next((i for i in tree.pous if i.kind == "PROGRAM"), None)
            project = self.project()
            if first is not None and project is not None and not self.editor_area.documents:
                self.editor_area.open_file(project, first.file, first.line, keyboard=False)

    def _follow_forcing(
        self, resource: str | None, status: p.Status | None, login_there: ResourceLogin | None
    ) -> None:
        looks = status is not None and (login_there is not None or status.access == "open")
        if resource is None or status is None or not looks:
            self.forcing_feed.follow(None)
        else:
            client = self.session.client_of(resource)
            self.forcing_feed.follow(Target(resource, client, status.crc, status.forcing))
        forcing.show_banner(self.forcing_banner, status, self.forcing_feed.snapshot())

    def remove(self) -> None:
        self.forcing_feed.close()
        if self.tree_reader is not None:
            self.tree_reader.close()
        for handle in self._handles:
            handle.remove()
        open_files = tuple(self.editor_area.documents)[:MAX_OPEN_FILES]
        self._keep(
            replace(self.layout, project=self.editor_area.project or "", open_files=open_files)
        )
        self.page_clicks.remove()
        self.panel.remove()
        self.drawing.remove()
        self.editor_area.remove()


def _hooks(work: Workspace) -> EditorHooks:
    """The editor's Compile, Download and Online change: the dialogs the Online change
    screen opens too."""
    deployment = deployment_of(work)
    return EditorHooks(
        lambda project: start_compile(deployment, project),
        lambda project: ask_download(deployment, project),
        lambda project: ask_online_change(deployment, project),
    )


def _header(user: str, level: str) -> str:
    return (
        '<div style="padding:4px 0"><b style="font-size:1.15em">PADT</b> '
        f'<span data-testid="user">{user}</span> '
        f'<span style="color:#868e96" data-testid="level">({level})</span></div>'
    )


def _session_note(left_ns: int) -> str:
    """The PADT session's time left, to the minute (to the second in the last minute)."""
    seconds = left_ns // 10**9
    if seconds >= 60:
        hours, minutes = divmod(seconds // 60, 60)
        left = f"{hours} h {minutes} min" if hours else f"{minutes} min"
    else:
        left = f"{seconds} s"
    return (
        '<div data-testid="session-left" style="color:#868e96;font-size:0.85em">'
        f"session ends in {left}</div>"
    )


def _login_note(resource: str | None, made: Any) -> str:
    if resource is None:
        return ""
    if made is None:
        return (
            '<div data-testid="resource-login" style="color:#868e96">not logged in to '
            f"{resource}</div>"
        )
    return (
        f'<div data-testid="resource-login">logged in to {resource} as {made.user} '
        f"({made.level})</div>"
    )
