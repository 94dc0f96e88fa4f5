"""The Forcing screen: the force levels of the selected resource (global, and one local
level per program) with whether the configuration allows them, whether forcing runs there
and its remaining time; Start and Stop per level with a time limit; the prepared force
values with their switch, whether they are in force and the live value; Unforce one and
Clear all. And the banner every tab shows while forcing runs."""

from __future__ import annotations

import html
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import viser

from backend.engineering.literals import LiteralError, parse_literal
from frontend.forcing_feed import ForcingSnapshot
from frontend.permissions import Allowed
from frontend.resource_feed import ResourceFeed, latest_values
from frontend.screen_registry import Now, Screen, Work
from runtime.contract import protocol as p
from runtime.contract.values import format_for_display

GLOBAL = "global"  # the level of global forcing, as `ForceInfo.level` and `remaining_ms` name it
GLOBAL_OPTION = "Global"
LOCAL_SUFFIX = " (local)"
DEFAULT_LIMIT = "T#10m"
NO_ENTRY = "-"
_CELL = "padding:2px 8px;border-bottom:1px solid #e9ecef;white-space:nowrap"
_GREY = "color:#868e96"
_RED = "#c92a2a"
_TITLE = '<div style="font-weight:600;margin:8px 0 2px;padding:0 8px">{}</div>'

# run(label, commands, question, note): asks `question`, then sends the commands in order
# to the selected resource; `note` is shown when they were done
Run = Callable[[str, Sequence[p.Command[p.StatusReply]], str, str | None], None]


@dataclass
class ForcingScreen:
    levels: viser.GuiHtmlHandle
    level: viser.GuiDropdownHandle[str]
    limit: viser.GuiTextHandle
    limit_error: viser.GuiHtmlHandle
    start: viser.GuiButtonHandle
    stop: viser.GuiButtonHandle
    entries: viser.GuiHtmlHandle
    entry: viser.GuiDropdownHandle[str]
    unforce: viser.GuiButtonHandle
    clear: viser.GuiButtonHandle
    reason: viser.GuiHtmlHandle
    # what the last refresh saw, for the buttons' callbacks
    snapshot: ForcingSnapshot | None = None
    types: dict[str, str] | None = None
    values: dict[str, Any] | None = None
    shown: tuple[str, str, str, str] = ("", "", "", "")


@dataclass
class Banner:
    handle: viser.GuiHtmlHandle
    shown: str = ""


# ---- the rules both forcing screens follow


def level_of(path: str, status: p.Status | None) -> str:
    """The force level of a variable: its program's (local) when its path starts with a
    program's name, else global (globals and I/O)."""
    head = path.split(".", 1)[0].upper()
    for program in status.programs if status is not None else ():
        if "." in path and program.name.upper() == head:
            return program.name
    return GLOBAL


def level_name(level: str) -> str:
    return "global forcing" if level == GLOBAL else f"local forcing of {level}"


def is_started(level: str, snapshot: ForcingSnapshot | None) -> bool:
    if snapshot is None or snapshot.state is None:
        return False
    return ("" if level == GLOBAL else level) in snapshot.state.started


def configured(level: str, snapshot: ForcingSnapshot | None) -> Allowed:
    """Whether the resource's configuration allows forcing at a level (the resource checks
    again; unknown until its parameters are read, and then not held against the user)."""
    parameters = snapshot.parameters if snapshot is not None else None
    if parameters is None:
        return Allowed(True)
    if parameters.resource.safety_operation:
        return Allowed(False, "the resource is in safety operation: no forcing")
    if level == GLOBAL:
        if not parameters.resource.global_forcing_allowed:
            return Allowed(False, "Global Forcing Allowed is OFF in the resource's configuration")
        return Allowed(True)
    program = next((x for x in parameters.programs if x.name == level), None)
    if program is not None and not program.local_forcing_allowed:
        return Allowed(False, f"Local Forcing Allowed of {level} is OFF in its configuration")
    return Allowed(True)


