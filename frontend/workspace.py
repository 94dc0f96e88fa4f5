"""The workspace of a logged-in browser, using the whole window: on the left the navigation
(who is logged in, the resource to work on, the login to it, the status bar); on the right
the work area with a tab per screen; in between, the viewport draws the selected resource
and its programs in the colours of their states."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any, Protocol

import viser

from backend.engineering.resource_client import ResourceClient, ResourceLogin
from frontend import page_clicks, plant_view, status_bar
from frontend.confirm import attempt, confirm
from frontend.forcing_feed import ForcingFeed, Target
from frontend.gui_value import set_value
from frontend.permissions import Allowed, allowed
from frontend.resource_feed import ResourceFeed
from frontend.screens import (
    code,
    documentation,
    events,
    forcing,
    io,
    online_test,
    parameters,
    reload,
    resources,
    single_step,
    trends,
    value_edit,
)
from frontend.ui_context import UiContext
from frontend.viser_lockdown import PASSWORD_LABEL
from runtime.contract import protocol as p


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


NAVIGATION_WIDTH = 300
WORK_WIDTH = 780
TRENDS_WIDTH = 1100  # a chart wants width: the drawing gives way while Trends is in front
NONE = "(none online)"


class Workspace:
    def __init__(self, session: WorkspaceSession) -> None:
        self.session = session
        client = session.client
        gui = client.gui
        gui.main_panel.dock_left()
        gui.main_panel.set_width(NAVIGATION_WIDTH)
        self._handles: list[Any] = []
        keep = self._handles.append
        self.forcing_feed = ForcingFeed()
        self.forcing_banner = forcing.build_banner(gui)  # on top, seen from every tab
        keep(self.forcing_banner.handle)
        keep(gui.add_html(_header(session.user, session.level)))
        self.session_note = gui.add_html("")
        keep(self.session_note)
        logout = gui.add_button("Log out")
        logout.on_click(lambda _: session.log_out())
        keep(logout)
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
        self.screens: list[str] = []  # the tabs' names, in their order
        self.shown = "Resources"  # the tab group opens on its first tab
        self.page_clicks = page_clicks.build(gui, self._clicked)
        self.panel = gui.add_panel()
        with self._tab("Resources", viser.Icon.SERVER):
            self.resources = resources.build(gui, self._confirm, self.selected)
        with self._tab("Online test", viser.Icon.TABLE):
            self.online_test = online_test.build(gui, session.user, session.context.watch_lists)
            self.value_edit = value_edit.build(gui, self._send_all)
        with self._tab("Single step", viser.Icon.PLAYER_TRACK_NEXT):
            self.single_step = single_step.build(gui, self._act)
        with self._tab("Forcing", viser.Icon.LOCK):
            self.forcing = forcing.build(gui, self._send_all)
        with self._tab("Parameters", viser.Icon.ADJUSTMENTS):
            self.parameters = parameters.build(gui, self._change)
        with self._tab("Events", viser.Icon.LIST_DETAILS):
            self.events = events.build(gui)
        with self._tab("Reload", viser.Icon.REFRESH):
            self.reload = reload.build(gui, self._reload_hooks())
        with self._tab("Code", viser.Icon.CODE):
            self.code = code.build(gui)
        with self._tab("I/O", viser.Icon.PLUG_CONNECTED):
            self.io = io.build(gui)
        with self._tab("Documentation", viser.Icon.FILE_TEXT):
            context = session.context
            self.documentation = documentation.build(
                gui, client, context.projects, context.backup_dir, session.level
            )
        with self._tab("Trends", viser.Icon.CHART_LINE):
            self.trends = trends.build(gui, client, session.user, session.context.watch_lists)
        self.panel.dock_right()
        self.panel.set_width(WORK_WIDTH)
        self.drawing = plant_view.PlantView(client)

    def _tab(self, name: str, icon: viser.IconName) -> viser.GuiTabHandle:
        self.screens.append(name)
        return self.panel.add_tab(name, icon)

    def _clicked(self, click: page_clicks.Click) -> None:
        if click.kind == "tab" and click.name in self.screens:
            if (click.name == "Trends") != (self.shown == "Trends"):
                self.panel.set_width(TRENDS_WIDTH if click.name == "Trends" else WORK_WIDTH)
            self.shown = click.name
            self.session.news()  # drawn at once, not at the next tick
        elif click.kind == "variable":  # checked as typed text by the value editor
            value_edit.choose(self.value_edit, click.name)

    def _reload_hooks(self) -> reload.ReloadHooks:
        session = self.session
        return reload.ReloadHooks(
            session.client,
            session.context.projects,
            session.context.backup_dir,
            session.user,
            self.selected,
            session.client_of,
        )

    def selected(self) -> str | None:
        value = self.resource.value
        return None if value == NONE else value

    # ---- actions
    def _log_in_to_resource(self) -> None:
        resource = self.selected()
        if resource is None:
            return
        user, password = self.resource_user.value.strip(), self.resource_password.value
        set_value(self.resource_password, "")  # not kept in the browser either
        attempt(
            self.session.client,
            f"Login to {resource}",
            lambda: self.session.log_in_to(resource, user, password),
        )

    def _confirm(self, label: str, command: p.Command[p.StatusReply], what: str) -> None:
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

    def _act(
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

    def _send_all(
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

    def _change(
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

    def _allowed(self, command: type[p.Command[Any]] | p.Command[Any]) -> Allowed:
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
        online = self.session.context.directory.online()
        names = tuple(name for name, _ in online) or (NONE,)
        if tuple(self.resource.options) != names:
            self.resource.options = names
        resource = self.selected()
        status = self._status(resource)
        directory = dict(online)
        if resource is not None and status is not None:
            directory[resource] = status  # what this browser's login verified
        self.status.content = status_bar.render(
            self.session.context.router, self.session.user, self.session.level, resource, status
        )
        login_there = self.session.resource_login(resource) if resource is not None else None
        self.resource_login.content = _login_note(resource, login_there)
        feed = self.session.feed_of(resource) if resource is not None else None
        self._follow_forcing(resource, status, login_there)  # its banner is on every tab
        token = login_there.token if login_there is not None else None
        # always: its live counts tell the Parameters screen what others changed
        events.refresh(self.events, resource, token, self.session.client_of)
        trends.collect(self.trends, resource, feed)  # its history goes on in any tab
        self._refresh_shown(resource, status, feed, token, directory)
        if feed is not None:  # only what some screen shows is watched, seen or not: a
            # tab opened shows its values at once
            feed.show(
                online_test.wanted(self.online_test)
                + value_edit.wanted(self.value_edit)
                + forcing.wanted(self.forcing_feed.snapshot())
                + code.wanted(self.code)
                + trends.wanted(self.trends)
            )
        self.drawing.show(resource, status)

    def _refresh_shown(
        self,
        resource: str | None,
        status: p.Status | None,
        feed: ResourceFeed | None,
        token: str | None,
        directory: dict[str, p.Status | None],
    ) -> None:
        """Redraw the screen in view; the others wait until they are opened (ten browsers
        drawing every screen ten times a second cost most of two cores)."""
        shown = self.shown
        if shown == "Resources":
            resources.refresh(self.resources, list(directory.items()), resource, self._allowed)
        elif shown == "Online test":
            online_test.refresh(self.online_test, feed)
            snapshot = self.forcing_feed.snapshot()
            value_edit.refresh(self.value_edit, status, snapshot, feed, self._allowed)
        elif shown == "Single step":
            single_step.refresh(self.single_step, status, self._allowed)
        elif shown == "Forcing":
            snapshot = self.forcing_feed.snapshot()
            forcing.refresh(self.forcing, status, snapshot, feed, self._allowed)
        elif shown == "Parameters":
            changed = events.live_count(self.events, resource, "parameter")
            parameters.refresh(
                self.parameters,
                resource,
                status,
                token,
                self.session.client_of,
                self._allowed,
                changed,
            )
        elif shown == "Reload":
            reload.refresh(self.reload, resource, status, self._allowed)
        elif shown == "Code":
            code.refresh(self.code, feed, self.session.context.projects)
        elif shown == "I/O":
            io.refresh(self.io, resource, status, token, self.session.client_of)
        elif shown == "Documentation":
            documentation.refresh(self.documentation, resource, status)
        elif shown == "Trends":
            client_of = self.session.client_of
            trends.refresh(self.trends, resource, feed, token, client_of, self._allowed)

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
        for handle in self._handles:
            handle.remove()
        self.page_clicks.remove()
        self.panel.remove()
        self.drawing.remove()


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
