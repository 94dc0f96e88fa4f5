"""The viser UI: resource state and CRC, OLT fields with live values, Start / Stop / Step.

Each browser gets its own GUI (login and user-specific views will live there). Live values
come from one watch set of the variables shown (the runtime sends nothing else), with their
quality; they are shown as one HTML table per client, which costs the browser far less
than one input widget per variable; a refresher thread pushes what changed ten times a
second.
"""

from __future__ import annotations

import html
import logging
import threading
from dataclasses import dataclass, field
from typing import Any

import viser

from backend.engineering.resource_client import (
    ResourceClient,
    ResourceUnreachable,
    Watch,
    WatchRefused,
)
from runtime.contract.values import format_value

REFRESH_S = 0.1
WATCH_PERIOD_MS = 100
log = logging.getLogger("padt.ui")


@dataclass
class _Latest:
    """What the runtime last told us; written by Zenoh callbacks, read by the refresher."""

    lock: threading.Lock = field(default_factory=threading.Lock)
    status: dict[str, Any] = field(default_factory=dict)
    values: dict[str, Any] = field(default_factory=dict)
    quality: dict[str, str] = field(default_factory=dict)  # live / forced / stale
    cycle: int = 0
    version: int = 0


@dataclass
class _ClientView:
    status: viser.GuiHtmlHandle
    table: viser.GuiHtmlHandle
    shown_version: int = -1


class PadtUi:
    def __init__(self, client: ResourceClient, host: str = "127.0.0.1", port: int = 8080) -> None:
        self.client = client
        self.latest = _Latest()
        self.types: dict[str, str] = {}
        self.views: dict[int, _ClientView] = {}
        self.server = viser.ViserServer(host=host, port=port, verbose=False)
        self.server.gui.configure_theme(control_width="large", show_logo=False)
        self.server.on_client_connect(self._connect)
        self.server.on_client_disconnect(self._disconnect)
        self._watch: Watch | None = None
        self._watching = threading.Lock()
        client.on_status(self._on_status)
        client.on_alive(self._on_alive)
        self._stop = threading.Event()
        self._refresher = threading.Thread(target=self._refresh_loop, daemon=True)
        self._refresher.start()
        threading.Thread(target=self._fetch_initial, daemon=True).start()

    @property
    def url(self) -> str:
        return f"http://127.0.0.1:{self.server.get_port()}"

    # ---- data from the runtime
    def _fetch_initial(self) -> None:
        """Show the resource at once, not only after its next publication."""
        try:
            status = self.client.command("status")
            values = self.client.command("values")
        except ResourceUnreachable as exc:
            log.info("%s; waiting for its status", exc)
            return
        self._on_status(status.get("status", {}))
        self._on_values({"cycle": values.get("cycle", 0), "values": values.get("values", {})})

    def _load_variables(self) -> None:
        with self._watching:  # a new configuration and a restarted runtime may coincide
            try:
                reply = self.client.command("variables")
            except ResourceUnreachable as exc:
                log.warning("%s", exc)
                return
            self.types = {v["path"]: v["type"] for v in reply.get("variables", [])}
            if self._watch is not None:
                self._watch.close()
                self._watch = None
            try:
                self._watch = self.client.watch(sorted(self.types), self._on_watch, WATCH_PERIOD_MS)
            except (ResourceUnreachable, WatchRefused) as exc:
                log.warning("no live values: %s", exc)
        with self.latest.lock:
            self.latest.version += 1

    def _on_alive(self, present: bool) -> None:
        """A runtime that (re)appears knows nothing of our watch set: register it again
        (outside Zenoh's thread)."""
        if present:
            threading.Thread(target=self._load_variables, daemon=True).start()

    def _on_status(self, status: dict[str, Any]) -> None:
        with self.latest.lock:
            crc_changed = status.get("crc") != self.latest.status.get("crc")
            self.latest.status = status
            self.latest.version += 1
        if crc_changed:
            # a (new) configuration: learn its variables; ask outside Zenoh's thread
            threading.Thread(target=self._load_variables, daemon=True).start()

    def _on_values(self, message: dict[str, Any]) -> None:
        with self.latest.lock:
            self.latest.values = message.get("values", {})
            self.latest.cycle = message.get("cycle", 0)
            self.latest.version += 1

    def _on_watch(self, message: dict[str, Any]) -> None:
        entries: dict[str, Any] = message.get("values", {})
        with self.latest.lock:
            self.latest.values = {path: entry["value"] for path, entry in entries.items()}
            self.latest.quality = {path: entry["quality"] for path, entry in entries.items()}
            self.latest.cycle = message.get("cycle", 0)
            self.latest.version += 1

    # ---- per-browser GUI
    def _connect(self, client: viser.ClientHandle) -> None:
        gui = client.gui
        gui.add_markdown(f"### Resource {html.escape(self.client.resource)}")
        status = gui.add_html("")
        with gui.add_folder("Commands"):
            for label, cmd in (("Start", "start"), ("Stop", "stop"), ("Step", "step")):
                self._command_button(client, label, cmd)
        with gui.add_folder("Online test (OLT)"):
            table = gui.add_html("")
        self.views[client.client_id] = _ClientView(status, table)

    def _command_button(self, client: viser.ClientHandle, label: str, cmd: str) -> None:
        def clicked(_event: viser.GuiEvent[viser.GuiButtonHandle]) -> None:
            self._command(client, cmd)

        client.gui.add_button(label).on_click(clicked)

    def _disconnect(self, client: viser.ClientHandle) -> None:
        self.views.pop(client.client_id, None)

    def _command(self, client: viser.ClientHandle, cmd: str) -> None:
        try:
            reply = self.client.command(cmd)
        except ResourceUnreachable as exc:
            client.add_notification("No answer", str(exc), color="red", auto_close_seconds=5)
            return
        if not reply.get("ok"):
            message = reply.get("error", {}).get("message", "refused")
            client.add_notification(f"{cmd} refused", message, color="red", auto_close_seconds=5)
        elif "status" in reply:
            self._on_status(reply["status"])

    # ---- rendering
    def _refresh_loop(self) -> None:
        while not self._stop.wait(REFRESH_S):
            with self.latest.lock:
                version = self.latest.version
                status, values, cycle = self.latest.status, self.latest.values, self.latest.cycle
                quality = self.latest.quality
            status_html = render_status(status, cycle)
            table_html = render_values(values, self.types, quality)
            for view in list(self.views.values()):
                if view.shown_version != version:
                    view.status.content = status_html
                    view.table.content = table_html
                    view.shown_version = version

    def close(self) -> None:
        self._stop.set()
        self.server.stop()


