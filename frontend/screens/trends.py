"""The Trends screen, as CODESYS Trace or TwinCAT Scope: chosen variables as line charts
(uPlot) over time, BOOLs as 0/1 steps, the values under the cursor in the chart's legend
and the current ones in a table beneath.

- **Live**: the values the resource feed receives (10 a second) for the charted
  variables, kept for 11 minutes per browser (frontend/trend_history.py) whether the tab
  is in view or not; a window of 30 s, 2 min or 10 min; pause to look at a moment while
  the history goes on collecting. The charted variables are recorded into an MCAP file
  on the resource with one button (operator level).
- **Recorded**: the resource's recordings (frontend/screens/trends_recorded.py)."""

from __future__ import annotations

import html
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import viser

from backend.engineering import recordings, variable_tree
from backend.engineering.recordings import RecordingSpec, TriggerError, parse_trigger
from backend.engineering.resource_client import ResourceClient
from backend.engineering.watch_lists import WatchLists
from frontend import trend_chart, trend_plot
from frontend.command_reading import CommandReading
from frontend.confirm import attempt
from frontend.permissions import Allowed
from frontend.resource_feed import ResourceFeed
from frontend.screen_registry import Now, Screen, Work
from frontend.screens import trends_recorded
from frontend.screens.trends_recorded import ACTIVE, Target
from frontend.trend_chart import TrendChart
from frontend.trend_history import HISTORY_S, TrendHistory
from frontend.trend_plot import MAX_CHARTED, Trace
from runtime.contract import protocol as p
from runtime.contract.protocol import MAX_PRE_CYCLES
from runtime.contract.values import format_for_display

WINDOWS = {"30 s": 30, "2 min": 120, "10 min": 600}
LIVE_POINTS = 2000  # per variable and redraw: 10 min at 10 Hz is cut to min/max pairs
REDRAWS = 300  # per window at most (ten a second): the chart moves ~3 pixels a step
LIST_READS_PER_S = 1  # the recordings' progress, while the screen is in view
MAX_MATCHES = 100
NO_MATCH, NOTHING, NO_LIST = "(no match)", "(none charted)", "(no watch lists)"
PAUSE, RESUME = "Pause", "Resume"
RECORD, STOP = "Record the charted variables", "Stop recording"
_GREY = "color:#868e96"


def wall_clock() -> Callable[[], float]:
    """Unix seconds that never go back (the samples must be in order for the chart): the
    calendar time once, then the monotonic clock."""
    offset = time.time() - time.monotonic()
    return lambda: offset + time.monotonic()


@dataclass
class RecordOptions:
    """What a recording started here takes besides the charted variables."""

    trigger: viser.GuiTextHandle  # an ST condition; empty: record from now
    pre_cycles: viser.GuiNumberHandle[int]
    seconds: viser.GuiNumberHandle[int]  # 0: until stopped
    note: viser.GuiHtmlHandle

    def spec(self, paths: list[str]) -> RecordingSpec:
        """Raises TriggerError for a trigger that is no condition."""
        trigger = self.trigger.value.strip() or None
        if trigger is not None:
            parse_trigger(trigger)
        seconds = int(self.seconds.value)
        return RecordingSpec(
            variables=tuple(paths),
            trigger=trigger,
            pre_cycles=int(self.pre_cycles.value) if trigger else 0,
            seconds=seconds or None,
        )


