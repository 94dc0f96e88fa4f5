"""One browser: logged out (it sees the login form only) or logged in with a PADT account
(it sees the workspace). The UI acts with that account and, at each resource, with the
resource login the user made in this browser; no built-in account acts for a browser."""

from __future__ import annotations

import threading
from collections.abc import Callable

import viser

from backend.engineering.resource_client import ResourceClient, ResourceLogin, ResourceUnreachable
from frontend import viser_lockdown
from frontend.resource_feed import ResourceFeed
from frontend.screens import login
from frontend.ui_context import UiContext
from frontend.workspace import Workspace
from runtime.contract.refusal import Refusal


class BrowserSession:
    def __init__(
        self,
        client: viser.ClientHandle,
        context: UiContext,
        address: str,
        on_news: Callable[[], None] = lambda: None,
    ) -> None:
        """`on_news` is called (from Zenoh's threads) when a resource sent something new
        for this browser; `take_news` then says so once."""
        self.client, self.context, self.address = client, context, address
        self._on_news = on_news
        self._news = False
        self.token: str | None = None  # the PADT session of this browser
        self.user, self.level = "", ""
        self._lock = threading.Lock()  # the refresher and the GUI's callbacks
        # Held while the screens are drawn, built or removed: a logout in viser's thread
        # must not remove the handles that the refresher is drawing into.
        self._drawing = threading.RLock()
        self._clients: dict[str, ResourceClient] = {}
        self._feeds: dict[str, ResourceFeed] = {}
        self._form: login.LoginForm | None = None
        self.workspace: Workspace | None = None
        client.gui.add_html(viser_lockdown.PAGE_HTML)  # for as long as the page lives
        self.show_login("")

    # ---- the PADT login
    def show_login(self, message: str) -> None:
        with self._drawing:
            self._close_workspace()
            self._form = login.build(self.client.gui, message, self._log_in)

    def _log_in(self, user: str, password: str) -> None:
        try:
            token, session = self.context.accounts.login(user, password, self.address)
        except Refusal as refused:
            self.show_login_message(refused.message)
            return
        with self._drawing:
            self.token, self.user, self.level = token, session.user, session.level
            if self._form is not None:
                self._form.remove()
                self._form = None
            self.workspace = Workspace(self)

    def show_login_message(self, message: str) -> None:
        if self._form is not None:
            self._form.message.content = login.note(message, error=True)

    def log_out(self) -> None:
        if self.token is not None:
            self.context.accounts.logout(self.token)
        self.token = None
        self.show_login("Logged out.")

    def time_left_ns(self) -> int:
        return self.context.accounts.time_left_ns(self.token) if self.token else 0

    def valid(self) -> bool:
        """Whether the PADT session still holds; an ended one shows the login again."""
        if self.token is None:
            return False
        try:
            self.context.accounts.check(self.token, "read-only")
        except Refusal:
            self.token = None
            self.show_login("Your session has ended: log in again.")
            return False
        return True

    def _close_workspace(self) -> None:
        with self._lock:
            for feed in self._feeds.values():
                feed.close()
            self._feeds.clear()
            for client in self._clients.values():
                client.close()
            self._clients.clear()
        if self.workspace is not None:
            self.workspace.remove()
            self.workspace = None

    # ---- resources, with this user's logins
    def resource_login(self, resource: str) -> ResourceLogin | None:
        if self.token is None:
            return None
        return self.context.accounts.resource_login(self.token, resource)

    def client_of(self, resource: str) -> ResourceClient:
        """This browser's client of a resource (Refusal `unknown_resource` when it is not
        online), signing with the user's login to it."""
        with self._lock:
            client = self._clients.get(resource)
            if client is None:
                client = self._clients[resource] = self.context.directory.client(resource)
            client.logged_in = self.resource_login(resource)
            return client

    def log_in_to(self, resource: str, user: str, password: str) -> ResourceLogin:
        """A login to a resource with the user's own account there; Refusal otherwise."""
        if self.token is None:
            raise Refusal("unauthenticated", "log in to the PADT first")
        client = self.client_of(resource)
        try:
            made = client.login(user, password)
        except ResourceUnreachable as exc:
            raise Refusal("unreachable", str(exc)) from None
        self.context.accounts.set_resource_login(self.token, resource, made)
        self.context.directory.trust(resource, made.publication_key)
        self.feed_of(resource).restart()
        return made

    def feed_of(self, resource: str) -> ResourceFeed:
        """The live data of a resource as this browser's login sees it."""
        with self._lock:
            feed = self._feeds.get(resource)
        if feed is None:
            feed = ResourceFeed(self.client_of(resource), self.news)
            with self._lock:
                self._feeds[resource] = feed
        return feed

    # ---- the refresher's calls
    def news(self) -> None:
        """Something new to show: the refresher draws this browser soon."""
        self._news = True
        self._on_news()

    def take_news(self) -> bool:
        news, self._news = self._news, False
        return news

    def refresh(self) -> None:
        with self._drawing:
            if self.workspace is not None and self.valid():
                self.workspace.refresh()

    def close(self) -> None:
        with self._drawing:
            self._close_workspace()
