"""The Trends screen, as CODESYS Trace or TwinCAT Scope: chosen variables as line charts
(uPlot) over time, BOOLs as 0/1 steps, the values under the cursor in the chart's legend
and the current ones in a table beneath.

- **Live**: the values the resource feed receives (10 a second) for the charted
  variables, kept for 11 minutes per browser (frontend/trend_history.py) whether the tab
  is in view or not; a window of 30 s, 2 min or 10 min; pause to look at a moment while
  the history goes on collecting.
- **Recorded**: the resource's recordings (docs/recording.md), one chosen downloaded, read
  and charted against its cycles' times; the charted variables recorded from here."""

from __future__ import annotations

import html
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import viser

from backend.engineering import variable_tree
from backend.engineering.watch_lists import WatchLists
from frontend import trend_plot
from frontend.resource_feed import ResourceFeed
from frontend.trend_history import TrendHistory
from frontend.trend_plot import MAX_CHARTED, Trace
from runtime.contract.values import format_for_display

WINDOWS = {"30 s": 30, "2 min": 120, "10 min": 600}
CHART_HEIGHT = 430
LIVE_POINTS = 2000  # per variable and redraw: 10 min at 10 Hz is cut to min/max pairs
MAX_MATCHES = 100
NO_MATCH, NOTHING, NO_LIST = "(no match)", "(none charted)", "(no watch lists)"
PAUSE, RESUME = "Pause", "Resume"
_GREY = "color:#868e96"


def wall_clock() -> Callable[[], float]:
    """Unix seconds that never go back (the samples must be in order for the chart): the
    calendar time once, then the monotonic clock."""
    offset = time.time() - time.monotonic()
    return lambda: offset + time.monotonic()


@dataclass
class LiveChart:
    """The chart of the Live tab and what it last drew."""

    gui: viser.GuiApi
    container: viser.GuiTabHandle
    order: float  # its place in the tab, kept when it is made again
    placeholder: viser.GuiHtmlHandle
    plot: viser.GuiUplotHandle | None = None
    charted: tuple[Trace, ...] = ()  # what `plot` was made for
    y_range: tuple[float, float] | None = None
    extremes: dict[str, tuple[float, float] | None] = field(default_factory=dict)  # drawn
    drawn_at: float = -math.inf  # when (clock) it was last drawn


@dataclass
class TrendsScreen:
    user: str
    lists: WatchLists
    clock: Callable[[], float]
    bar: viser.GuiButtonGroupHandle
    status: viser.GuiHtmlHandle
    chart: LiveChart
    table: viser.GuiHtmlHandle
    search: viser.GuiTextHandle
    matches: viser.GuiDropdownHandle[str]
    add: viser.GuiButtonHandle
    watch_list: viser.GuiDropdownHandle[str]
    add_list: viser.GuiButtonHandle
    charted_choice: viser.GuiDropdownHandle[str]
    remove: viser.GuiButtonHandle
    note: viser.GuiHtmlHandle
    history: TrendHistory = field(default_factory=TrendHistory)
    paths: list[str] = field(default_factory=list)  # the charted variables, in order
    types: dict[str, str] = field(default_factory=dict)  # the resource's variables
    types_version: int = -1
    values_version: int = -1  # of the feed's values last sampled
    window_s: int = 30
    paused: bool = False
    shown_table: str = ""
    shown_status: str = ""


