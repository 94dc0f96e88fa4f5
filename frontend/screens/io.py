"""The I/O screen: the resource's field I/O over Modbus TCP (docs/modbus.md). The served
image (where it listens, requests, exception responses, writes taken), each remote device
(its state, last error, requests, failures, round trip) and every mapped point with what
is on the wire now: served values (safe ones in STOP), inputs as delivered (their safe
values with quality bad while the device is lost).

The devices come with the resource's status; the points are read with the `io` command
twice a second while this screen is in view, off the refresher."""

from __future__ import annotations

import html
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import viser

from backend.engineering.reload import counted
from backend.engineering.resource_client import ResourceClient
from frontend.command_reading import CommandReading
from frontend.screen_registry import Now, Screen, Work
from runtime.contract import protocol as p
from runtime.contract.values import format_for_display

READS_PER_S = 2
MAX_ROWS = 500
ALL_SOURCES = "(all)"
_CELL = "padding:2px 6px;border-bottom:1px solid #e9ecef;vertical-align:top"
_GREY = "color:#868e96"
_STATE_COLORS = {"connected": "#2b8a3e", "connecting": "#e67700", "lost": "#c92a2a"}
# a node id or a key is long, one word: it wraps anywhere rather than push the table wide
# (a Modbus place wraps between its words)
_PLACE = {"opcua": "overflow-wrap:anywhere", "zenoh": "overflow-wrap:anywhere"}
_QUALITY_STYLES = {
    "good": "color:#2b8a3e",
    "bad": "color:#e67700;font-style:italic",
    "safe": "color:#868e96",
    "waiting": "color:#868e96;font-style:italic",
}
_QUALITY_WORDS = {
    "good": "as on the wire",
    "bad": "safe value: its device is lost",
    "safe": "safe value: the resource does not run",
    "waiting": "no value served yet",
}


@dataclass
class IoScreen:
    server: viser.GuiHtmlHandle
    devices: viser.GuiHtmlHandle
    source: viser.GuiDropdownHandle[str]
    points: viser.GuiHtmlHandle
    reading: CommandReading[p.IoReply] = field(
        default_factory=lambda: CommandReading(p.GetIo(), "its I/O")
    )
    shown: dict[str, str] = field(default_factory=dict)


def build(gui: viser.GuiApi) -> IoScreen:
    server = gui.add_html("")
    devices = gui.add_html("")
    source = gui.add_dropdown("Points of", (ALL_SOURCES,))
    points = gui.add_html("")
    return IoScreen(server, devices, source, points)


def refresh(
    screen: IoScreen,
    resource: str | None,
    status: p.Status | None,
    login_token: str | None,
    client_of: Callable[[str], ResourceClient],
) -> None:
    if resource is None or status is None:
        _show(screen, "server", screen.server, "<p>Select a resource.</p>")
        _show(screen, "devices", screen.devices, "")
        _show(screen, "points", screen.points, "")
        return
    _show(screen, "server", screen.server, render_server(status.io))
    _show(screen, "devices", screen.devices, render_devices(status.io))
    if status.io is None:
        _show(screen, "points", screen.points, "")
        return
    moment = int(time.monotonic() * READS_PER_S)  # read again twice a second
    screen.reading.ensure((resource, status.crc, login_token, moment), client_of)
    reply, error = screen.reading.current(resource)
    points = reply.points if reply is not None else []
    sources = (ALL_SOURCES, *sorted({x.source for x in points}, key=_source_order))
    if tuple(screen.source.options) != sources:
        screen.source.options = sources  # the choice kept while offered (events.py)
    chosen = screen.source.value
    shown = [x for x in points if chosen in (ALL_SOURCES, x.source)]
    table = render_points(shown, error) if reply is not None or error else _note("reading ...")
    _show(screen, "points", screen.points, table)


def _source_order(source: str) -> tuple[int, str]:
    return ({"server": 0, "OPC UA server": 1}.get(source, 2), source)


