"""The online test screen: the resource's state, configuration CRC and programs, Start /
Stop / Step, and an OLT field per variable with its live value and quality. Values are
shown as one HTML table per browser, which costs the browser far less than one input
widget per variable."""

from __future__ import annotations

import html
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import viser

from runtime.contract import protocol as p
from runtime.contract.values import format_value

COMMANDS: tuple[tuple[str, type[p.Command[p.StatusReply]]], ...] = (
    ("Start", p.Start),
    ("Stop", p.Stop),
    ("Step", p.Step),
)


@dataclass
class OnlineTestView:
    """One browser's handles on this screen."""

    status: viser.GuiHtmlHandle
    table: viser.GuiHtmlHandle
    shown_version: int = -1


def build(
    gui: viser.GuiApi, resource: str, act: Callable[[p.Command[p.StatusReply]], None]
) -> OnlineTestView:
    gui.add_markdown(f"### Resource {html.escape(resource)}")
    status = gui.add_html("")
    with gui.add_folder("Commands"):
        for label, command in COMMANDS:
            _button(gui, label, command, act)
    with gui.add_folder("Online test (OLT)"):
        table = gui.add_html("")
    return OnlineTestView(status, table)


def _button(
    gui: viser.GuiApi,
    label: str,
    command: type[p.Command[p.StatusReply]],
    act: Callable[[p.Command[p.StatusReply]], None],
) -> None:
    def clicked(_event: viser.GuiEvent[viser.GuiButtonHandle]) -> None:
        act(command())

    gui.add_button(label).on_click(clicked)


_CELL = "padding:2px 8px;border-bottom:1px solid #e5e5e5"


def render_status(status: p.Status | None, cycle: int) -> str:
    state = html.escape(status.state if status is not None else "unknown")
    crc = html.escape((status.crc if status is not None else None) or "-")
    color = {"RUN": "#2b8a3e"}.get(state, "#c92a2a" if "ERROR" in state else "#e67700")
    rows = [
        ("State", f'<b data-testid="resource-state" style="color:{color}">{state}</b>'),
        ("Configuration CRC", f'<code data-testid="resource-crc">{crc}</code>'),
        ("Cycle", f'<span data-testid="resource-cycle">{cycle}</span>'),
    ]
    for program in status.programs if status is not None else []:
        name = html.escape(program.name)
        text = html.escape(program.state)
        if program.error:
            text += f" ({html.escape(program.error)})"
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
