"""Writing and forcing one value from the Online test: the variable (its type, current value
and quality shown as it is typed), the new value as an ST literal of its type (checked
with the compiler's literal rules at the field, before anything is sent), **Write** (once)
and **Force** (prepare its force value), each confirmed with the old and the new value."""

from __future__ import annotations

import html
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import viser

from backend.engineering.literals import LiteralError, parse_literal
from frontend.forcing_feed import ForcingSnapshot
from frontend.permissions import Allowed
from frontend.resource_feed import ResourceFeed, latest_values
from frontend.screens.forcing import Run, configured, is_started, level_name, level_of
from runtime.contract import protocol as p
from runtime.contract.values import format_for_display

MAX_MATCHES = 6
_GREY = "color:#868e96"
_LINE = "font-size:0.875em;padding:2px 8px"  # a line under a field, as small as its label
_RED = "#c92a2a"


@dataclass(frozen=True)
class Edit:
    """What the two fields mean now."""

    path: str | None  # the variable as the resource names it; None: no such variable
    type_name: str = ""
    value: Any = None
    variable_problem: str = ""
    value_problem: str = ""
    matches: tuple[str, ...] = ()  # paths that contain what was typed


@dataclass
class ValueEditScreen:
    variable: viser.GuiTextHandle
    info: viser.GuiHtmlHandle
    new_value: viser.GuiTextHandle
    error: viser.GuiHtmlHandle
    write: viser.GuiButtonHandle
    force: viser.GuiButtonHandle
    reason: viser.GuiHtmlHandle
    # what the last refresh saw, for the buttons' callbacks
    status: p.Status | None = None
    snapshot: ForcingSnapshot | None = None
    types: dict[str, str] | None = None
    values: dict[str, Any] | None = None
    shown: tuple[str, str, str] = ("", "", "")
    # the fields as last read: read again only when they or the variables change
    read: tuple[str, str, dict[str, str], Edit] | None = None


def build(gui: viser.GuiApi, run: Run) -> ValueEditScreen:
    with gui.add_folder("Write or force a value"):
        variable = gui.add_text(
            "Variable",
            "",
            hint="the variable's path, e.g. TankControl.level, or click its row in the table",
        )
        info = gui.add_html("")
        new_value = gui.add_text(
            "New value", "", hint="an ST literal of the variable's type: TRUE, 42, -3.5, T#2s"
        )
        error = gui.add_html("")
        write = gui.add_button("Write", disabled=True)
        force = gui.add_button("Force", color="red", disabled=True)
        reason = gui.add_html("")
    screen = ValueEditScreen(variable, info, new_value, error, write, force, reason)
    write.on_click(lambda _: _write(screen, run))
    force.on_click(lambda _: _force(screen, run))
    return screen


def choose(screen: ValueEditScreen, path: str) -> None:
    """Put a variable into the field (for a click on a row of the Online test table)."""
    screen.variable.value = path  # type: ignore[misc]  # viser's setter, see workspace.py


def read_edit(variable: str, literal: str, types: dict[str, str]) -> Edit:
    typed = variable.strip()
    if not typed:
        return Edit(None, variable_problem="choose a variable")
    by_upper = {path.upper(): path for path in types}  # ST names are case-insensitive
    path = by_upper.get(typed.upper())
    if path is None:
        wanted = typed.upper()
        matches = tuple(x for x in sorted(types) if wanted in x.upper())[:MAX_MATCHES]
        return Edit(None, variable_problem=f"no variable {typed}", matches=matches)
    type_name = types[path]
    if not literal.strip():
        return Edit(path, type_name, value_problem="type the new value")
    try:
        value = parse_literal(literal, type_name)
    except LiteralError as exc:
        return Edit(path, type_name, value_problem=str(exc))
    return Edit(path, type_name, value)


def _current(screen: ValueEditScreen, edit: Edit) -> str:
    values = screen.values or {}
    if edit.path is None or edit.path not in values:
        return "(unknown)"
    return format_for_display(values[edit.path], edit.type_name)


def _write(screen: ValueEditScreen, run: Run) -> None:
    edit = read_edit(screen.variable.value, screen.new_value.value, screen.types or {})
    if edit.path is None or edit.value_problem:  # said at the fields; nothing is sent
        return
    old, new = _current(screen, edit), format_for_display(edit.value, edit.type_name)
    question = (
        f"Write {edit.path} ({edit.type_name}) once: {old} → {new}. The program may set it "
        "again in its next cycle; a forced variable keeps its force value."
    )
    run(f"Write {edit.path}", [p.Write(edit.path, edit.value)], question, None)


