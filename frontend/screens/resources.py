"""The Resources screen: every resource on the router with the host it runs on, its state,
configuration CRC, cycle statistics and programs; and the commands of the selected
resource (Start, Stop, Cold start, Init; each program's Start and Stop), each confirmed,
each disabled with the reason when the user's levels do not allow it."""

from __future__ import annotations

import html
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import viser

from frontend.permissions import Allowed
from frontend.screen_registry import Now, Screen, Work
from frontend.state_rules import disabled_note, program_allows, resource_allows, state_words
from runtime.contract import protocol as p

COMMANDS: tuple[tuple[str, type[p.Command[p.StatusReply]], str], ...] = (
    ("Start", p.Start, "start the resource (RUN)"),
    ("Stop", p.Stop, "stop the resource: its outputs go to their safe values"),
    ("Cold start", p.ColdStart, "set every variable to its initial value (in STOP)"),
    ("Init", p.Init, "leave ERROR STOP for STOP (a cold start follows)"),
)
_CELL = "padding:3px 6px;border-bottom:1px solid #e9ecef;white-space:nowrap"
# a host name may be 253 characters: the cell shows its start, the tooltip all of it
_HOST_CELL = "max-width:12em;overflow:hidden;text-overflow:ellipsis"
STATE_COLORS = {"RUN": "#2b8a3e", "ERROR STOP": "#c92a2a"}


@dataclass
class ResourcesScreen:
    table: viser.GuiHtmlHandle
    buttons: dict[type[p.Command[p.StatusReply]], viser.GuiButtonHandle]
    program: viser.GuiDropdownHandle[str]
    program_buttons: dict[type[p.StartProgram | p.StopProgram], viser.GuiButtonHandle]
    reason: viser.GuiHtmlHandle
    shown: str = ""
    shown_reason: str = ""


def build(
    gui: viser.GuiApi,
    act: Callable[[str, p.Command[p.StatusReply], str], None],
    selected: Callable[[], str | None],
) -> ResourcesScreen:
    """`act(label, command, what)` asks the user and sends the command to `selected()`."""
    table = gui.add_html("")
    buttons: dict[type[p.Command[p.StatusReply]], viser.GuiButtonHandle] = {}
    with gui.add_folder("Commands of the selected resource"):
        for label, command, what in COMMANDS:
            button = gui.add_button(label, disabled=True)
            buttons[command] = button

            def clicked(
                _: Any, command: Any = command, label: str = label, what: str = what
            ) -> None:
                act(label, command(), what)

            button.on_click(clicked)
        program = gui.add_dropdown("Program", ("-",))
        program_buttons: dict[type[p.StartProgram | p.StopProgram], viser.GuiButtonHandle] = {}
        for label, kind in (("Start program", p.StartProgram), ("Stop program", p.StopProgram)):
            button = gui.add_button(label, disabled=True)
            program_buttons[kind] = button

            def program_clicked(_: Any, kind: Any = kind, label: str = label) -> None:
                name = program.value
                act(label, kind(name), f"{label.lower()} {name} of {selected()}")

            button.on_click(program_clicked)
        reason = gui.add_html("")
    return ResourcesScreen(table, buttons, program, program_buttons, reason)


def refresh(
    screen: ResourcesScreen,
    online: list[tuple[str, p.Status | None]],
    selected: str | None,
    allowed: Callable[[type[p.Command[Any]]], Allowed],
    away: bool = False,
) -> None:
    """`away`: the selected resource is out of reach, so no command can reach it."""
    page = render(online, selected)
    if page != screen.shown:
        screen.table.content = page
        screen.shown = page
    status = dict(online).get(selected) if selected is not None else None
    programs = tuple(x.name for x in status.programs) if status is not None else ()
    programs = programs or ("-",)  # a dropdown needs an option (no configuration: no program)
    if tuple(screen.program.options) != programs:
        screen.program.options = programs
    chosen = _program(status, screen.program.value)
    reasons: list[str] = []  # the levels' first, then each button's state's
    by_state: list[str] = []
    for command, button in [*screen.buttons.items(), *screen.program_buttons.items()]:
        verdict = allowed(command) if selected is not None else Allowed(False, "no resource")
        if away:
            verdict = Allowed(False, f"{selected} is out of reach")
        if verdict.reason and verdict.reason not in reasons:
            reasons.append(verdict.reason)
        if verdict.ok and status is not None:  # what the state allows
            verdict = (
                resource_allows(command, status)
                if command in screen.buttons
                else program_allows(command, status, chosen)
                if chosen is not None
                else Allowed(False, "choose a program")
            )
            if verdict.reason:
                by_state.append(f"{button.label}: {verdict.reason}")
        button.disabled = not verdict.ok
        button.hint = verdict.reason or None
    # a tooltip alone is missed (viser shows none on a disabled button): say it beside them
    note = disabled_note("commands-disabled", reasons + by_state)
    if note != screen.shown_reason:
        screen.reason.content = note
        screen.shown_reason = note


