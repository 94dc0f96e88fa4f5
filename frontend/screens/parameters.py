"""The Parameters screen: the resource's and each program's parameters as the resource holds
them (`parameters`), in the parameter table of docs/parameters.md with value, range and
whether it changes online; and an editor for one parameter at a time. Only the parameters
the table marks online are editable (with Allow Online Settings ON, and Allow Online
Settings itself only by an Administrator); the others are disabled with the reason. A new
value is checked here against its type, range and the rules between the parameters before
it is sent, and the change is confirmed with the old and the new value and a warning: the
controller cannot judge whether the value suits the plant. The resource checks it again."""

from __future__ import annotations

import dataclasses
import html
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import viser

from backend.engineering.resource_client import ResourceClient
from frontend.command_reading import CommandReading
from frontend.permissions import Allowed
from frontend.screen_registry import Now, Screen, Work
from frontend.screens import events
from runtime.contract import protocol as p
from runtime.contract.artifact import ProgramConfig, ResourceConfig
from runtime.contract.parameters import (
    PROGRAM_BY_NAME,
    PROGRAM_PARAMETERS,
    RESOURCE_BY_NAME,
    RESOURCE_PARAMETERS,
    ParameterError,
    ParameterSpec,
    resource_consistency,
)

# the names of spec section 6, as SILworX shows them
LABELS = {
    "safety_time_ms": "Safety Time",
    "watchdog_ms": "Watchdog Time",
    "target_cycle_ms": "Target Cycle Time",
    "target_cycle_mode": "Target Cycle Time Mode",
    "multitasking_mode": "Multitasking Mode",
    "com_slice_ms": "Max. Com. Time Slice",
    "allow_online_settings": "Allow Online Settings",
    "autostart": "Autostart",
    "start_allowed": "Start Allowed",
    "load_allowed": "Load Allowed",
    "reload_allowed": "Reload Allowed",
    "global_forcing_allowed": "Global Forcing Allowed",
    "global_force_timeout_reaction": "Global Force Timeout Reaction",
    "safety_operation": "Safety Operation",
    "program_id": "Program ID",
    "priority": "Priority",
    "max_duration_us": "Max. Duration for Each Cycle",
    "max_cycles": "Maximum Number of Cycles",
    "freeze_allowed": "Freeze Allowed",
    "local_forcing_allowed": "Local Forcing Allowed",
    "local_force_timeout_reaction": "Local Force Timeout Reaction",
    "safety_related": "Safety-related",
}
RULES = {  # the rules between parameters, beside the range they narrow
    "watchdog_ms": "at most ½ Safety Time",
    "target_cycle_ms": "at most the Watchdog Time; 0: none",
    "max_duration_us": "0: to its end each cycle",
}
WARNING = (
    "The controller checks only the range and the rules between its parameters; it cannot "
    "tell whether the new value suits the plant. A watchdog or cycle time that does not "
    "fit the process safety time can leave the process unprotected, or trip the resource "
    "into ERROR STOP and take its outputs to their safe values. Change a running safety "
    "controller only when you have checked the value against the plant."
)
NO_DOWNLOAD = "changes only with a download (not changeable online)"
_CELL = "padding:2px 8px;border-bottom:1px solid #e9ecef;line-height:1.25"
_GREY = "color:#868e96"
# the same columns in every table, so that the resource's and the programs' line up
_COLUMNS = "".join(f'<col style="width:{w}">' for w in ("32%", "14%", "39%", "15%"))


def unit(name: str) -> str:
    return "ms" if name.endswith("_ms") else "µs" if name.endswith("_us") else ""


def show(value: Any, name: str) -> str:
    """A parameter value as the table shows it: ON/OFF, a number with its unit, a word."""
    if isinstance(value, bool):
        return "ON" if value else "OFF"
    return f"{value} {unit(name)}".strip()


