"""The Recorded tab of the Trends screen: the resource's recordings (docs/recording.md) with
their state, cycles, dropped cycles and size; the chosen one downloaded from the resource
(backend/engineering/recordings.py), read (`read_recording`) and charted against its
cycles' log time, with the same cursor as the live chart; its .mcap files saved by the
browser for Foxglove or the mcap tools. Downloads and reading run on a thread of their own:
the screen stays usable meanwhile."""

from __future__ import annotations

import html
import io
import logging
import threading
from collections.abc import Callable
from dataclasses import dataclass, field
from datetime import datetime
from typing import Any

import numpy as np
import viser

from backend.engineering import recordings, variable_tree
from backend.engineering.resource_client import ResourceClient, ResourceUnreachable
from frontend import trend_chart, trend_plot
from frontend.confirm import attempt, confirm
from frontend.permissions import Allowed
from frontend.trend_chart import AXIS_EACH, AXIS_ONE, TrendChart
from frontend.trend_plot import MAX_CHARTED, Floats, Trace, chartable
from runtime.contract import protocol as p
from runtime.contract.recording import Recording, RecordingUnreadable, read_recording
from runtime.contract.refusal import Refusal

ACTIVE = ("waiting", "recording")  # a recording that has not ended

RECORDED_POINTS = 10_000  # per variable: a long recording is cut to min/max pairs
MAX_OPEN_BYTES = 32 * 1024 * 1024  # larger recordings: download them, open in Foxglove
NONE_YET = "(no recordings)"
CHART, DOWNLOAD = "Chart it", "Download .mcap"
_GREY = "color:#868e96"
log = logging.getLogger("padt.ui")


@dataclass(frozen=True)
class Target:
    """The resource the Trends screen works on, as the last refresh saw it."""

    resource: str
    client_of: Callable[[str], ResourceClient]
    allowed: Callable[[type[p.Command[Any]]], Allowed]


@dataclass(frozen=True, eq=False)  # the same when it is the same reading (numpy inside)
class Opened:
    """A recording read back: its files' contents in order, with its info of the moment."""

    info: p.RecordingInfo
    parts: list[Recording]
    times: Floats  # Unix seconds, each cycle's log time


@dataclass(frozen=True)
class Selection:
    """The variables of an opened recording the chart shows, with their values."""

    traces: list[Trace]
    columns: list[Floats]
    note: str  # what the user should know about the recording and the choice


@dataclass
class RecordedTab:
    client: viser.ClientHandle
    choice: viser.GuiDropdownHandle[str]
    actions: viser.GuiButtonGroupHandle
    choose: viser.GuiTextHandle  # words of the variables to chart
    listing: viser.GuiHtmlHandle
    note: viser.GuiHtmlHandle
    chart: TrendChart
    table: viser.GuiHtmlHandle
    manage: viser.GuiButtonHandle  # stop the chosen recording, or delete it
    manage_note: viser.GuiHtmlHandle
    target: Target | None = None
    listed: list[p.RecordingInfo] = field(default_factory=list)
    opened: Opened | None = None
    selection: Selection | None = None
    drawn: tuple[Opened | None, str, tuple[str, ...], bool] = (None, "", (), False)  # charted
    busy: bool = False
    message: tuple[str, str] = ("", "")  # text, colour: the last download's outcome
    relist: Callable[[], None] = lambda: None  # read the recordings again now
    own_axes: bool = False  # each number on an axis of its own
    shown: dict[str, str] = field(default_factory=dict)


def build(gui: viser.GuiApi, client: viser.ClientHandle, tab: viser.GuiTabHandle) -> RecordedTab:
    choice = gui.add_dropdown("Recording", (NONE_YET,))
    actions = gui.add_button_group("Recording actions", (CHART, DOWNLOAD, AXIS_EACH))
    choose = gui.add_text("Variables to chart", "")
    note = gui.add_html("")
    placeholder = gui.add_html(
        f'<div data-testid="recorded-empty" style="{_GREY};padding:16px 10px">Choose a '
        f"recording and <b>{CHART}</b>: it is downloaded from the resource and drawn "
        "against its cycles' times.</div>"
    )
    table = gui.add_html("")
    listing = gui.add_html("")
    # under the list: what is done to the recording chosen in it, seldom and for good
    manage = gui.add_button(
        "Delete the recording", icon=viser.Icon.TRASH, color="gray", disabled=True
    )
    manage_note = gui.add_html("")
    chart = TrendChart(gui, tab, placeholder)
    screen = RecordedTab(
        client, choice, actions, choose, listing, note, chart, table, manage, manage_note
    )
    actions.on_click(lambda event: _act(screen, event.target.value))
    manage.on_click(lambda _: _manage(screen))
    return screen


