"""The status bar: where this browser is and what it acts on. Router, user and level,
resource, its CRC, state and cycle, whether anything is forced, and whether its access is
open (no accounts)."""

from __future__ import annotations

import html

from runtime.contract import protocol as p

_STATE_COLORS = {"RUN": "#2b8a3e"}


def render(
    router: str, user: str, level: str, resource: str | None, status: p.Status | None
) -> str:
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