def value_range(spec: ParameterSpec) -> str:
    if spec.kind is bool:
        text = "ON / OFF"
    elif spec.choices:
        text = " | ".join(spec.choices)
    else:
        text = f"{spec.low}..{spec.high} {unit(spec.name)}".strip()
    rule = RULES.get(spec.name)
    return f"{text}; {rule}" if rule else text


def online_text(spec: ParameterSpec) -> str:
    if not spec.online:
        return "no (download)"
    return "yes (Administrator)" if spec.administrator else "yes"


# ---- checking a new value before it is sent


def parse_value(spec: ParameterSpec, text: str) -> bool | int | str:
    """What the user typed as a value of the parameter's type; ParameterError says why not.
    A number may carry the parameter's unit ("300 ms"); a switch is ON/OFF or TRUE/FALSE."""
    word = text.strip()
    if spec.kind is bool:
        if word.upper() in ("ON", "TRUE"):
            return True
        if word.upper() in ("OFF", "FALSE"):
            return False
        raise ParameterError(f"{LABELS[spec.name]} is ON or OFF, not {word!r}")
    if spec.kind is int:
        number = word.removesuffix(unit(spec.name)).strip() if unit(spec.name) else word
        try:
            return int(number, 10)
        except ValueError:
            raise ParameterError(
                f"{LABELS[spec.name]} is a whole number of {unit(spec.name) or 'units'}, "
                f"not {word!r}"
            ) from None
    return word


def check_change(
    name: str, text: str, resource: ResourceConfig, programs: list[ProgramConfig]
) -> bool | int | str:
    """The new value of resource parameter `name` if the resource would take it (the same
    checks as runtime/online_parameters.py, from the same table); ParameterError if not."""
    spec = RESOURCE_BY_NAME[name]
    value: bool | int | str = spec.check(parse_value(spec, text))
    if value == getattr(resource, name):
        raise ParameterError(f"{LABELS[name]} is {show(value, name)} already")
    changed: dict[str, Any] = {**dataclasses.asdict(resource), name: value}
    problems = resource_consistency(changed)
    if problems:
        raise ParameterError(problems[0])
    sliced = sum(x.max_duration_us for x in programs)
    if sliced > changed["watchdog_ms"] * 1000:
        raise ParameterError(f"the programs' time slices ({sliced} µs) exceed that watchdog")
    return value


# ---- the screen

Change = Callable[[str, str, p.Command[p.StatusReply], Callable[[], None]], None]


@dataclass
class ParametersScreen:
    header: viser.GuiHtmlHandle
    table: viser.GuiHtmlHandle
    parameter: viser.GuiDropdownHandle[str]
    info: viser.GuiHtmlHandle  # the chosen parameter's name, value and range
    text: viser.GuiTextHandle
    choice: viser.GuiDropdownHandle[str]
    error: viser.GuiHtmlHandle
    set_button: viser.GuiButtonHandle
    reason: viser.GuiHtmlHandle
    source: CommandReading[p.ParametersReply] = field(
        default_factory=lambda: CommandReading(p.GetParameters(), "its parameters")
    )
    resource: str | None = None
    rendered: p.ParametersReply | None = None  # the reading the table shows
    state: str = ""  # of the resource, for the confirmation
    crc: str = ""
    shown: dict[str, str] = field(default_factory=dict)  # what each html handle holds
    prefilled: tuple[str, str] = ("", "")  # (parameter, value) put into the field
    names: dict[str, str] = field(default_factory=dict)  # picker's option -> parameter


def editable_names(programs: list[ProgramConfig]) -> tuple[str, ...]:
    """The editor's choice: the online parameters first, then the others (disabled with
    the reason), then the programs' as `Program / name`."""
    online = [x.name for x in RESOURCE_PARAMETERS if x.online]
    others = [x.name for x in RESOURCE_PARAMETERS if not x.online]
    in_programs = [f"{x.name} / {spec.name}" for x in programs for spec in PROGRAM_PARAMETERS]
    return (*online, *others, *in_programs)


