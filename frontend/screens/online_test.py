"""The Online test screen: an OLT field per variable of the selected resource with its
live value and quality, from this browser's own watch set. Values are shown as one HTML
table per browser, which costs the browser far less than one input widget per variable."""

from __future__ import annotations

import html
from dataclasses import dataclass
from typing import Any

import viser

from frontend.resource_feed import ResourceFeed
from runtime.contract.values import format_for_display


@dataclass
class OnlineTestScreen:
    table: viser.GuiHtmlHandle
    shown_version: int = -1


def build(gui: viser.GuiApi) -> OnlineTestScreen:
    return OnlineTestScreen(gui.add_html(""))


def refresh(screen: OnlineTestScreen, feed: ResourceFeed | None) -> None:
    if feed is None:
        screen.table.content = "<p>Select a resource you are logged in to.</p>"
        screen.shown_version = -1
        return
    latest = feed.latest
    with latest.lock:
        version, values, types, quality = (
            latest.version,
            latest.values,
            latest.types,
            latest.quality,
        )
    if version != screen.shown_version:
        screen.table.content = render_values(values, types, quality)
        screen.shown_version = version


_CELL = "padding:2px 8px;border-bottom:1px solid #e5e5e5"


_QUALITY_COLORS = {"forced": "#c92a2a", "stale": "#868e96"}


def render_values(
    values: dict[str, Any], types: dict[str, str], quality: dict[str, str] | None = None
) -> str:
    rows = []
    for path in sorted(values):
        type_name = types.get(path, "")
        shown = html.escape(format_for_display(values[path], type_name))
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