_CELL = "padding:2px 8px;border-bottom:1px solid #e5e5e5"


def render_status(status: dict[str, Any], cycle: int) -> str:
    state = html.escape(str(status.get("state", "unknown")))
    crc = html.escape(str(status.get("crc") or "-"))
    color = {"RUN": "#2b8a3e"}.get(state, "#c92a2a" if "ERROR" in state else "#e67700")
    rows = [
        ("State", f'<b data-testid="resource-state" style="color:{color}">{state}</b>'),
        ("Configuration CRC", f'<code data-testid="resource-crc">{crc}</code>'),
        ("Cycle", f'<span data-testid="resource-cycle">{cycle}</span>'),
    ]
    for program in status.get("programs", []):
        name = html.escape(str(program.get("name")))
        text = html.escape(str(program.get("state")))
        if program.get("error"):
            text += f" ({html.escape(str(program['error']))})"
        rows.append((f"Program {name}", f'<span data-program="{name}">{text}</span>'))
    body = "".join(
        f'<tr><td style="{_CELL}">{k}</td><td style="{_CELL}">{v}</td></tr>' for k, v in rows
    )
    return f'<table style="font-size:0.9em;width:100%">{body}</table>'


_QUALITY_COLORS = {"forced": "#c92a2a", "stale": "#868e96"}


def render_values(
    values: dict[str, Any], types: dict[str, str], quality: dict[str, str] | None = None
) -> str:
    rows = []
    for path in sorted(values):
        type_name = types.get(path, "")
        shown = html.escape(format_value(values[path], type_name))
        name = html.escape(path)
        how = (quality or {}).get(path, "live")
        color = _QUALITY_COLORS.get(how, "inherit")
        rows.append(
            f'<tr><td style="{_CELL}">{name}</td>'
            f'<td style="{_CELL};color:#868e96">{html.escape(type_name)}</td>'
            f'<td style="{_CELL};text-align:right;font-family:monospace;color:{color}" '
            f'data-var="{name}" data-quality="{html.escape(how)}">{shown}</td></tr>'
        )
    head = (
        f'<tr><th style="{_CELL};text-align:left">Variable</th>'
        f'<th style="{_CELL};text-align:left">Type</th>'
        f'<th style="{_CELL};text-align:right">Value</th></tr>'
    )
    return f'<table style="font-size:0.9em;width:100%">{head}{"".join(rows)}</table>'