def build(
    gui: viser.GuiApi, user: str, lists: WatchLists, clock: Callable[[], float] | None = None
) -> TrendsScreen:
    tabs = gui.add_tab_group()
    with tabs.add_tab("Live", viser.Icon.CHART_LINE) as live:
        # the scope's bar: the window and pause in one row, what is shown under it
        bar = gui.add_button_group("Window", (*WINDOWS, PAUSE))
        status = gui.add_html("")
        placeholder = gui.add_html(_placeholder())
        table = gui.add_html("")
        with gui.add_folder("Variables"):
            search = gui.add_text("Find variable", "")
            matches = gui.add_dropdown("Found", (NO_MATCH,))
            add = gui.add_button("Add to chart", icon=viser.Icon.PLUS)
            watch_list = gui.add_dropdown("From watch list", (NO_LIST,))
            add_list = gui.add_button("Chart the watch list")
            charted_choice = gui.add_dropdown("Charted", (NOTHING,))
            remove = gui.add_button("Remove from chart", icon=viser.Icon.MINUS)
            note = gui.add_html("")
    screen = TrendsScreen(
        user,
        lists,
        clock or wall_clock(),
        bar,
        status,
        LiveChart(gui, live, placeholder.order, placeholder),
        table,
        search,
        matches,
        add,
        watch_list,
        add_list,
        charted_choice,
        remove,
        note,
    )
    bar.on_click(lambda event: _bar_clicked(screen, event.target.value))
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
    else:
        toggle_pause(screen)
    _redraw_soon(screen)


def toggle_pause(screen: TrendsScreen) -> None:
    screen.paused = not screen.paused
    screen.bar.options = (*WINDOWS, RESUME if screen.paused else PAUSE)


def show_matches(screen: TrendsScreen) -> None:
    chartable = {p: t for p, t in screen.types.items() if trend_plot.chartable(t)}
    found, count = variable_tree.search(chartable, screen.search.value, MAX_MATCHES)
    _set_options(screen.matches, found or [NO_MATCH])
    if screen.search.value.strip():
        more = f" (the first {MAX_MATCHES} in Found)" if count > MAX_MATCHES else ""
        _say(screen, f"{count} variable{'s' if count != 1 else ''} to chart match{more}")


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


def collect(screen: TrendsScreen, feed: ResourceFeed | None) -> None:
    """Take the feed's new values into the history (cheap: called on every refresh, the
    tab in view or not)."""
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


def refresh(screen: TrendsScreen, feed: ResourceFeed | None) -> None:
    """Draw the tab in view: the chart as often as its window needs (a point a pixel: ten
    times a second for 30 s, about twice for 10 min), the table of current values."""
    _set_options(screen.watch_list, [x.name for x in screen.lists.of(screen.user)] or [NO_LIST])
    now = screen.clock()
    seconds = screen.window_s
    chart = screen.chart
    if not screen.paused and now - chart.drawn_at >= max(0.09, seconds / 1000):
        chart.drawn_at = now
        _draw(screen, now - seconds)
    values = feed.latest.values if feed is not None else {}
    _show_table(screen, values)
    _show_status(screen, feed, seconds)


def _draw(screen: TrendsScreen, start_s: float) -> None:
    chart = screen.chart
    charted = tuple(trend_plot.traces([(p, screen.types.get(p, "")) for p in screen.paths]))
    if not charted:
        if chart.plot is not None:
            chart.plot.remove()
            chart.plot = None
        chart.placeholder.visible = True
        return
    times, by_path = screen.history.since(start_s)
    columns = [by_path[t.path] for t in charted]
    numbers = [c for c, t in zip(columns, charted, strict=True) if not t.is_bool]
    y_range = trend_plot.y_range(numbers, chart.y_range)
    bools = [t.is_bool for t in charted]
    data = trend_plot.data(times, columns, bools, start_s, LIVE_POINTS)
    # A chart of other variables or another y range is made anew rather than changed:
    # viser carries the x zoom over a rebuild of its uPlot as a fraction of the data's
    # span, and the rebuild that new scales cause left the time axis at 1970.
    if chart.plot is None or charted != chart.charted or y_range != chart.y_range:
        if chart.plot is not None:
            chart.plot.remove()
        with chart.container:  # in the chart's place, under the placeholder it replaces
            chart.plot = chart.gui.add_uplot(
                data,
                height=CHART_HEIGHT,
                order=chart.order + 0.001,
                **trend_plot.options(charted, y_range),
            )
        chart.charted, chart.y_range = charted, y_range
        chart.placeholder.visible = False
    else:
        chart.plot.data = data
    chart.extremes = {
        t.path: trend_plot.extremes(column) for t, column in zip(charted, columns, strict=True)
    }