def _chosen(screen: RecordedTab) -> p.RecordingInfo | None:
    return next((x for x in screen.listed if x.id == screen.choice.value), None)


def _act(screen: RecordedTab, action: str) -> None:
    if action in (AXIS_EACH, AXIS_ONE):
        screen.own_axes = not screen.own_axes
        axes = AXIS_ONE if screen.own_axes else AXIS_EACH
        screen.actions.options = (CHART, DOWNLOAD, axes)
        return
    chosen, target = _chosen(screen), screen.target
    if chosen is None or target is None or screen.busy:
        return
    client = target.client_of(target.resource)
    screen.busy = True
    what = "downloading and reading" if action == CHART else "downloading"
    screen.message = (f"{what} {chosen.id} ({_size(chosen)}) ...", "#495057")
    work = _open if action == CHART else _download
    threading.Thread(target=_guarded, args=(screen, work, client, chosen), daemon=True).start()


def _manage(screen: RecordedTab) -> None:
    """Stop the chosen recording while it runs (whoever started it); delete it, asked
    first, once it has ended."""
    chosen, target = _chosen(screen), screen.target
    if chosen is None or target is None:
        return
    client = target.client_of(target.resource)
    if chosen.state in ACTIVE:
        attempt(
            screen.client, f"Stop recording {chosen.id}", lambda: recordings.stop(client, chosen.id)
        )
        screen.relist()
        return

    def delete() -> None:
        what = f"Delete recording {chosen.id}"
        deleted = attempt(screen.client, what, lambda: recordings.delete(client, chosen.id))
        opened = screen.opened
        if deleted and opened is not None and opened.info.id == chosen.id:
            screen.opened = None
        screen.relist()

    files = len(chosen.files)
    confirm(
        screen.client,
        f"Delete recording {chosen.id}: {target.resource}",
        f"Its {files} file{'s' if files != 1 else ''} ({_size(chosen)}, {chosen.cycles:,} "
        f"cycles) are deleted from the state folder of {target.resource}. This cannot be "
        "undone: download it first to keep it.",
        delete,
    )


def _guarded(
    screen: RecordedTab,
    work: Callable[[RecordedTab, ResourceClient, p.RecordingInfo], None],
    client: ResourceClient,
    chosen: p.RecordingInfo,
) -> None:
    """Run a download; whatever goes wrong is said on the screen, never raised."""
    try:
        work(screen, client, chosen)
    except (Refusal, RecordingUnreadable, ResourceUnreachable) as exc:
        text = f"{exc.code}: {exc.message}" if isinstance(exc, Refusal) else str(exc)
        screen.message = (f"{chosen.id}: {text}", "#c92a2a")
    except Exception:  # the screen stays usable whatever went wrong
        log.exception("opening recording %s failed", chosen.id)
        screen.message = (f"{chosen.id} could not be read (see the PADT's log)", "#c92a2a")
    finally:
        screen.busy = False


def _files(chosen: p.RecordingInfo) -> list[p.RecordingFile]:
    return sorted(chosen.files, key=lambda f: recordings.part_number(f.name))


def _download(screen: RecordedTab, client: ResourceClient, chosen: p.RecordingInfo) -> None:
    for file in _files(chosen):
        data = recordings.download(client, file.name)
        screen.client.send_file_download(file.name, data, save_immediately=True)
    names = ", ".join(f.name for f in _files(chosen))
    screen.message = (f"saved by the browser: {names}", "#2f9e44")


def _open(screen: RecordedTab, client: ResourceClient, chosen: p.RecordingInfo) -> None:
    total = sum(f.size for f in chosen.files)
    if total > MAX_OPEN_BYTES:
        raise RecordingUnreadable(
            f"{_size(chosen)} is too much to chart here: download it and open it in Foxglove"
        )
    parts = [
        read_recording(io.BytesIO(recordings.download(client, f.name, MAX_OPEN_BYTES)))
        for f in _files(chosen)
    ]
    times = np.array([t for part in parts for t in part.times_ns], dtype=np.float64) / 1e9
    screen.opened = Opened(chosen, parts, times)
    screen.message = ("", "")