def timeout_reaction(level: str, snapshot: ForcingSnapshot | None) -> str:
    parameters = snapshot.parameters if snapshot is not None else None
    if parameters is None:
        return "-"
    if level == GLOBAL:
        return parameters.resource.global_force_timeout_reaction
    program = next((x for x in parameters.programs if x.name == level), None)
    return program.local_force_timeout_reaction if program is not None else "-"


def duration(seconds: float) -> str:
    """A remaining time as a person reads it: `4 min 12 s`, `1 h 05 min`, `9 s`."""
    whole = int(seconds + 0.999)  # counts down to 0 s only when it is over
    hours, rest = divmod(whole, 3600)
    minutes, secs = divmod(rest, 60)
    if hours:
        return f"{hours} h {minutes:02d} min"
    if minutes:
        return f"{minutes} min {secs} s"
    return f"{secs} s"


def time_limit(text: str) -> tuple[int | None, str]:
    """The time limit typed as a TIME literal, in ms (None: no limit), or the error."""
    if not text.strip():
        return None, ""
    try:
        ns = parse_literal(text, "TIME")
    except LiteralError:
        return None, f"{text.strip()} is no time: write it as T#5m, T#90s or T#1h30m"
    ms = int(ns) // 1_000_000
    if not 1 <= ms <= p.MAX_MS:
        return None, "the time limit is from T#1ms to T#24h"
    return ms, ""


def remaining_text(level: str, snapshot: ForcingSnapshot | None, now: float) -> str:
    if snapshot is None:
        return "-"
    left = snapshot.remaining_s(level, now)
    return "no time limit" if left is None else f"{duration(left)} left"


# ---- the banner


def build_banner(gui: viser.GuiApi) -> Banner:
    return Banner(gui.add_html("", visible=False))


def show_banner(banner: Banner, status: p.Status | None, snapshot: ForcingSnapshot | None) -> None:
    content = render_banner(status, snapshot, time.monotonic())
    if content != banner.shown:
        banner.handle.content = content
        banner.handle.visible = bool(content)
        banner.shown = content


def render_banner(status: p.Status | None, snapshot: ForcingSnapshot | None, now: float) -> str:
    """A red strip while forcing runs at the selected resource (its pushed status says so;
    the details come with the next answer to `GetForcing`)."""
    if status is None or not status.forcing:
        return ""
    details = ""
    state = snapshot.state if snapshot is not None else None
    if state is not None and state.started:
        active = sum(1 for e in state.entries if e.active)
        count = {0: "no value forced", 1: "1 value forced"}.get(active, f"{active} values forced")
        levels = "; ".join(
            f"{'global' if level == '' else 'local ' + level}, "
            f"{remaining_text(level or GLOBAL, snapshot, now)}"
            for level in state.started
        )
        details = f" — {count} · {levels}"
    return (
        f'<div data-testid="forcing-banner" style="background:{_RED};color:white;'
        'font-weight:600;padding:6px 10px;border-radius:4px;margin:2px 0">'
        f"FORCING ACTIVE{html.escape(details)}</div>"
    )


# ---- the screen


def build(gui: viser.GuiApi, run: Run) -> ForcingScreen:
    levels = gui.add_html("")
    with gui.add_folder("Start and stop forcing"):
        level = gui.add_dropdown("Forcing level", (GLOBAL_OPTION,))
        limit = gui.add_text(
            "Time limit", DEFAULT_LIMIT, hint="a TIME literal (T#10m, T#1h); empty: no limit"
        )
        limit_error = gui.add_html("")
        start = gui.add_button("Start forcing", color="red", disabled=True)
        stop = gui.add_button("Stop forcing", disabled=True)
    entries = gui.add_html("")
    with gui.add_folder("Remove force values"):
        entry = gui.add_dropdown("Force value", (NO_ENTRY,))
        unforce = gui.add_button("Unforce", disabled=True)
        clear = gui.add_button("Clear all", disabled=True)
    reason = gui.add_html("")
    screen = ForcingScreen(
        levels, level, limit, limit_error, start, stop, entries, entry, unforce, clear, reason
    )
    start.on_click(lambda _: _start(screen, run))
    stop.on_click(lambda _: _stop(screen, run))
    unforce.on_click(lambda _: _unforce(screen, run))
    clear.on_click(lambda _: _clear(screen, run))
    return screen