def _show(screen: IoScreen, name: str, handle: viser.GuiHtmlHandle, content: str) -> None:
    """Send HTML only when it changed."""
    if screen.shown.get(name) != content:
        handle.content = content
        screen.shown[name] = content


# ---- what the user reads (pure)


def _note(text: str, testid: str = "io-note") -> str:
    return f'<p data-testid="{testid}" style="{_GREY}">{html.escape(text)}</p>'


def _table(head: list[str], rows: list[str], testid: str) -> str:
    header = "".join(f'<th style="{_CELL};text-align:left">{h}</th>' for h in head)
    return (
        f'<table data-testid="{testid}" style="border-collapse:collapse;width:100%;'
        f'font-size:0.9em"><tr>{header}</tr>{"".join(rows)}</table>'
    )


def render_server(io: p.IoStatus | None) -> str:
    """A line per server of the resource's: Modbus TCP first, then OPC UA."""
    if io is None:
        return _note("This configuration has no field I/O (Modbus TCP, OPC UA, exchange).")
    if not io.servers:
        return _note(
            "The resource serves no field I/O (Modbus TCP serve = false, no OPC UA, "
            "no exchange publication)."
        )
    return "".join(_server_line(server) for server in io.servers)


_PROTOCOLS = {
    "modbus": "Modbus TCP server",
    "opcua": "OPC UA server",
    "zenoh": "Exchange publication",
}


def _server_line(server: p.ServerStatus) -> str:
    name = _PROTOCOLS.get(server.protocol, server.protocol)
    opening = f'<p data-testid="io-server" data-protocol="{html.escape(server.protocol)}">'
    if not server.listening:
        why = html.escape(server.error or "not listening")
        return (
            f'{opening}<b>{name}</b> <span style="color:#c92a2a">does not listen: {why}</span></p>'
        )
    if server.protocol == "zenoh":
        return (
            f"{opening}<b>{name}</b> on <code>{html.escape(server.host)}</code> · "
            f"{counted(server.requests, 'message')} put</p>"
        )
    if server.protocol == "opcua":
        where = f"opc.tcp://{html.escape(server.host)}:{server.port}"
        return (
            f"{opening}<b>{name}</b> listening on <code>{where}</code> · "
            f"{counted(server.sessions, 'session')} · {counted(server.requests, 'request')} · "
            f"{counted(server.exceptions, 'refusal')} · {counted(server.writes, 'write')} taken"
            f'<br><span style="{_GREY}">certificate SHA-1 '
            f"<code>{html.escape(server.certificate)}</code></span></p>"
        )
    return (
        f"{opening}<b>{name}</b> listening on "
        f"<code>{html.escape(server.host)}:{server.port}</code> · "
        f"{counted(server.requests, 'request')} · "
        f"{counted(server.exceptions, 'exception response')} · "
        f"{counted(server.writes, 'write')} taken</p>"
    )


def render_devices(io: p.IoStatus | None) -> str:
    if io is None:
        return ""
    if not io.devices:
        return _note("No remote I/O devices are configured.")
    rows = []
    for device in io.devices:
        color = _STATE_COLORS.get(device.state, "#495057")
        trip = f"{device.round_trip_ms:.1f} ms" if device.state == "connected" else ""
        error = device.last_error or ""
        # what the state says more (its round trip, its last error) under it: the table
        # fits the side panel (1400x900) without scrolling sideways
        below = _below(trip) + (
            f'<div style="color:#c92a2a;overflow-wrap:anywhere">{html.escape(error)}</div>'
            if error
            else ""
        )
        rows.append(
            f'<tr data-device="{html.escape(device.name)}">'
            f'<td style="{_CELL}"><b>{html.escape(device.name)}</b>'
            f"{_below(_device_address(device), escaped=True)}</td>"
            f'<td style="{_CELL}"><span style="color:{color};font-weight:600" data-state>'
            f"{html.escape(device.state)}</span>{below}</td>"
            f'<td style="{_CELL};text-align:right">{device.requests}</td>'
            f'<td style="{_CELL};text-align:right">{device.failures}</td></tr>'
        )
    head = ["Device", "State", "Requests", "Failures"]
    return _table(head, rows, "io-devices")


