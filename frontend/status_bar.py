"""The status bar: where this browser is and what it acts on. Router, user and level,
resource, its CRC, state and cycle, whether anything is forced, and whether its access is
open (no accounts)."""

from __future__ import annotations

import html
import time

from frontend.resource_feed import Reach
from runtime.contract import protocol as p

_STATE_COLORS = {"RUN": "#2b8a3e"}


def render(
    router: str,
    user: str,
    level: str,
    resource: str | None,
    status: p.Status | None,
    reach: Reach | None = None,
) -> str:
    """`reach`: whether the resource's runtime is on the bus now, and when it last was not
    (the values shown while it is away are the last it sent)."""
    items = [
        ("Router", html.escape(router)),
        ("User", f"{html.escape(user)} ({html.escape(level)})"),
        ("Resource", html.escape(resource or "-")),
    ]
    if status is None:
        items.append(("State", '<span data-testid="resource-state">not logged in</span>'))
    else:
        state = html.escape(status.state)
        color = _STATE_COLORS.get(status.state, "#c92a2a" if "ERROR" in state else "#e67700")
        items += [
            ("State", f'<b data-testid="resource-state" style="color:{color}">{state}</b>'),
            ("CRC", f'<code data-testid="resource-crc">{html.escape(status.crc or "-")}</code>'),
            ("Cycle", f'<span data-testid="resource-cycle">{status.cycle}</span>'),
        ]
        if status.forcing:
            items.append(("Forcing", '<b data-testid="forcing" style="color:#c92a2a">ACTIVE</b>'))
        if reach is not None and reach.away_since_ns is not None:
            since = _clock_time(reach.away_since_ns)
            items.append(
                (
                    "Reach",
                    '<b data-testid="resource-reach" style="color:#c92a2a">out of reach since '
                    f"{since}</b>: what is shown is what it last sent",
                )
            )
        elif reach is not None and reach.last_outage is not None:
            gone, back = reach.last_outage
            items.append(
                (
                    "Reach",
                    '<span data-testid="resource-reach" style="color:#e67700">out of reach '
                    f"{_clock_time(gone)} to {_clock_time(back)} ({(back - gone) / 1e9:.1f} s)"
                    "</span>: values and trends have a gap there; its events of that time "
                    "are in Events",
                )
            )
        if status.access == "open":
            items.append(("Access", '<b style="color:#e67700">open (no accounts)</b>'))
        elif status.access == "setup":  # no configuration: the first download commissions it
            items.append(("Access", '<b style="color:#e67700">setup secret (no configuration)</b>'))
    rows = "".join(
        f'<tr><td style="padding:1px 6px;color:#868e96">{name}</td>'
        f'<td style="padding:1px 6px">{value}</td></tr>'
        for name, value in items
    )
    return f'<table data-testid="statusbar" style="font-size:0.85em;width:100%">{rows}</table>'


def reach_banner(resource: str | None, reach: Reach | None) -> str:
    """A strip on top, seen from every tab, while the chosen resource is out of reach: what
    every screen shows of it meanwhile is what it last sent."""
    if resource is None or reach is None or reach.away_since_ns is None:
        return ""
    return (
        '<div data-testid="reach-banner" style="background:#e67700;color:white;'
        'font-weight:600;padding:6px 10px;border-radius:4px;margin:2px 0">'
        f"{html.escape(resource)} OUT OF REACH since {_clock_time(reach.away_since_ns)}: "
        "the values shown are the last it sent</div>"
    )


def _clock_time(ns: int) -> str:
    """A wall-clock time of this host, as the status bar shows it (hh:mm:ss)."""
    return time.strftime("%H:%M:%S", time.localtime(ns / 1e9))