def option(name: str) -> str:
    """How the picker offers a parameter: its name as docs/parameters.md gives it, with its
    unit and key ("Watchdog Time, ms (watchdog_ms)"; "TankControl / Priority (priority)")."""
    program, _, key = name.rpartition(" / ")
    where = f"{program} / " if program else ""
    measured = f", {unit(key)}" if unit(key) else ""
    return f"{where}{LABELS[key]}{measured} ({key})"


def chosen(screen: ParametersScreen) -> str:
    """The parameter picked (`watchdog_ms`, `TankControl / priority`)."""
    return screen.names.get(screen.parameter.value, screen.parameter.value)


def build(gui: viser.GuiApi, change: Change) -> ParametersScreen:
    """`change(title, question, command, then)` asks `question`, sends `command` to the
    selected resource and calls `then()` after the answer, whatever it was."""
    header = gui.add_html("")
    # the editor above the tables: the tables are long, the editor is what one works with
    with gui.add_folder("Change a parameter online"):
        names = editable_names([])  # the programs' are offered once read
        parameter = gui.add_dropdown("Parameter", tuple(map(option, names)))
        info = gui.add_html("")
        text = gui.add_text("New value", "")
        choice = gui.add_dropdown("New setting", ("-",), visible=False)
        error = gui.add_html("")
        set_button = gui.add_button("Set parameter", color="blue", disabled=True)
        reason = gui.add_html("")
    table = gui.add_html("")
    screen = ParametersScreen(
        header, table, parameter, info, text, choice, error, set_button, reason
    )
    screen.names = {option(name): name for name in names}
    set_button.on_click(lambda _: _clicked(screen, change))
    text.on_update(lambda _: _check_typed(screen))  # as the user types
    choice.on_update(lambda _: _check_typed(screen))
    return screen


def _check_typed(screen: ParametersScreen) -> None:
    """Say what is wrong with the value in the field as it is typed (what the field was
    filled with is the value now: nothing to say)."""
    name, resource = chosen(screen), screen.resource
    spec = RESOURCE_BY_NAME.get(name)
    reply, _ = screen.source.current(resource) if resource is not None else (None, "")
    if spec is None or reply is None:
        return
    typed = _typed(screen, spec)
    wrong = ""
    if screen.prefilled != (name, typed):
        try:
            check_change(name, typed, reply.resource, reply.programs)
        except ParameterError as refused:
            wrong = str(refused)
    _show(screen, "error", _error_note(wrong) if wrong else "")


def _typed(screen: ParametersScreen, spec: ParameterSpec) -> str:
    return screen.text.value if not (spec.kind is bool or spec.choices) else screen.choice.value


def _clicked(screen: ParametersScreen, change: Change) -> None:
    name = chosen(screen)
    resource = screen.resource
    reply, _ = screen.source.current(resource) if resource is not None else (None, "")
    spec = RESOURCE_BY_NAME.get(name)
    if reply is None or spec is None or resource is None:
        return
    try:
        value = check_change(name, _typed(screen, spec), reply.resource, reply.programs)
    except ParameterError as wrong:
        _show(screen, "error", _error_note(str(wrong)))
        return
    _show(screen, "error", "")
    old = getattr(reply.resource, name)
    running = ", at once, while it runs" if screen.state.startswith("RUN") else ""
    question = (
        f"Change {LABELS[name]} ({name}) of resource {resource} (configuration "
        f"{screen.crc or '-'}, {screen.state or 'state unknown'}) from {show(old, name)} to "
        f"{show(value, name)}{running}. {WARNING}"
    )
    change(f"Change {LABELS[name]}", question, p.SetParameter(name, value), screen.source.changed)


def _error_note(text: str) -> str:
    return f'<div data-testid="parameter-error" style="color:#c92a2a">{html.escape(text)}</div>'


def _show(screen: ParametersScreen, part: str, content: str) -> None:
    """Send an html handle's content only when it changed (ten refreshes a second)."""
    if screen.shown.get(part) != content:
        getattr(screen, part).content = content
        screen.shown[part] = content