def _below(text: str, escaped: bool = False) -> str:
    """A cell's second line: what completes its first, smaller and grey."""
    if not text:
        return ""
    shown = text if escaped else html.escape(text)
    return f'<div style="{_GREY};font-size:0.9em;overflow-wrap:anywhere">{shown}</div>'


def _device_address(device: p.DeviceStatus) -> str:
    if device.protocol in ("opcua", "zenoh"):  # an endpoint URL, a publication's key
        return f"<code>{html.escape(device.host)}</code>"
    return f"<code>{html.escape(device.host)}:{device.port}</code> unit {device.unit_id}"


def render_points(points: list[p.IoPoint], error: str) -> str:
    if error:
        return f'<p data-testid="io-error" style="color:#c92a2a">{html.escape(error)}</p>'
    if not points:
        return _note("No mapped points.")
    rows = []
    for point in points[:MAX_ROWS]:
        style = _QUALITY_STYLES.get(point.quality, "")
        value = format_for_display(point.value, point.type)
        # a Modbus table's name reads as words; a node id or a variable keeps its _
        place = html.escape(
            point.place.replace("_", " ") if point.protocol == "modbus" else point.place
        )
        rows.append(
            f'<tr><td style="{_CELL}">{html.escape(point.source)}</td>'
            f'<td style="{_CELL}">{html.escape(point.variable)}'
            f"{_below(point.type)}</td>"
            f'<td style="{_CELL};text-align:right;font-family:monospace;{style}" '
            f'data-point="{html.escape(point.variable)}" data-quality="{point.quality}" '
            f'title="{_QUALITY_WORDS.get(point.quality, "")}">{html.escape(value)}</td>'
            f'<td style="{_CELL}" data-writable>{_writable(point)}</td>'
            f'<td style="{_CELL}"><code>{html.escape(point.location)}</code>'
            f'<div style="{_GREY};font-size:0.9em;{_PLACE.get(point.protocol, "")}">'
            f"<code>{place}</code></div></td></tr>"
        )
    more = len(points) - MAX_ROWS
    count = _note(f"the first {MAX_ROWS} of {len(points)} points shown") if more > 0 else ""
    # the type under the variable, the place on the wire under the location: five columns
    # fit the side panel at 1400x900
    head = ["Source", "Variable", "Value", "Writable", "Location"]
    return count + _table(head, rows, "io-points") + legend()


def _writable(point: p.IoPoint) -> str:
    """Whether a client may write a served point; a remote device's points are the
    resource's own to read and write there."""
    if point.protocol == "zenoh":  # the exchange writes it, or it goes out to others
        return f'<span style="{_GREY}">no (exchange)</span>'
    if point.source not in ("server", "OPC UA server"):
        return f'<span style="{_GREY}">no (device)</span>'
    return "yes" if point.writable else "no"


def legend() -> str:
    items = " · ".join(
        f'<span style="{_QUALITY_STYLES[q]};font-weight:600">{q}</span> {_QUALITY_WORDS[q]}'
        for q in ("good", "bad", "safe")
    )
    return f'<div style="{_GREY};font-size:0.85em;padding:4px 0">{items}</div>'


class Io(Screen):
    name = "I/O"
    icon = viser.Icon.PLUG_CONNECTED

    def __init__(self, work: Work) -> None:
        super().__init__(work)
        self.screen = build(work.gui)

    def refresh(self, now: Now) -> None:
        refresh(self.screen, now.resource, now.status, now.token, self.work.client_of)