def _force(screen: ValueEditScreen, run: Run) -> None:
    edit = read_edit(screen.variable.value, screen.new_value.value, screen.types or {})
    if edit.path is None or edit.value_problem:
        return
    old, new = _current(screen, edit), format_for_display(edit.value, edit.type_name)
    level = level_of(edit.path, screen.status)
    started = is_started(level, screen.snapshot)
    name = level_name(level)
    question = f"Force {edit.path} ({edit.type_name}): {old} → {new} ({name}). " + (
        f"{name[0].upper()}{name[1:]} runs: the force value replaces the program's value at once."
        if started
        else f"{name[0].upper()}{name[1:]} is not started: the force value is prepared and "
        "acts once you start it on the Forcing tab."
    )
    note = (
        None
        if started
        else f"{new} is prepared for {edit.path}, not in force: {name} is not started. "
        "Start it on the Forcing tab."
    )
    run(f"Force {edit.path}", [p.Force(edit.path, edit.value)], question, note)


def refresh(
    screen: ValueEditScreen,
    status: p.Status | None,
    snapshot: ForcingSnapshot | None,
    feed: ResourceFeed | None,
    allowed: Callable[[type[p.Command[Any]]], Allowed],
) -> None:
    values, types, quality = latest_values(feed)
    screen.status, screen.snapshot, screen.types, screen.values = status, snapshot, types, values
    typed, literal = screen.variable.value, screen.new_value.value
    known = screen.read
    if known is not None and known[:2] == (typed, literal) and known[2] is types:
        edit = known[3]
    else:
        edit = read_edit(typed, literal, types)  # a dict of every variable: not ten times a second
        screen.read = (typed, literal, types, edit)
    level = level_of(edit.path, status) if edit.path is not None else None
    problem = edit.variable_problem or edit.value_problem
    fields = Allowed(not problem, problem)
    no_resource = Allowed(False, "no resource")
    safety = Allowed(True)
    parameters = snapshot.parameters if snapshot is not None else None
    if parameters is not None and parameters.resource.safety_operation:
        safety = Allowed(False, "the resource is in safety operation: no writes")
    write = _first(allowed(p.Write) if status is not None else no_resource, safety, fields)
    force = _first(
        allowed(p.Force) if status is not None else no_resource,
        configured(level, snapshot) if level is not None else Allowed(True),
        fields,
    )
    reasons: list[str] = []
    for button, verdict in ((screen.write, write), (screen.force, force)):
        button.disabled = not verdict.ok
        button.hint = verdict.reason or None
        # the fields say their own problems; the note says what the levels do not allow
        if verdict.reason and verdict.reason != fields.reason and verdict.reason not in reasons:
            reasons.append(verdict.reason)
    page = (
        render_info(edit, values, quality, level, snapshot),
        render_error(edit),
        _disabled(reasons),
    )
    for handle, content, before in zip(
        (screen.info, screen.error, screen.reason), page, screen.shown, strict=True
    ):
        if content != before:
            handle.content = content
    screen.shown = page


def _first(*verdicts: Allowed) -> Allowed:
    return next((x for x in verdicts if not x.ok), Allowed(True))


def render_info(
    edit: Edit,
    values: dict[str, Any],
    quality: dict[str, str],
    level: str | None,
    snapshot: ForcingSnapshot | None,
) -> str:
    """The chosen variable: its type, current value and quality, and its force level."""
    if edit.path is None:
        if edit.variable_problem == "choose a variable":
            return f'<div style="{_LINE};{_GREY}">Type a variable, e.g. TankControl.level.</div>'
        text = html.escape(edit.variable_problem)
        hint = ""
        if edit.matches:
            hint = " — did you mean " + ", ".join(
                f"<code>{html.escape(x)}</code>" for x in edit.matches
            )
        return f'<div data-testid="edit-info" style="{_LINE};color:{_RED}">{text}{hint}</div>'
    how = quality.get(edit.path, "live")
    current = format_for_display(values[edit.path], edit.type_name) if edit.path in values else "-"
    color = {"forced": _RED, "stale": "#868e96"}.get(how, "inherit")
    forcing = ""
    if level is not None:
        started = "started" if is_started(level, snapshot) else "not started"
        forcing = f' · <span style="{_GREY}">{html.escape(level_name(level))}: {started}</span>'
    return (
        f'<div data-testid="edit-info" style="{_LINE}"><code>{html.escape(edit.path)}</code> '
        f'<span style="{_GREY}">{html.escape(edit.type_name)}</span> · now '
        f'<b data-testid="edit-current" style="font-family:monospace;color:{color}">'
        f"{html.escape(current)}</b> ({html.escape(how)}){forcing}</div>"
    )


def render_error(edit: Edit) -> str:
    if edit.path is None or not edit.value_problem or edit.value_problem == "type the new value":
        return ""
    return (
        f'<div data-testid="value-error" style="{_LINE};color:{_RED}">'
        f"{html.escape(edit.value_problem)}</div>"
    )


def _disabled(reasons: list[str]) -> str:
    if not reasons:
        return ""
    text = "; ".join(html.escape(x) for x in reasons)
    return f'<div data-testid="edit-disabled" style="{_LINE};{_GREY}">Disabled: {text}</div>'


def wanted(screen: ValueEditScreen) -> list[str]:
    """The variable being edited, whose current value the screen shows."""
    edit = screen.read[3] if screen.read is not None else None
    return [edit.path] if edit is not None and edit.path is not None else []