def refresh(
    screen: ParametersScreen,
    resource: str | None,
    status: p.Status | None,
    login_token: str | None,
    client_of: Callable[[str], ResourceClient],
    allowed: Callable[[p.Command[Any]], Allowed],
    changed_elsewhere: int = 0,
) -> None:
    """`changed_elsewhere` goes up with every parameter change the resource reports (from
    any client): then the parameters are read again."""
    if resource != screen.resource:
        screen.resource = resource
        _show(screen, "error", "")
    screen.state = status.state if status is not None else ""
    screen.crc = status.crc or "" if status is not None else ""
    if resource is None:
        _show(screen, "header", "<p>Select a resource.</p>")
        _show(screen, "table", "")
        screen.rendered = None
        reply: p.ParametersReply | None = None
    else:
        crc = status.crc or "" if status is not None else ""
        key = (resource, crc, login_token, screen.source.changes, changed_elsewhere)
        screen.source.ensure(key, client_of)
        reply, error = screen.source.current(resource)
        _show(screen, "header", render_header(resource, status, reply, error))
        if reply is not screen.rendered:  # the same reading renders the same table
            screen.rendered = reply
            _show(screen, "table", render(reply) if reply is not None else "")
    names = editable_names(reply.programs if reply is not None else [])
    options = tuple(map(option, names))
    if tuple(screen.parameter.options) != options:
        screen.names = dict(zip(options, names, strict=True))
        screen.parameter.options = options
    name = chosen(screen)
    spec = RESOURCE_BY_NAME.get(name)
    _editor(screen, name, spec, reply)
    _show(screen, "info", render_info(name, reply))
    editable = verdict(name, spec, reply, allowed)
    screen.set_button.disabled = not editable.ok
    screen.text.disabled = screen.choice.disabled = not editable.ok
    screen.set_button.hint = editable.reason or None
    note = (
        f'<div data-testid="parameter-disabled" style="{_GREY}">Disabled: '
        f"{html.escape(editable.reason)}</div>"
        if editable.reason
        else ""
    )
    _show(screen, "reason", note)


def _editor(
    screen: ParametersScreen,
    name: str,
    spec: ParameterSpec | None,
    reply: p.ParametersReply | None,
) -> None:
    """The field for the chosen parameter, filled with its value when the parameter or its
    value changes (not while the user types)."""
    chooses = spec is not None and (spec.kind is bool or bool(spec.choices))
    if screen.choice.visible != chooses:
        screen.choice.visible = chooses
        screen.text.visible = not chooses
    if reply is None:
        return
    current = _current(name, reply)
    if screen.prefilled == (name, current):
        return
    if screen.prefilled[0] != name:
        _show(screen, "error", "")
    screen.prefilled = (name, current)
    if spec is not None and chooses:
        options = ("ON", "OFF") if spec.kind is bool else spec.choices
        if tuple(screen.choice.options) != options:
            screen.choice.options = options
        screen.choice.value = current  # type: ignore[misc]  # (setter apart from getter)
    else:
        screen.text.value = current  # type: ignore[misc]


def _current(name: str, reply: p.ParametersReply) -> str:
    """The shown value of a resource parameter or of `Program / name`."""
    if name in RESOURCE_BY_NAME:
        return show(getattr(reply.resource, name), name)
    program, _, parameter = name.partition(" / ")
    config = next((x for x in reply.programs if x.name == program), None)
    return show(getattr(config, parameter), parameter) if config is not None else ""


def verdict(
    name: str,
    spec: ParameterSpec | None,
    reply: p.ParametersReply | None,
    allowed: Callable[[p.Command[Any]], Allowed],
) -> Allowed:
    if reply is None:
        return Allowed(False, "the parameters have not been read")
    if spec is None:
        return Allowed(False, f"program parameters ({name}) change only with a download")
    if not spec.online:
        return Allowed(False, f"{LABELS[name]} {NO_DOWNLOAD}")
    verdict = allowed(p.SetParameter(name, getattr(reply.resource, name)))
    if not verdict.ok:
        return verdict
    if not spec.administrator and not reply.resource.allow_online_settings:
        return Allowed(False, "Allow Online Settings is OFF: no parameter changes online")
    return Allowed(True)