def _program(status: p.Status | None, name: str) -> p.ProgramStatus | None:
    programs = status.programs if status is not None else ()
    return next((x for x in programs if x.name == name), None)


def render(online: list[tuple[str, p.Status | None]], selected: str | None) -> str:
    head = "".join(
        f'<th style="{_CELL};text-align:left">{name}</th>'
        for name in ("Resource", "Host", "State", "CRC", "Cycle", "Last", "Min", "Max", "Mean",
                     "Jitter", "Overruns", "Programs")
    )  # fmt: skip
    rows = [_row(name, status, name == selected) for name, status in online]
    if not rows:
        rows = [f'<tr><td style="{_CELL}" colspan="12">No resource is online.</td></tr>']
    return (
        '<div style="overflow-x:auto"><table data-testid="resources" '
        f'style="font-size:0.85em;border-collapse:collapse"><tr>{head}</tr>{"".join(rows)}'
        "</table></div>"
    )


def _row(name: str, status: p.Status | None, selected: bool) -> str:
    weight = "font-weight:600;" if selected else ""
    cells = [
        f'<td style="{_CELL};{weight}" data-resource="{html.escape(name)}">{html.escape(name)}</td>'
    ]
    if status is None:
        note = "log in to the resource to see its state"
        return "".join(cells) + f'<td style="{_CELL};color:#868e96" colspan="11">{note}</td>'
    stats = status.stats
    color = STATE_COLORS.get(status.state, "#e67700")
    cells += [
        f'<td style="{_CELL};{_HOST_CELL}" data-host="{html.escape(name)}" '
        f'title="{html.escape(status.host or "")}">{html.escape(status.host or "-")}</td>',
        f'<td style="{_CELL};color:{color};font-weight:600" data-state="{html.escape(name)}">'
        f"{html.escape(state_words(status.state))}</td>",
        f'<td style="{_CELL};font-family:monospace">{html.escape(status.crc or "-")}</td>',
        f'<td style="{_CELL};text-align:right">{status.cycle}</td>',
        *(
            f'<td style="{_CELL};text-align:right">{value:.3f} ms</td>'
            for value in (
                stats.last_ms,
                stats.min_ms,
                stats.max_ms,
                stats.mean_ms,
                stats.jitter_max_ms,
            )
        ),
        f'<td style="{_CELL};text-align:right">{stats.overruns}</td>',
        f'<td style="{_CELL};white-space:normal;min-width:9em">{_programs(status)}</td>',
    ]
    return f"<tr>{''.join(cells)}</tr>"


def _programs(status: p.Status) -> str:
    return "<br>".join(  # one a line: the table stays within the work area
        f'<span data-program="{html.escape(x.name)}">{html.escape(x.name)}: '
        f"{html.escape(state_words(x.state))}</span>"
        for x in status.programs
    )


class Resources(Screen):
    name = "Resources"
    icon = viser.Icon.SERVER

    def __init__(self, work: Work) -> None:
        super().__init__(work)
        self.screen = build(work.gui, work.confirm, work.selected)

    def refresh(self, now: Now) -> None:
        directory = dict(now.directory)
        if now.resource is not None and now.status is not None and not now.away:
            directory[now.resource] = now.status  # what this browser's login verified
        refresh(self.screen, list(directory.items()), now.resource, self.work.allowed, now.away)