def _chosen_level(screen: ForcingScreen) -> str:
    option = screen.level.value
    return GLOBAL if option == GLOBAL_OPTION else option.removesuffix(LOCAL_SUFFIX)


def _program(level: str) -> str | None:
    return None if level == GLOBAL else level


def _start(screen: ForcingScreen, run: Run) -> None:
    level = _chosen_level(screen)
    ms, error = time_limit(screen.limit.value)
    if error:  # shown at the field already
        return
    limit = "without a time limit" if ms is None else f"for {duration(ms / 1000)}"
    again = " (it runs: this sets a new time limit)" if is_started(level, screen.snapshot) else ""
    reaction = timeout_reaction(level, screen.snapshot)
    question = (
        f"Start {level_name(level)} {limit}{again}. Every force value of this level with its "
        f"switch ON replaces the program's value until forcing stops"
        + (f"; when the time runs out: {reaction}." if ms is not None else ".")
    )
    run(f"Start {level_name(level)}", [p.StartForcing(_program(level), ms)], question, None)


def _stop(screen: ForcingScreen, run: Run) -> None:
    level = _chosen_level(screen)
    question = f"Stop {level_name(level)}: the programs set these variables again."
    run(f"Stop {level_name(level)}", [p.StopForcing(_program(level))], question, None)


def _unforce(screen: ForcingScreen, run: Run) -> None:
    variable = screen.entry.value
    info = _entry(screen.snapshot, variable)
    if info is None:
        return
    shown = _shown(info.value, (screen.types or {}).get(info.variable, ""))
    question = f"Remove the force value {shown} of {info.variable}"
    question += ": the program sets it again." if info.active else " (it is not in force)."
    run(f"Unforce {info.variable}", [p.Unforce(info.variable)], question, None)


def _clear(screen: ForcingScreen, run: Run) -> None:
    state = screen.snapshot.state if screen.snapshot is not None else None
    if state is None:
        return
    names = ", ".join(e.variable for e in state.entries)
    count = len(state.entries)
    commands: list[p.Command[p.StatusReply]] = [p.Unforce(e.variable) for e in state.entries]
    commands += [p.StopForcing(level or None) for level in state.started]
    parts = []
    if count:
        parts.append(
            f"remove the force value of {names}"
            if count == 1
            else f"remove all {count} force values ({names})"
        )
    if state.started:
        parts.append("stop " + ", ".join(level_name(x or GLOBAL) for x in state.started))
    what = " and ".join(parts)
    question = f"{what[:1].upper()}{what[1:]}: the programs set every variable again."
    run("Clear all forcing", commands, question, None)


def _entry(snapshot: ForcingSnapshot | None, variable: str) -> p.ForceInfo | None:
    state = snapshot.state if snapshot is not None else None
    return next((e for e in state.entries if e.variable == variable), None) if state else None