def render_info(name: str, reply: p.ParametersReply | None) -> str:
    """Beside the chosen parameter: its name, its value now and what it may be."""
    program, _, parameter = name.rpartition(" / ")
    spec = RESOURCE_BY_NAME.get(name) or PROGRAM_BY_NAME.get(parameter)
    if spec is None or reply is None:
        return ""
    where = f"{program}: " if program else ""
    text = f"{where}{LABELS[spec.name]} is {_current(name, reply)} (range {value_range(spec)})"
    return (
        f'<div data-testid="parameter-info" style="{_GREY};margin:0 0 2px 8px">'
        f"{html.escape(text)}</div>"
    )


def render_header(
    resource: str, status: p.Status | None, reply: p.ParametersReply | None, error: str
) -> str:
    if reply is None:
        text = error or "reading the parameters ..."
        return f'<p data-testid="parameters-note" style="{_GREY}">{html.escape(text)}</p>'
    state = f"{status.state}, configuration {status.crc or '-'}" if status is not None else ""
    note = ""
    if not reply.resource.allow_online_settings:
        note = (
            '<div style="color:#e67700">Allow Online Settings is OFF: the parameters change '
            "only with a download.</div>"
        )
    return (
        f'<div style="margin-bottom:4px"><b>{html.escape(resource)}</b> '
        f'<span style="{_GREY}">{html.escape(state)}</span></div>{note}'
    )


def render(reply: p.ParametersReply) -> str:
    """The parameter table: the resource's, then each program's."""
    parts = [_table("Resource", "resource", RESOURCE_PARAMETERS, reply.resource)]
    for program in reply.programs:
        title = f"Program {program.name} ({program.pou})"
        parts.append(_table(title, program.name, PROGRAM_PARAMETERS, program))
    return "".join(parts)


def _table(title: str, prefix: str, specs: tuple[ParameterSpec, ...], config: Any) -> str:
    head = "".join(
        f'<th style="{_CELL};text-align:left">{name}</th>'
        for name in ("Parameter", "Value", "Range", "Online")
    )
    rows = []
    for spec in specs:
        value = show(getattr(config, spec.name), spec.name)
        where = html.escape(f"{prefix}.{spec.name}")
        online = online_text(spec)
        colour = "#2b8a3e" if spec.online else "#868e96"
        rows.append(
            f'<tr><td style="{_CELL}">{LABELS[spec.name]}<br><span style="{_GREY};'
            f'font-family:monospace;font-size:0.9em">{spec.name}</span></td>'
            f'<td style="{_CELL};font-family:monospace;font-weight:600;white-space:nowrap" '
            f'data-param="{where}">{html.escape(value)}</td>'
            f'<td style="{_CELL};overflow-wrap:anywhere">{html.escape(value_range(spec))}</td>'
            f'<td style="{_CELL};color:{colour}" data-online="{where}">'
            f"{online}</td></tr>"
        )
    return (
        f'<div style="font-weight:600;margin:8px 0 2px">{html.escape(title)}</div>'
        f'<table data-testid="parameters-{html.escape(prefix)}" style="font-size:0.85em;'
        f'border-collapse:collapse;width:100%;table-layout:fixed">{_COLUMNS}<tr>{head}</tr>'
        f"{''.join(rows)}</table>"
    )


class Parameters(Screen):
    name = "Parameters"
    icon = viser.Icon.ADJUSTMENTS

    def __init__(self, work: Work) -> None:
        super().__init__(work)
        self.screen = build(work.gui, work.change)

    def refresh(self, now: Now) -> None:
        log = self.work.screen(events.Events)  # a parameter event: changed by someone else
        changed = events.live_count(log.screen, now.resource, "parameter") if log else 0
        refresh(
            self.screen,
            now.resource,
            now.status,
            now.token,
            self.work.client_of,
            self.work.allowed,
            changed,
        )
