"""The viser UI server: a GUI per browser, each its own session (frontend/browser_session.py),
kept up to date by one refresher thread: a browser whose resource sent something new is
redrawn at once (new values reach the page without waiting for a tick), and every browser
ten times a second. Every action goes through the engineering services' resource client,
and so through the resource's own checks."""

from __future__ import annotations

import logging
import threading
import time

import viser

from backend.engineering.client_address import NO_PROXIES, TrustedProxies, client_address
from frontend import viser_lockdown, viser_wakeup
from frontend.browser_session import BrowserSession
from frontend.ui_context import UiContext

REFRESH_S = 0.1
GATHER_S = 0.005  # news that arrive together are drawn together
log = logging.getLogger("padt.ui")


class PadtUi:
    def __init__(
        self,
        context: UiContext,
        host: str = "127.0.0.1",
        port: int = 8080,
        trusted: TrustedProxies = NO_PROXIES,
    ) -> None:
        self.context = context
        self._trusted = trusted  # the proxies whose X-Forwarded-For names the browser
        self.browsers: dict[int, BrowserSession] = {}
        self._lock = threading.Lock()
        viser_wakeup.install()
        self.server = viser.ViserServer(host=host, port=port, verbose=False)
        viser_lockdown.lock_down(self.server)
        self.server.on_client_connect(self._connect)
        self.server.on_client_disconnect(self._disconnect)
        self._stop = threading.Event()
        self._news = threading.Event()
        self._refresher = threading.Thread(target=self._refresh_loop, daemon=True)
        self._refresher.start()

    @property
    def url(self) -> str:
        return f"http://127.0.0.1:{self.server.get_port()}"

    def _connect(self, client: viser.ClientHandle) -> None:
        address = self._address(client.client_id)
        session = BrowserSession(client, self.context, address, self._news.set)
        with self._lock:
            self.browsers[client.client_id] = session

    def _disconnect(self, client: viser.ClientHandle) -> None:
        with self._lock:
            session = self.browsers.pop(client.client_id, None)
        if session is not None:
            session.close()

    def _address(self, client_id: int) -> str:
        """The browser's address: failed logins lock a name for it only. viser does not
        publish it; its websocket connection knows it (viser is pinned below 1.2), and
        behind a trusted proxy the handshake's X-Forwarded-For says whom the proxy saw."""
        connections = getattr(self.server._websock_server, "_live_connections", {})
        connection = connections.get(client_id)
        address = getattr(connection, "remote_address", None)
        if not address:
            return f"browser {client_id}"
        request = getattr(connection, "request", None)
        forwarded = request.headers.get_all("X-Forwarded-For") if request is not None else []
        return client_address(str(address[0]), forwarded, self._trusted)

    def _refresh_loop(self) -> None:
        last_tick = 0.0
        while not self._stop.is_set():
            self._news.wait(REFRESH_S)
            self._stop.wait(GATHER_S)
            self._news.clear()
            now = time.monotonic()
            tick = now - last_tick >= REFRESH_S
            last_tick = now if tick else last_tick
            with self._lock:
                sessions = list(self.browsers.values())
            for session in sessions:
                if not (session.take_news() or tick):
                    continue
                try:
                    session.refresh()
                except Exception:  # one browser's trouble is not the others'
                    log.exception("refreshing a browser failed")

    def close(self) -> None:
        self._stop.set()
        with self._lock:
            sessions = list(self.browsers.values())
        for session in sessions:
            session.close()
        self.server.stop()