def refresh(
    screen: ForcingScreen,
    status: p.Status | None,
    snapshot: ForcingSnapshot | None,
    feed: ResourceFeed | None,
    allowed: Callable[[type[p.Command[Any]]], Allowed],
) -> None:
    values, types, quality = latest_values(feed)
    screen.snapshot, screen.types, screen.values = snapshot, types, values
    programs = [x.name for x in status.programs] if status is not None else []
    options = (GLOBAL_OPTION, *(name + LOCAL_SUFFIX for name in programs))
    if tuple(screen.level.options) != options:
        screen.level.options = options
    state = snapshot.state if snapshot is not None else None
    variables = tuple(e.variable for e in state.entries) if state and state.entries else ()
    if tuple(screen.entry.options) != (variables or (NO_ENTRY,)):
        screen.entry.options = variables or (NO_ENTRY,)

    now = time.monotonic()
    level = _chosen_level(screen)
    _ms, error = time_limit(screen.limit.value)
    reasons: list[str] = []
    operator = allowed(p.StartForcing) if status is not None else Allowed(False, "no resource")
    start = _first(operator, configured(level, snapshot))
    if start.ok and status is not None and not status.state.startswith("RUN"):
        start = Allowed(False, "forcing starts only while the resource runs")
    stop = _first(
        operator, _when(is_started(level, snapshot), f"{level_name(level)} is not started")
    )
    remove = _first(operator, _when(bool(variables), "no force value is prepared"))
    clear = _first(
        operator, _when(bool(variables) or bool(state and state.started), "nothing to clear")
    )
    for button, verdict in (
        (screen.start, start),
        (screen.stop, stop),
        (screen.unforce, remove),
        (screen.clear, clear),
    ):
        button.disabled = not verdict.ok
        button.hint = verdict.reason or None
        if verdict.reason and verdict.reason not in reasons:
            reasons.append(verdict.reason)
    page = (
        render_levels(programs, snapshot, now),
        render_entries(state, types, values, quality),
        _error(error) if error else "",
        _disabled(reasons, snapshot),
    )
    handles = (screen.levels, screen.entries, screen.limit_error, screen.reason)
    for handle, content, before in zip(handles, page, screen.shown, strict=True):
        if content != before:
            handle.content = content
    screen.shown = page


def _first(*verdicts: Allowed) -> Allowed:
    return next((x for x in verdicts if not x.ok), Allowed(True))


def _when(condition: bool, reason: str) -> Allowed:
    return Allowed(True) if condition else Allowed(False, reason)


def _error(text: str) -> str:
    style = f"font-size:0.875em;padding:2px 8px;color:{_RED}"  # under its field
    return f'<div data-testid="limit-error" style="{style}">{html.escape(text)}</div>'


def _disabled(reasons: list[str], snapshot: ForcingSnapshot | None) -> str:
    lines = []
    if reasons:
        text = "; ".join(html.escape(x) for x in reasons)
        style = f"{_GREY};padding:0 8px"
        lines.append(f'<div data-testid="forcing-disabled" style="{style}">Disabled: {text}</div>')
    if snapshot is not None and snapshot.error:
        lines.append(
            f'<div style="color:{_RED}">No answer about forcing: '
            f"{html.escape(snapshot.error)}</div>"
        )
    return "".join(lines)


def _shown(value: Any, type_name: str) -> str:
    return format_for_display(value, type_name)


def render_levels(programs: list[str], snapshot: ForcingSnapshot | None, now: float) -> str:
    """One row per force level: allowed by the configuration, started, time left."""
    if snapshot is None:
        return "<p>Select a resource you are logged in to.</p>"
    head = "".join(
        f'<th style="{_CELL};text-align:left">{name}</th>'
        for name in ("Level", "Allowed", "Forcing", "Time left", "When the time runs out")
    )
    rows = []
    for level in (GLOBAL, *programs):
        verdict = configured(level, snapshot)
        started = is_started(level, snapshot)
        name = "Global" if level == GLOBAL else f"{level} (local)"
        state = (
            f'<b style="color:{_RED}">started</b>'
            if started
            else f'<span style="{_GREY}">stopped</span>'
        )
        left = remaining_text(level, snapshot, now) if started else "-"
        allowed_cell = "yes" if verdict.ok else f'<span style="{_GREY}">no</span>'
        rows.append(
            f'<tr data-level="{html.escape(level)}"><td style="{_CELL}">{html.escape(name)}</td>'
            f'<td style="{_CELL}" title="{html.escape(verdict.reason)}">{allowed_cell}</td>'
            f'<td style="{_CELL}" data-testid="forcing-{html.escape(level)}">{state}</td>'
            f'<td style="{_CELL};font-family:monospace" data-remaining="{html.escape(level)}">'
            f"{html.escape(left)}</td>"
            f'<td style="{_CELL}">{html.escape(timeout_reaction(level, snapshot))}</td></tr>'
        )
    return (
        _TITLE.format("Force levels")
        + '<div style="overflow-x:auto"><table data-testid="forcing-levels" '
        f'style="font-size:0.9em;border-collapse:collapse;width:100%"><tr>{head}</tr>'
        f"{''.join(rows)}</table></div>"
    )


