"""What every screen of the work area is: one interface (`Screen`) over what the workspace
offers it (`Work`) and what one refresh knows (`Now`). The screens themselves are listed
once, in `frontend/screens/__init__.py`; the workspace makes a tab of each, in that order,
redraws the one in view, follows all of them and watches what they show. A new screen is a
module with a `Screen` and a line in that list."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, ClassVar, Protocol, TypeVar

import viser

from backend.engineering.resource_client import ResourceClient, ResourceLogin
from frontend.forcing_feed import ForcingFeed, ForcingSnapshot
from frontend.page_clicks import Click
from frontend.permissions import Allowed
from frontend.resource_feed import ResourceFeed
from frontend.ui_context import UiContext
from runtime.contract import protocol as p

S = TypeVar("S", bound="Screen")


class Work(Protocol):
    """What the workspace offers every screen (a `Workspace`; named here so that no screen
    imports the workspace)."""

    gui: viser.GuiApi
    client: viser.ClientHandle
    context: UiContext
    user: str
    level: str
    forcing_feed: ForcingFeed

    def selected(self) -> str | None:
        """The resource chosen in the navigation."""
        ...

    def project(self) -> str | None:
        """The project chosen in the navigation (its tree)."""
        ...

    def allowed(self, command: type[p.Command[Any]] | p.Command[Any]) -> Allowed: ...
    def client_of(self, resource: str) -> ResourceClient: ...
    def confirm(self, label: str, command: p.Command[p.StatusReply], what: str) -> None: ...
    def act(
        self,
        label: str,
        make: Callable[[], p.Command[p.StatusReply]],
        question: str | None,
        times: int,
    ) -> None: ...
    def send_all(
        self,
        label: str,
        commands: Sequence[p.Command[p.StatusReply]],
        question: str,
        note: str | None,
    ) -> None: ...
    def change(
        self,
        title: str,
        question: str,
        command: p.Command[p.StatusReply],
        then: Callable[[], None],
    ) -> None: ...
    def screen(self, kind: type[S]) -> S | None: ...
    def open_in_editor(self, project: str, file: str, line: int, col: int) -> None:
        """Open a file of a project in the editor, the cursor at line:col."""
        ...

    def show_coverage(self, project: str, files: dict[str, Any]) -> None:
        """Shade the lines of the project's files in the editor as a test run ran them."""
        ...


@dataclass(frozen=True)
class Now:
    """What one refresh of a browser knows, the same for every screen."""

    resource: str | None  # the selected resource
    status: p.Status | None  # its status as this browser's feed has it
    feed: ResourceFeed | None
    login: ResourceLogin | None  # this browser's login to it
    directory: list[tuple[str, p.Status | None]]  # every resource online, by name
    forcing: ForcingSnapshot | None

    @property
    def token(self) -> str | None:
        return self.login.token if self.login is not None else None

    @property
    def away(self) -> bool:
        """The selected resource's runtime is gone from the bus (what is shown of it is
        what it last sent)."""
        return self.feed is not None and self.feed.latest.reach.away_since_ns is not None


class Screen:
    """A tab of the work area. A subclass names its tab and icon, builds its controls in
    `__init__` (inside its tab) and draws them in `refresh`; the rest is optional."""

    name: ClassVar[str]
    icon: ClassVar[viser.IconName]
    width: ClassVar[int | None] = None  # a screen that wants more room than the others

    def __init__(self, work: Work) -> None:
        self.work = work

    def refresh(self, now: Now) -> None:
        """Draw the screen: only while it is in view (ten browsers drawing every screen
        ten times a second cost most of two cores)."""

    def follow(self, now: Now) -> None:
        """At every refresh, in view or not: what must not miss a moment (live events, a
        chart's history)."""

    def watches(self) -> list[str]:
        """The variables whose values the screen shows, watched in view or not: a tab
        opened shows its values at once."""
        return []

    def clicked(self, click: Click) -> None:
        """A click in the page that viser does not report (a row of a table)."""