@dataclass
class TrendsScreen:
    client: viser.ClientHandle
    user: str
    lists: WatchLists
    clock: Callable[[], float]
    bar: viser.GuiButtonGroupHandle
    status: viser.GuiHtmlHandle
    chart: TrendChart
    table: viser.GuiHtmlHandle
    record: viser.GuiButtonHandle
    record_note: viser.GuiHtmlHandle
    options: RecordOptions
    search: viser.GuiTextHandle
    matches: viser.GuiDropdownHandle[str]
    watch_list: viser.GuiDropdownHandle[str]
    charted_choice: viser.GuiDropdownHandle[str]
    note: viser.GuiHtmlHandle
    recorded: trends_recorded.RecordedTab
    history: TrendHistory = field(default_factory=TrendHistory)
    paths: list[str] = field(default_factory=list)  # the charted variables, in order
    types: dict[str, str] = field(default_factory=dict)  # the resource's variables
    types_version: int = -1
    values_version: int = -1  # of the feed's values last sampled
    resource: str | None = None  # whose values the history holds
    window_s: int = 30
    paused: bool = False
    own_axes: bool = False  # each number on an axis of its own
    target: Target | None = None
    recording: str | None = None  # the id of the recording started here
    listing: CommandReading[p.RecordingsReply] = field(
        default_factory=lambda: CommandReading(p.RecordList(), "its recordings")
    )
    shown: dict[str, str] = field(default_factory=dict)  # HTML sent, by part


def build(
    gui: viser.GuiApi, client: viser.ClientHandle, user: str, lists: WatchLists
) -> TrendsScreen:
    tabs = gui.add_tab_group()
    with tabs.add_tab("Live", viser.Icon.CHART_LINE) as live:
        # the scope's bar: the window and pause in one row, what is shown under it
        bar = gui.add_button_group("Window", (*WINDOWS, PAUSE, trend_chart.AXIS_EACH))
        status = gui.add_html("")
        placeholder = gui.add_html(_placeholder())
        table = gui.add_html("")
        record = gui.add_button(RECORD, icon=viser.Icon.PLAYER_RECORD)
        record_note = gui.add_html("")
        with gui.add_folder("Recording options", expand_by_default=False):
            trigger = gui.add_text("Trigger", "", hint="TankControl.alarmLow, level > 800")
            pre_cycles = gui.add_number("Cycles before it", 0, min=0, max=MAX_PRE_CYCLES, step=1)
            seconds = gui.add_number("Stop after (s)", 0, min=0, max=7 * 86_400, step=1)
            options_note = gui.add_html(_options_note(""))
        with gui.add_folder("Variables"):
            search = gui.add_text("Find variable", "")
            matches = gui.add_dropdown("Found", (NO_MATCH,))
            add = gui.add_button("Add to chart", icon=viser.Icon.PLUS)
            watch_list = gui.add_dropdown("From watch list", (NO_LIST,))
            add_list = gui.add_button("Chart the watch list")
            charted_choice = gui.add_dropdown("Charted", (NOTHING,))
            remove = gui.add_button("Remove from chart", icon=viser.Icon.MINUS)
            note = gui.add_html("")
    with tabs.add_tab("Recorded", viser.Icon.DATABASE) as recorded_tab:
        recorded = trends_recorded.build(gui, client, recorded_tab)
    screen = TrendsScreen(
        client,
        user,
        lists,
        wall_clock(),
        bar,
        status,
        TrendChart(gui, live, placeholder),
        table,
        record,
        record_note,
        RecordOptions(trigger, pre_cycles, seconds, options_note),
        search,
        matches,
        watch_list,
        charted_choice,
        note,
        recorded,
    )
    bar.on_click(lambda event: _bar_clicked(screen, event.target.value))
    record.on_click(lambda _: _record_clicked(screen))
    trigger.on_update(lambda _: _check_trigger(screen.options))
    search.on_update(lambda _: show_matches(screen))
    add.on_click(lambda _: chart_variables(screen, [screen.matches.value]))
    add_list.on_click(lambda _: chart_variables(screen, list(_list_variables(screen))))
    remove.on_click(lambda _: remove_variable(screen, screen.charted_choice.value))
    return screen


# ---- what the user does
def chart_variables(screen: TrendsScreen, paths: list[str]) -> None:
    """Add variables to the chart: the ones that can be charted, up to MAX_CHARTED."""
    known = [p for p in paths if p in screen.types]
    unfit = [p for p in known if not trend_plot.chartable(screen.types[p])]
    fit = [p for p in known if p not in unfit and p not in screen.paths]
    room = MAX_CHARTED - len(screen.paths)
    added = fit[:room]
    screen.paths.extend(added)
    screen.history.follow(screen.paths)
    said = [f"{len(added)} added to the chart"]
    if unfit:
        said.append(f"{len(unfit)} not charted: a STRING has no line")
    if len(fit) > room:
        said.append(f"at most {MAX_CHARTED} variables on one chart")
    _say(screen, "; ".join(said), error=not added)
    _after_change(screen)


