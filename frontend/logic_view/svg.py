"""What every live drawing shares: the qualities' colours (those of the Online test), a
value as text, and the attributes that make a drawn value clickable (the page reports a
click on an element with `data-logic-var`, frontend/page_clicks.py)."""

from __future__ import annotations

import html
from typing import Any

from runtime.contract.values import format_for_display

ACTIVE = "#2f9e44"  # TRUE, an active step, power flow
ACTIVE_FILL = "#d3f9d8"
IDLE = "#495057"
MUTED = "#adb5bd"
FORCED = "#c92a2a"  # as the Online test marks a forced value


def escape(text: str) -> str:
    return html.escape(text, quote=True)


def shown(
    path: str, values: dict[str, Any], types: dict[str, str], quality: dict[str, str]
) -> tuple[str, str]:
    """(text, quality) of a variable's value: "…"/"waiting" before its first value."""
    if path not in values or path not in types:
        return "…", "waiting"
    return format_for_display(values[path], types[path]), quality.get(path, "live")


def clickable(path: str) -> str:
    """The attributes of a drawn value that a click chooses for writing or forcing."""
    return f'data-logic-var="{escape(path)}" style="cursor:pointer"'


def value_color(text: str, how: str) -> str:
    if how == "forced":
        return FORCED
    if how in ("stale", "waiting", "deleted", "bad"):
        return MUTED
    return ACTIVE if text == "TRUE" else IDLE