def render_entries(
    state: p.ForcingState | None,
    types: dict[str, str],
    values: dict[str, Any],
    quality: dict[str, str],
) -> str:
    """The prepared force values: variable, type, level, force value, switch, in force or
    waiting for its level to start, and the variable's live value beside it."""
    title = _TITLE.format("Force values")
    if state is None:
        return title + f'<div style="{_GREY};padding:0 8px">Reading the force table ...</div>'
    if not state.entries:
        note = "No force value is prepared. Force a value from the Online test tab."
        return (
            title + f'<div data-testid="no-force-values" style="{_GREY};padding:0 8px">{note}</div>'
        )
    head = "".join(
        f'<th style="{_CELL};text-align:{align}">{name}</th>'
        for name, align in (
            ("Variable", "left"), ("Type", "left"), ("Level", "left"), ("Force value", "right"),
            ("Switch", "left"), ("State", "left"), ("Live value", "right"),
        )
    )  # fmt: skip
    rows = []
    for e in state.entries:
        type_name = types.get(e.variable, "")
        name = html.escape(e.variable)
        now_state = (
            f'<b style="color:{_RED}">in force</b>'
            if e.active
            else f'<span style="{_GREY}">{"switch OFF" if not e.switch else "waiting for start"}'
            "</span>"
        )
        live = html.escape(_shown(values[e.variable], type_name)) if e.variable in values else "-"
        how = quality.get(e.variable, "live")
        rows.append(
            f'<tr data-forced="{name}"><td style="{_CELL}">{name}</td>'
            f'<td style="{_CELL};{_GREY}">{html.escape(type_name)}</td>'
            f'<td style="{_CELL}">{html.escape(e.level)}</td>'
            f'<td style="{_CELL};text-align:right;font-family:monospace" data-force-value="{name}">'
            f"{html.escape(_shown(e.value, type_name))}</td>"
            f'<td style="{_CELL}">{"ON" if e.switch else "OFF"}</td>'
            f'<td style="{_CELL}" data-force-state="{name}">{now_state}</td>'
            f'<td style="{_CELL};text-align:right;font-family:monospace" '
            f'data-quality="{html.escape(how)}">{live}</td></tr>'
        )
    return (
        title + '<div style="overflow-x:auto"><table data-testid="force-values" '
        f'style="font-size:0.9em;border-collapse:collapse;width:100%"><tr>{head}</tr>'
        f"{''.join(rows)}</table></div>"
    )


def wanted(snapshot: ForcingSnapshot | None) -> list[str]:
    """The forced variables, whose live values the Force values table shows."""
    state = snapshot.state if snapshot is not None else None
    return [entry.variable for entry in state.entries] if state is not None else []


class Forcing(Screen):
    name = "Forcing"
    icon = viser.Icon.LOCK

    def __init__(self, work: Work) -> None:
        super().__init__(work)
        self.screen = build(work.gui, work.send_all)

    def refresh(self, now: Now) -> None:
        refresh(self.screen, now.status, now.forcing, now.feed, self.work.allowed)

    def watches(self) -> list[str]:
        return wanted(self.work.forcing_feed.snapshot())