def select(opened: Opened, words: str, preferred: list[str]) -> Selection:
    """The variables to chart: those matching `words` (as the variable search does), else
    those charted live that the recording has, else its first ones; at most MAX_CHARTED
    that have a line."""
    header = opened.parts[0].header
    fit = {path: (i, kind) for i, (path, kind) in enumerate(header.variables) if chartable(kind)}
    if words.strip():
        chosen, _ = variable_tree.search(fit, words, MAX_CHARTED)
    else:
        chosen = [x for x in preferred if x in fit] or list(fit)[:MAX_CHARTED]
    traces = trend_plot.traces([(path, fit[path][1]) for path in chosen])
    rows = [row for part in opened.parts for row in part.rows]
    columns = [
        np.fromiter((trend_plot.number(row[fit[t.path][0]], t.type) for row in rows), np.float64)
        for t in traces
    ]
    info, times = opened.info, opened.times
    said = [f"{len(rows):,} cycles"]
    if rows:
        said.append(f"from {_clock(times[0])} to {_clock(times[-1])}")
    said.append(f"{len(traces)} of {len(header.variables)} variables charted")
    if len(fit) > len(traces):
        said.append("type in Variables to chart to choose others")
    if info.dropped:
        said.append(f"{info.dropped:,} cycles dropped while recording")
    cut = [part.problem for part in opened.parts if not part.complete]
    if info.state in ACTIVE:
        said.append("still recording: shown as far as written")
    elif cut:
        said.append(f"the file ends early ({cut[0]}): shown up to its last whole chunk")
    return Selection(traces, columns, " · ".join(said))


# ---- while the screen is in view
def refresh(
    screen: RecordedTab,
    target: Target | None,
    listed: list[p.RecordingInfo],
    error: str,
    preferred: list[str],
    relist: Callable[[], None],
) -> None:
    """`preferred`: the variables charted live, charted first when the recording has them;
    `relist`: read the recordings again now."""
    resource = target.resource if target is not None else None
    if resource != (screen.target.resource if screen.target is not None else None):
        screen.opened = None
    screen.target, screen.listed, screen.relist = target, listed, relist
    ids = [x.id for x in listed] or [NONE_YET]
    if tuple(screen.choice.options) != tuple(ids):
        screen.choice.options = tuple(ids)  # the choice kept while offered (events.py)
    _show(screen, "listing", screen.listing, render_listing(listed, error))
    _refresh_manage(screen)
    opened = screen.opened
    words = screen.choose.value
    wanted = (opened, words, tuple(preferred), screen.own_axes)
    if wanted != screen.drawn:
        screen.chart.clear()  # a new y range for new variables
        screen.selection = None if opened is None else select(opened, words, preferred)
        if opened is not None and screen.selection is not None:
            picked = screen.selection
            columns, times = picked.columns, opened.times
            screen.chart.draw(picked.traces, times, columns, None, RECORDED_POINTS, screen.own_axes)
        screen.drawn = wanted
    selection = screen.selection
    extremes = screen.chart.extremes
    traces = selection.traces if selection else []
    rows = [trend_chart.table_row(t, extremes.get(t.path), None) for t in traces]
    table = trend_chart.table(rows, with_now=False, testid="recorded-values") if rows else ""
    _show(screen, "table", screen.table, table)
    text, colour = screen.message
    if not text and opened is not None and selection is not None:
        text, colour = f"{opened.info.id}: {selection.note}", "#495057"
    style = f"color:{colour};padding:0 10px;font-size:0.9em"
    note = f'<div data-testid="recorded-note" style="{style}">{html.escape(text)}</div>'
    _show(screen, "note", screen.note, note if text else "")