def remove_variable(screen: TrendsScreen, path: str) -> None:
    if path not in screen.paths:
        return
    screen.paths.remove(path)
    screen.history.follow(screen.paths)
    _say(screen, f"{path} removed from the chart")
    _after_change(screen)


def _bar_clicked(screen: TrendsScreen, button: str) -> None:
    if button in WINDOWS:
        screen.window_s = WINDOWS[button]
    elif button in (PAUSE, RESUME):
        screen.paused = not screen.paused
    else:
        screen.own_axes = not screen.own_axes
    axes = trend_chart.AXIS_ONE if screen.own_axes else trend_chart.AXIS_EACH
    screen.bar.options = (*WINDOWS, RESUME if screen.paused else PAUSE, axes)
    _redraw_soon(screen)


def show_matches(screen: TrendsScreen) -> None:
    chartable = {p: t for p, t in screen.types.items() if trend_plot.chartable(t)}
    found, count = variable_tree.search(chartable, screen.search.value, MAX_MATCHES)
    _set_options(screen.matches, found or [NO_MATCH])
    if screen.search.value.strip():
        more = f" (the first {MAX_MATCHES} in Found)" if count > MAX_MATCHES else ""
        _say(screen, f"{count} variable{'s' if count != 1 else ''} to chart match{more}")


def _record_clicked(screen: TrendsScreen) -> None:
    """Start recording the charted variables on the resource, or stop the recording
    started here."""
    target = screen.target
    if target is None:
        return
    client = target.client_of(target.resource)
    running = screen.recording
    if running is not None and _state_of(screen, running) in ACTIVE:
        attempt(
            screen.client, f"Stop recording {running}", lambda: recordings.stop(client, running)
        )
    elif screen.paths:
        try:
            spec = screen.options.spec(screen.paths)
        except TriggerError as wrong:
            screen.options.note.content = _options_note(str(wrong))
            return

        def start() -> None:
            screen.recording = recordings.start(client, spec).id

        attempt(screen.client, f"Record {len(screen.paths)} variables of {target.resource}", start)
    screen.listing.changed()


def _check_trigger(options: RecordOptions) -> None:
    """Say at once what is wrong with the trigger typed, as it is typed."""
    text = options.trigger.value.strip()
    try:
        if text:
            parse_trigger(text)
    except TriggerError as wrong:
        options.note.content = _options_note(str(wrong))
        return
    options.note.content = _options_note("")


def _after_change(screen: TrendsScreen) -> None:
    _set_options(screen.charted_choice, screen.paths or [NOTHING])
    _redraw_soon(screen)


def _redraw_soon(screen: TrendsScreen) -> None:
    screen.chart.drawn_at = -math.inf


def _list_variables(screen: TrendsScreen) -> tuple[str, ...]:
    name = screen.watch_list.value
    return next((x.variables for x in screen.lists.of(screen.user) if x.name == name), ())


# ---- ten times a second
def wanted(screen: TrendsScreen) -> list[str]:
    """The charted variables: watched whether the tab is in view or not, so that their
    history goes on."""
    return screen.paths


def collect(screen: TrendsScreen, resource: str | None, feed: ResourceFeed | None) -> None:
    """Take the feed's new values into the history (cheap: called on every refresh, the
    tab in view or not). Another resource starts the history anew."""
    if resource != screen.resource:
        screen.resource = resource
        screen.history.clear()
        screen.recording = None
    if feed is None:
        return
    latest = feed.latest
    with latest.lock:
        types_version, types = latest.types_version, latest.types
        values, values_version = latest.values, latest.values_version
    if types_version != screen.types_version:
        screen.types, screen.types_version = types, types_version
        show_matches(screen)
    if values_version == screen.values_version or not screen.paths:
        return
    screen.values_version = values_version
    here = [p for p in screen.paths if p in values]
    sample = {p: trend_plot.number(values[p], types.get(p, "")) for p in here}
    screen.history.add(screen.clock(), sample)