def _show_table(screen: TrendsScreen, values: dict[str, Any]) -> None:
    """The charted variables with their colour, type, current value and the lowest and
    highest value in the chart; the values under the cursor are in the chart's legend."""
    page = ""
    if screen.paths:
        extremes = screen.chart.extremes
        rows = []
        for trace in trend_plot.traces([(p, screen.types.get(p, "")) for p in screen.paths]):
            name = html.escape(trace.path)
            now = (
                format_for_display(values[trace.path], trace.type) if trace.path in values else "…"
            )
            low, high = extremes.get(trace.path) or (math.nan, math.nan)
            rows.append(
                f'<tr><td><span class="sw" style="background:{trace.colour}"></span></td>'
                f'<td>{name}</td><td class="t">{html.escape(trace.type)}</td>'
                f'<td class="v" data-trend="{name}">{html.escape(now)}</td>'
                f'<td class="v">{trend_plot.shown(low, trace)}</td>'
                f'<td class="v">{trend_plot.shown(high, trace)}</td></tr>'
            )
        page = _TABLE_HEAD + "".join(rows) + "</table>"
    if page != screen.shown_table:
        screen.table.content = page
        screen.shown_table = page


# uPlot's legend (the values under the cursor) in viser is small and pale: read at a glance
_LEGEND_STYLE = (
    "<style>.uplot .u-legend{font-size:0.8em}.uplot .u-legend .u-value{color:#212529;"
    "font-family:monospace}</style>"
)
_TABLE_HEAD = (
    "<style>.trv{width:calc(100% - 24px);margin:0 14px 0 10px;font-size:0.85em;"
    "border-collapse:collapse}"
    ".trv td,.trv th{padding:1px 6px;border-bottom:1px solid #f1f3f5}"
    ".trv th{color:#868e96;font-weight:500;text-align:left}.trv .t{color:#868e96}"
    ".trv .v{text-align:right;font-family:monospace;white-space:nowrap}"
    ".trv .sw{display:inline-block;width:18px;height:3px;vertical-align:middle}</style>"
    '<table class="trv" data-testid="trend-values"><tr><th style="width:22px"></th>'
    '<th>Variable</th><th>Type</th><th style="text-align:right">Now</th>'
    '<th style="text-align:right">Min in chart</th>'
    '<th style="text-align:right">Max in chart</th></tr>'
)


def _show_status(screen: TrendsScreen, feed: ResourceFeed | None, seconds: int) -> None:
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
            f"{state} · last {_duration(seconds)} shown · {count} variable"
            f"{'s' if count != 1 else ''} · {held} of history kept (up to 11 min) · "
            "drag across the chart to zoom, double-click to show it all"
        )
    page = (
        f'<div data-testid="trend-status" style="font-size:0.85em;padding:0 10px;{_GREY}">'
        f"{text}</div>{_LEGEND_STYLE}"
    )
    if page != screen.shown_status:
        screen.status.content = page
        screen.shown_status = page


def _duration(seconds: float) -> str:
    whole = int(seconds)
    return f"{whole // 60} min {whole % 60} s" if whole >= 60 else f"{whole} s"


def _placeholder() -> str:
    return (
        f'<div data-testid="trend-empty" style="{_GREY};padding:24px 8px">'
        "Choose variables to chart under <b>Variables</b> below: by search, or a whole "
        "watch list. Numbers are drawn as lines on the left axis, BOOLs as 0/1 steps on "
        "the right.</div>"
    )


def _say(screen: TrendsScreen, text: str, error: bool = False) -> None:
    colour = "#c92a2a" if error else "#495057"
    shown = f'<div data-testid="trend-note" style="color:{colour}">{html.escape(text)}</div>'
    screen.note.content = shown if text else ""


def _set_options(dropdown: viser.GuiDropdownHandle[str], options: list[str]) -> None:
    wanted = tuple(options)
    if tuple(dropdown.options) != wanted:
        dropdown.options = wanted
