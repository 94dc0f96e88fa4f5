"""The viser UI server: a GUI per browser, kept up to date from the resource feed by a
refresher thread ten times a second; every action goes through the engineering services'
resource client, and so through the resource's own checks."""

from __future__ import annotations

import threading

import viser

from backend.engineering.resource_client import ResourceClient, ResourceUnreachable
from frontend.resource_feed import ResourceFeed
from frontend.screens import online_test
from frontend.screens.online_test import OnlineTestView
from runtime.contract import protocol as p
from runtime.contract.refusal import Refusal

REFRESH_S = 0.1


class PadtUi:
    def __init__(self, client: ResourceClient, host: str = "127.0.0.1", port: int = 8080) -> None:
        self.client = client
        self.feed = ResourceFeed(client)
        self.views: dict[int, OnlineTestView] = {}
        self.server = viser.ViserServer(host=host, port=port, verbose=False)
        self.server.gui.configure_theme(control_width="large", show_logo=False)
        self.server.on_client_connect(self._connect)
        self.server.on_client_disconnect(self._disconnect)
        self._stop = threading.Event()
        self._refresher = threading.Thread(target=self._refresh_loop, daemon=True)
        self._refresher.start()

    @property
    def url(self) -> str:
        return f"http://127.0.0.1:{self.server.get_port()}"

    def _connect(self, client: viser.ClientHandle) -> None:
        def act(command: p.Command[p.StatusReply]) -> None:
            self._act(client, command)

        self.views[client.client_id] = online_test.build(client.gui, self.client.resource, act)

    def _disconnect(self, client: viser.ClientHandle) -> None:
        self.views.pop(client.client_id, None)

    def _act(self, client: viser.ClientHandle, command: p.Command[p.StatusReply]) -> None:
        try:
            reply = self.client.ask(command)
        except ResourceUnreachable as exc:
            client.add_notification("No answer", str(exc), color="red", auto_close_seconds=5)
            return
        except Refusal as refused:
            title = f"{command.NAME} refused"
            client.add_notification(title, refused.message, color="red", auto_close_seconds=5)
            return
        self.feed.show_status(reply.status)

    def _refresh_loop(self) -> None:
        latest = self.feed.latest
        while not self._stop.wait(REFRESH_S):
            with latest.lock:
                version, status, cycle = latest.version, latest.status, latest.cycle
                values, types, quality = latest.values, latest.types, latest.quality
            status_html = online_test.render_status(status, cycle)
            table_html = online_test.render_values(values, types, quality)
            for view in list(self.views.values()):
                if view.shown_version != version:
                    view.status.content = status_html
                    view.table.content = table_html
                    view.shown_version = version

    def close(self) -> None:
        self._stop.set()
        self.server.stop()