def refresh(
    screen: TrendsScreen,
    resource: str | None,
    feed: ResourceFeed | None,
    token: str | None,
    client_of: Callable[[str], ResourceClient],
    allowed: Callable[[type[p.Command[Any]]], Allowed],
) -> None:
    """Draw the screen in view: the live chart as often as its window needs (ten times a
    second for 30 s, every 0.4 s for 2 min, every 2 s for 10 min: the data sent stays
    under 400 KiB/s for 16 variables), the table of current values, the recordings
    (read once a second)."""
    screen.target = Target(resource, client_of, allowed) if resource is not None else None
    _set_options(screen.watch_list, [x.name for x in screen.lists.of(screen.user)] or [NO_LIST])
    listed: list[p.RecordingInfo] = []
    error = ""
    if resource is not None:
        moment = int(time.monotonic() * LIST_READS_PER_S)
        key = (resource, token, moment, screen.listing.changes)
        screen.listing.ensure(key, client_of)
        reply, error = screen.listing.current(resource)
        listed = reply.recordings if reply is not None else []
    now = screen.clock()
    chart = screen.chart
    if not screen.paused and now - chart.drawn_at >= max(0.09, screen.window_s / REDRAWS):
        chart.drawn_at = now
        start = now - screen.window_s
        charted = _traces(screen)
        times, by_path = screen.history.since(start)
        columns = [by_path[t.path] for t in charted]
        chart.draw(charted, times, columns, start, LIVE_POINTS, screen.own_axes)
    values = feed.latest.values if feed is not None else {}
    _show(screen, "table", screen.table, _values_table(screen, values))
    _show(screen, "status", screen.status, _status(screen, feed))
    _refresh_record(screen, listed, allowed)
    trends_recorded.refresh(
        screen.recorded, screen.target, listed, error, screen.paths, screen.listing.changed
    )


def _refresh_record(
    screen: TrendsScreen,
    listed: list[p.RecordingInfo],
    allowed: Callable[[type[p.Command[Any]]], Allowed],
) -> None:
    ours = next((x for x in listed if x.id == screen.recording), None)
    running = ours is not None and ours.state in ACTIVE
    label = f"{STOP} {ours.id}" if running and ours is not None else RECORD
    if screen.record.label != label:
        screen.record.label = label
        screen.record.icon = viser.Icon.PLAYER_STOP if running else viser.Icon.PLAYER_RECORD
        screen.record.color = "red" if running else None
    verdict = allowed(p.RecordStop if running else p.RecordStart)
    reason = verdict.reason if not verdict.ok else ""
    if not reason and not running and not screen.paths:
        reason = "chart variables first: the recording takes the charted ones"
    if screen.target is None:
        reason = "select a resource"
    if screen.record.disabled != bool(reason):
        screen.record.disabled = bool(reason)
    _show(screen, "record", screen.record_note, _record_note(ours, reason))


def _state_of(screen: TrendsScreen, recording: str) -> str:
    reply, _ = screen.listing.current(screen.resource or "")
    found = [x.state for x in (reply.recordings if reply else []) if x.id == recording]
    return found[0] if found else ""


def _traces(screen: TrendsScreen) -> list[Trace]:
    return trend_plot.traces([(p, screen.types.get(p, "")) for p in screen.paths])


# ---- what the user reads
def _values_table(screen: TrendsScreen, values: dict[str, Any]) -> str:
    """The charted variables with their colour, type, current value and the lowest and
    highest value in the chart; the values under the cursor are in the chart's legend."""
    if not screen.paths:
        return ""
    extremes = screen.chart.extremes
    rows = []
    for trace in _traces(screen):
        value = values.get(trace.path)
        now = "…" if value is None else format_for_display(value, trace.type)
        rows.append(trend_chart.table_row(trace, extremes.get(trace.path), now))
    return trend_chart.table(rows, with_now=True, testid="trend-values")