def _refresh_manage(screen: RecordedTab) -> None:
    chosen, target = _chosen(screen), screen.target
    running = chosen is not None and chosen.state in ACTIVE
    if chosen is None:
        label = "Delete the recording"
    else:
        label = f"Stop recording {chosen.id}" if running else f"Delete recording {chosen.id}"
    if screen.manage.label != label:
        screen.manage.label = label
        screen.manage.icon = viser.Icon.PLAYER_STOP if running else viser.Icon.TRASH
        screen.manage.color = "red" if running else "gray"
    reason = ""
    if target is not None and chosen is not None:
        verdict = target.allowed(p.RecordStop if running else p.RecordDelete)
        reason = verdict.reason if not verdict.ok else ""
    if screen.manage.disabled != (chosen is None or bool(reason)):
        screen.manage.disabled = chosen is None or bool(reason)
    note = (
        f'<div data-testid="manage-disabled" style="{_GREY};font-size:0.85em;padding:0 10px">'
        f"Disabled: {html.escape(reason)}</div>"
        if reason
        else ""
    )
    _show(screen, "manage", screen.manage_note, note)


# ---- what the user reads
def progress(recording: p.RecordingInfo) -> str:
    """One line of a recording's state: `rec-1 recording: 1,234 cycles, 0 dropped, 56 KB`."""
    state = {"waiting": "waiting for its trigger"}.get(recording.state, recording.state)
    line = (
        f"{recording.id} {state}: {recording.cycles:,} cycles, {recording.dropped:,} dropped, "
        f"{_size(recording)}"
    )
    return line + (f" ({recording.error})" if recording.error else "")


_STATE_COLOURS = {"recording": "#c92a2a", "waiting": "#e8590c", "done": "#2f9e44"}


def render_listing(listed: list[p.RecordingInfo], error: str) -> str:
    if error or not listed:
        colour = "#c92a2a" if error else "#868e96"
        text = html.escape(error) or (
            "No recordings on this resource yet: record the charted variables on the Live "
            "tab, or with <code>padt record</code>."
        )
        return f'<div data-testid="recordings" style="color:{colour};padding:0 10px">{text}</div>'
    cell = "padding:2px 8px;border-bottom:1px solid #e9ecef"
    rows = []
    for x in listed:
        colour = _STATE_COLOURS.get(x.state, "#868e96")
        dropped = f'<span style="color:#c92a2a">{x.dropped:,}</span>' if x.dropped else "0"
        inputs = " + inputs" if x.all_inputs else ""
        name = html.escape(x.id)
        rows.append(
            f'<tr data-recording="{name}"><td style="{cell}">{name}</td>'
            f'<td style="{cell};color:{colour}" data-state>{html.escape(x.state)}</td>'
            f'<td style="{cell};text-align:right">{x.variables:,}{inputs}</td>'
            f'<td style="{cell};text-align:right" data-cycles>{x.cycles:,}</td>'
            f'<td style="{cell};text-align:right">{dropped}</td>'
            f'<td style="{cell};text-align:right">{_size(x)}</td>'
            f'<td style="{cell}">{_clock(x.started_ns / 1e9, date=True)}</td></tr>'
        )
    head = "".join(
        f'<th style="{cell};text-align:{align};color:#868e96;font-weight:500">{name}</th>'
        for name, align in (
            ("Recording", "left"), ("State", "left"), ("Variables", "right"),
            ("Cycles", "right"), ("Dropped", "right"), ("Size", "right"), ("Started", "left"),
        )
    )  # fmt: skip
    style = "width:calc(100% - 24px);margin:8px 14px 0 10px;border-collapse:collapse"
    return (
        f'<table data-testid="recordings" style="{style};font-size:0.85em"><tr>{head}</tr>'
        f"{''.join(rows)}</table>"
    )


def _size(recording: p.RecordingInfo) -> str:
    size = sum(f.size for f in recording.files)
    if size >= 1024 * 1024:
        return f"{size / 1024 / 1024:.1f} MB"
    return f"{size / 1024:.0f} KB" if size >= 1024 else f"{size} B"


def _clock(unix_s: float, date: bool = False) -> str:
    """The PADT's local time, to the millisecond (or the second with the date)."""
    moment = datetime.fromtimestamp(unix_s)
    return moment.strftime("%Y-%m-%d %H:%M:%S") if date else moment.strftime("%H:%M:%S.%f")[:-3]


def _show(screen: RecordedTab, part: str, handle: viser.GuiHtmlHandle, content: str) -> None:
    if screen.shown.get(part) != content:
        handle.content = content
        screen.shown[part] = content
