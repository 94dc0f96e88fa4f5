"""The workspace of a logged-in browser, using the whole window: on the left the navigation
(who is logged in, the resource to work on, the login to it, the status bar); on the right
the work area with a tab per screen; in between, the viewport draws the selected resource
and its programs in the colours of their states."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, Protocol

import viser

from backend.engineering.resource_client import ResourceClient, ResourceLogin
from frontend import plant_view, status_bar
from frontend.confirm import attempt, confirm
from frontend.permissions import Allowed, allowed
from frontend.resource_feed import ResourceFeed
from frontend.screens import code, login, online_test, resources, single_step
from frontend.ui_context import UiContext
from runtime.contract import protocol as p


class WorkspaceSession(Protocol):
    """What the workspace needs of the browser session that owns it (a `BrowserSession`);
    named here so that the workspace does not import its owner."""

    client: viser.ClientHandle
    context: UiContext
    user: str
    level: str

    def log_out(self) -> None: ...
    def resource_login(self, resource: str) -> ResourceLogin | None: ...
    def client_of(self, resource: str) -> ResourceClient: ...
    def log_in_to(self, resource: str, user: str, password: str) -> ResourceLogin: ...
    def feed_of(self, resource: str) -> ResourceFeed: ...


NAVIGATION_WIDTH = 300
WORK_WIDTH = 780
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
        keep(gui.add_html(_header(session.user, session.level)))
        logout = gui.add_button("Log out")
        logout.on_click(lambda _: session.log_out())
        keep(logout)
        self.resource = gui.add_dropdown("Resource", (NONE,))
        keep(self.resource)
        with gui.add_folder("Login to the resource") as folder:
            self.resource_user = gui.add_text("User", session.user)
            self.resource_password = gui.add_text("Password", "")
            gui.add_html(login.masked(self.resource_password))
            button = gui.add_button("Log in to resource", color="blue")
            self.resource_login = gui.add_html("")
        button.on_click(lambda _: self._log_in_to_resource())
        keep(folder)
        with gui.add_folder("Status") as status_folder:
            self.status = gui.add_html("")
        keep(status_folder)
        self.panel = gui.add_panel()
        with self.panel.add_tab("Resources", viser.Icon.SERVER):
            self.resources = resources.build(gui, self._confirm, self.selected)
        with self.panel.add_tab("Online test", viser.Icon.TABLE):
            self.online_test = online_test.build(gui)
        with self.panel.add_tab("Single step", viser.Icon.PLAYER_TRACK_NEXT):
            self.single_step = single_step.build(gui, self._act)
        with self.panel.add_tab("Code", viser.Icon.CODE):
            self.code = code.build(gui)
        self.panel.dock_right()
        self.panel.set_width(WORK_WIDTH)
        self.drawing = plant_view.PlantView(client)

    def selected(self) -> str | None:
        value = self.resource.value
        return None if value == NONE else value

    # ---- actions
    def _log_in_to_resource(self) -> None:
        resource = self.selected()
        if resource is None:
            return
        user, password = self.resource_user.value.strip(), self.resource_password.value
        # Not kept in the browser either. viser defines the setter apart from
        # the getter, which mypy reads as a read-only property.
        self.resource_password.value = ""  # type: ignore[misc]
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
            f"{what[0].upper()}{what[1:]}. Resource {resource} runs configuration "
            f"{self._crc(resource)}.",
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
                f"{question[0].upper()}{question[1:]}.",
                lambda: attempt(self.session.client, f"{label} ({resource})", send),
            )

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

    def _allowed(self, command: type[p.Command[Any]]) -> Allowed:
        resource = self.selected()
        status = self._status(resource)
        open_access = status is not None and status.access == "open"
        login_there = self.session.resource_login(resource) if resource is not None else None
        return allowed(self.session.level, login_there, command, open_access)

    # ---- ten times a second
    def refresh(self) -> None:
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
        resources.refresh(self.resources, list(directory.items()), resource, self._allowed)
        online_test.refresh(
            self.online_test, self.session.feed_of(resource) if resource is not None else None
        )
        single_step.refresh(self.single_step, status, self._allowed)
        code.refresh(
            self.code,
            self.session.feed_of(resource) if resource is not None else None,
            self.session.context.projects,
        )
        self.drawing.show(resource, status)

    def remove(self) -> None:
        for handle in self._handles:
            handle.remove()
        self.panel.remove()
        self.drawing.remove()


def _header(user: str, level: str) -> str:
    return (
        '<div style="padding:4px 0"><b style="font-size:1.15em">PADT</b> '
        f'<span data-testid="user">{user}</span> '
        f'<span style="color:#868e96" data-testid="level">({level})</span></div>'
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