def _status(screen: TrendsScreen, feed: ResourceFeed | None) -> str:
    if feed is None:
        text = "Select a resource you are logged in to."
    elif not screen.paths:
        text = "Nothing charted yet."
    else:
        held = _duration(screen.history.span_s())
        count = len(screen.paths)
        state = (
            '<b style="color:#e8590c">paused</b> (the history goes on collecting)'
            if screen.paused
            else '<b style="color:#2f9e44">live</b>'
        )
        text = (
            f"{state} · last {_duration(screen.window_s)} shown · {count} variable"
            f"{'s' if count != 1 else ''} · {held} of history kept (up to "
            f"{HISTORY_S // 60} min) · drag across the chart to zoom, double-click to "
            "show it all"
        )
    return (
        f'<div data-testid="trend-status" style="font-size:0.85em;padding:0 10px;{_GREY}">'
        f"{text}</div>{trend_chart.LEGEND_STYLE}"
    )


def _record_note(ours: p.RecordingInfo | None, reason: str) -> str:
    lines = []
    if ours is not None:
        lines.append(html.escape(trends_recorded.progress(ours)))
    if reason:
        lines.append(f"Disabled: {html.escape(reason)}")
    if not lines:
        return ""
    return (
        f'<div data-testid="record-note" style="font-size:0.85em;padding:0 10px;{_GREY}">'
        + "<br>".join(lines)
        + "</div>"
    )


def _options_note(error: str) -> str:
    """What is wrong with the trigger, or how the options work."""
    if error:
        red = 'data-testid="trigger-error" style="color:#c92a2a;font-size:0.85em"'
        return f"<div {red}>{html.escape(error)}</div>"
    return (
        f'<div style="{_GREY};font-size:0.85em">With a trigger (an ST condition: '
        "<code>TankControl.alarmLow</code>, <code>NOT TankControl.pump</code>, "
        "<code>TankControl.level &gt; 800</code>) the recording waits for it to become true "
        "and keeps the cycles before it; Stop after 0 s records until stopped.</div>"
    )


def _duration(seconds: float) -> str:
    whole = int(seconds)
    return f"{whole // 60} min {whole % 60} s" if whole >= 60 else f"{whole} s"


def _placeholder() -> str:
    return (
        f'<div data-testid="trend-empty" style="{_GREY};padding:24px 10px">'
        "Choose variables to chart under <b>Variables</b> below: by search, or a whole "
        "watch list. Numbers are drawn as lines on the left axis, BOOLs as 0/1 steps on "
        "the right.</div>"
    )


def _say(screen: TrendsScreen, text: str, error: bool = False) -> None:
    colour = "#c92a2a" if error else "#495057"
    shown = f'<div data-testid="trend-note" style="color:{colour};padding:0 4px">'
    screen.note.content = f"{shown}{html.escape(text)}</div>" if text else ""


def _show(screen: TrendsScreen, part: str, handle: viser.GuiHtmlHandle, content: str) -> None:
    """Send HTML only when it changed."""
    if screen.shown.get(part) != content:
        handle.content = content
        screen.shown[part] = content


def _set_options(dropdown: viser.GuiDropdownHandle[str], options: list[str]) -> None:
    wanted = tuple(options)
    if tuple(dropdown.options) != wanted:
        dropdown.options = wanted


class Trends(Screen):
    name = "Trends"
    icon = viser.Icon.CHART_LINE
    width = 1100  # a chart wants width: the drawing gives way while Trends is in front

    def __init__(self, work: Work) -> None:
        super().__init__(work)
        self.screen = build(work.gui, work.client, work.user, work.context.watch_lists)

    def follow(self, now: Now) -> None:
        collect(self.screen, now.resource, now.feed)  # its history goes on in any tab

    def refresh(self, now: Now) -> None:
        client_of = self.work.client_of
        refresh(self.screen, now.resource, now.feed, now.token, client_of, self.work.allowed)

    def watches(self) -> list[str]:
        return wanted(self.screen)
