"""The Events screen: a resource's event log, live. The short-term log (every event, the
resource's ring) or the long-term log (user actions and configuration changes, kept on
disk and hash-chained), newest first, filtered by kind, user and time, a bounded number of
rows with the count of what the filter matched; and the state of the long-term log's hash
chain as this PADT checked it (backend/engineering/event_chain.py).

The existing events are read with `events` (paged), the new ones arrive as the resource
publishes them: Zenoh's thread only copies them into a list under a lock; the refresher
merges them and reads the long-term log on after a new event, in a thread of its own."""

from __future__ import annotations

import html
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from datetime import datetime
from typing import Literal

import viser

from backend.engineering.event_chain import ChainState, check_chain
from backend.engineering.resource_client import ResourceClient, ResourceUnreachable
from frontend.screen_registry import Now, Screen, Work
from runtime.contract import protocol as p
from runtime.contract.refusal import Refusal

MAX_ROWS = 200  # rows shown; the count says how many matched
KEEP = 1000  # short-term events kept here: as many as the resource's ring holds
RETRY_S = 5.0  # a refused or unanswered read of the log is tried again after this
MAX_LIVE = 10_000  # live events waiting for the refresher (a burst while it is held up)
LOGS = ("Short-term (every event)", "Long-term (user actions, configuration)")
SINCE: dict[str, int | None] = {
    "all": None,
    "last 10 min": 600,
    "last hour": 3600,
    "last 24 hours": 86_400,
}
ALL_KINDS, ALL_USERS, NO_USER = "(all kinds)", "(all users)", "(no user)"
_CELL = "padding:3px 8px;border-bottom:1px solid #e9ecef;vertical-align:top"
_GREY = "color:#868e96"
KIND_COLORS = {"error": "#c92a2a", "watchdog": "#c92a2a", "rejected": "#c92a2a"}


class EventFeed:
    """The event log of one resource as one browser's login may read it."""

    def __init__(self, client: ResourceClient) -> None:
        self._client = client
        self._lock = threading.Lock()
        self.short: list[p.Event] = []  # oldest first
        self.long: list[p.Event] = []
        self.chain = ChainState()
        self.error = ""
        self.loaded = False  # the short-term log has been read: live events count
        self.version = 0  # goes up with every change, so the screen renders only then
        self.kinds_seen: dict[str, int] = {}  # live events by kind (other screens read on)
        self._live: list[p.Event] = []
        self._reading_short = False
        self._reading_long = False
        self._long_due = True
        self._failed_at = 0.0
        self._closed = False
        client.on_events(self._on_event)
        self._start(self._read_short)

    def close(self) -> None:
        """Another login or resource: this feed's subscription ignores what comes."""
        with self._lock:
            self._closed = True

    def _on_event(self, event: p.Event) -> None:
        # Zenoh's thread: copy, nothing else
        with self._lock:
            if not self._closed and len(self._live) < MAX_LIVE:
                self._live.append(event)

    def pump(self) -> None:
        """The refresher's call: take the live events in; read on where they do not follow
        (a gap, or a restarted runtime whose numbers start again), and the long-term log
        after anything new."""
        with self._lock:
            if not self.loaded:
                if self.error:  # not ours to see (or no answer): read again now and then
                    self._live.clear()
                    if time.monotonic() - self._failed_at > RETRY_S:
                        self._start_locked(self._read_short)
                return  # until the first read is in, live events wait (it may cover them)
            live, self._live = self._live, []
            for event in live:
                last = self.short[-1].seq if self.short else 0
                if event.seq == last + 1 or not self.short:
                    self.short.append(event)
                    self._long_due = True
                    self.kinds_seen[event.kind] = self.kinds_seen.get(event.kind, 0) + 1
                elif event.seq > last:  # missed some: read on from the last one we have
                    self._start_locked(self._read_short)
                    break
                elif not self._known(event):  # numbers start again: a restarted runtime
                    self.short, self.long, self.chain = [], [], ChainState()
                    self.loaded = False
                    self._start_locked(self._read_short)
                    break
            del self.short[:-KEEP]
            if live:
                self.version += 1
            if self._long_due and not self._reading_long:
                self._long_due = False
                self._reading_long = True
                threading.Thread(target=self._read_long, daemon=True).start()

    def _known(self, event: p.Event) -> bool:
        """Whether the event is one we have (read and published both)."""
        for mine in reversed(self.short):
            if mine.seq == event.seq:
                return mine.time_ns == event.time_ns
            if mine.seq < event.seq:
                return False
        return False

    def live_count(self, kind: str) -> int:
        with self._lock:
            return self.kinds_seen.get(kind, 0)

    def snapshot(self, long_term: bool) -> tuple[list[p.Event], ChainState, bool, str, int]:
        """The events of one log, the chain, whether read, why not, and the version."""
        with self._lock:
            events = list(self.long if long_term else self.short)
            return events, self.chain, self.loaded, self.error, self.version

    def _start(self, target: Callable[[], None]) -> None:
        with self._lock:
            self._start_locked(target)

    def _start_locked(self, target: Callable[[], None]) -> None:
        if not self._reading_short:
            self._reading_short = True
            threading.Thread(target=target, daemon=True).start()

    def _pages(self, log: Literal["short", "long"], after: int) -> tuple[list[p.Event], list[str]]:
        """Every entry after `after`, page by page."""
        events: list[p.Event] = []
        prevs: list[str] = []
        while True:
            reply = self._client.ask(p.GetEvents(after, p.MAX_EVENTS, log))
            events += reply.events
            prevs += reply.prev
            if len(reply.events) < p.MAX_EVENTS:
                return events, prevs
            after = reply.events[-1].seq

    def _read_short(self) -> None:
        with self._lock:
            after = self.short[-1].seq if self.short else 0
        try:
            events, _ = self._pages("short", after)
            error = ""
        except Refusal as refused:
            events, error = [], _why(refused)
        except ResourceUnreachable as exc:
            events, error = [], str(exc)
        with self._lock:
            self._reading_short = False
            self.error = error
            self._failed_at = time.monotonic()
            if not error:
                last = self.short[-1].seq if self.short else 0
                self.short += [x for x in events if x.seq > last]
                del self.short[:-KEEP]
                self.loaded = True
            self.version += 1

    def _read_long(self) -> None:
        with self._lock:
            after = self.long[-1].seq if self.long else 0
            chain = self.chain
        try:
            events, prevs = self._pages("long", after)
        except (Refusal, ResourceUnreachable):
            events, prevs = [], []  # the short-term read says why; try with the next event
        chain = check_chain(events, prevs, chain) if events else chain
        with self._lock:
            self._reading_long = False
            if events and (not self.long or self.long[-1].seq == after):
                self.long += events
                self.chain = chain
                self.version += 1


def _why(refused: Refusal) -> str:
    if refused.code in ("unauthenticated", "forbidden"):
        return "log in to the resource to see its event log"
    return f"{refused.code}: {refused.message}"


# ---- filtering and rendering: plain functions


@dataclass(frozen=True)
class Filter:
    kind: str = ALL_KINDS
    user: str = ALL_USERS
    since_s: int | None = None
    from_ns: int | None = None  # the range typed, local time: from its first moment
    to_ns: int | None = None  # up to and including its last


_MOMENT_FORMATS = (  # with how much of its unit "to" takes in
    ("%Y-%m-%d %H:%M:%S", 1),
    ("%Y-%m-%d %H:%M", 60),
    ("%Y-%m-%d", 86_400),
)


def parse_moment(text: str, end: bool) -> tuple[int | None, str]:
    """A moment typed as local time, "2026-11-24", "2026-11-24 14:05" or with seconds:
    its first nanosecond, or with `end` its last (the whole day or minute named); None
    when empty; and what is wrong when it is no such moment."""
    text = text.strip()
    if not text:
        return None, ""
    for pattern, unit_s in _MOMENT_FORMATS:
        try:
            moment = datetime.strptime(text, pattern).astimezone()
        except ValueError:
            continue
        first = int(moment.timestamp()) * 10**9
        return (first + unit_s * 10**9 - 1 if end else first), ""
    return None, f"'{text[:40]}' is no date and time like 2026-11-24 14:05"


def matches(event: p.Event, chosen: Filter, now_ns: int) -> bool:
    if chosen.kind != ALL_KINDS and event.kind != chosen.kind:
        return False
    if chosen.user == NO_USER and event.user is not None:
        return False
    if chosen.user not in (ALL_USERS, NO_USER) and event.user != chosen.user:
        return False
    if chosen.from_ns is not None and event.time_ns < chosen.from_ns:
        return False
    if chosen.to_ns is not None and event.time_ns > chosen.to_ns:
        return False
    return chosen.since_s is None or event.time_ns >= now_ns - chosen.since_s * 10**9


def select(events: list[p.Event], chosen: Filter, now_ns: int) -> tuple[list[p.Event], int]:
    """The rows to show, newest first, at most MAX_ROWS; and how many matched."""
    matching = [x for x in reversed(events) if matches(x, chosen, now_ns)]
    return matching[:MAX_ROWS], len(matching)


def local_time(time_ns: int) -> str:
    moment = datetime.fromtimestamp(time_ns / 1e9).astimezone()
    return moment.strftime("%Y-%m-%d %H:%M:%S.%f")[:-3]


def render_chain(chain: ChainState, loaded: bool) -> str:
    if chain.broken_seq is not None:
        colour, mark = "#c92a2a", "✗"
    elif chain.entries and loaded:
        colour, mark = "#2b8a3e", "✓"
    else:
        colour, mark = "#868e96", "-"
    return (
        f'<div style="margin:2px 0 6px"><span style="{_GREY}">Hash chain of the long-term '
        f'log:</span> <span data-testid="event-chain" style="color:{colour};font-weight:600">'
        f"{mark} {html.escape(chain.describe())}</span></div>"
    )


def render(
    shown: list[p.Event], matched: int, total: int, log_name: str, broken: int | None = None
) -> str:
    """The table; `broken`: the seq of the long-term entry where the chain breaks (marked)."""
    offset = datetime.now().astimezone().strftime("%z")
    head = "".join(
        f'<th style="{_CELL};text-align:left;white-space:nowrap">{name}</th>'
        for name in ("Seq", f"Time (UTC{offset[:3]}:{offset[3:]})", "Kind", "User", "Message")
    )
    rows = [_row(event, event.seq == broken) for event in shown]
    if not rows:
        rows = [f'<tr><td style="{_CELL};{_GREY}" colspan="5">No event matches.</td></tr>']
    more = f", the newest {len(shown)} shown" if matched > len(shown) else ""
    count = (
        f'<div data-testid="events-count" style="{_GREY};margin-bottom:2px">{matched} of '
        f"{total} events of the {log_name} log match{more}.</div>"
    )
    return (
        f'{count}<div style="overflow-x:auto"><table data-testid="events" '
        f'style="font-size:0.85em;border-collapse:collapse;width:100%"><tr>{head}</tr>'
        f"{''.join(rows)}</table></div>"
    )


def _row(event: p.Event, broken: bool = False) -> str:
    colour = KIND_COLORS.get(event.kind, "inherit")
    details = ", ".join(f"{k}={v}" for k, v in sorted(event.details.items()))
    title = f' title="{html.escape(details)}"' if details else ""
    mark = ' style="background:#fff5f5" title="the hash chain breaks here"' if broken else ""
    user = html.escape(event.user) if event.user is not None else f'<span style="{_GREY}">-</span>'
    return (
        f'<tr data-seq="{event.seq}" data-kind="{html.escape(event.kind)}"{mark}>'
        f'<td style="{_CELL};text-align:right;{_GREY}">{event.seq}</td>'
        f'<td style="{_CELL};white-space:nowrap;font-family:monospace">'
        f"{local_time(event.time_ns)}</td>"
        f'<td style="{_CELL};color:{colour};font-weight:600">{html.escape(event.kind)}</td>'
        f'<td style="{_CELL}" data-user>{user}</td>'
        f'<td style="{_CELL}"{title}>{html.escape(event.message)}</td></tr>'
    )


# ---- the screen


@dataclass
class EventsScreen:
    log: viser.GuiDropdownHandle[str]
    kind: viser.GuiDropdownHandle[str]
    user: viser.GuiDropdownHandle[str]
    since: viser.GuiDropdownHandle[str]
    start: viser.GuiTextHandle
    end: viser.GuiTextHandle
    chain: viser.GuiHtmlHandle
    table: viser.GuiHtmlHandle
    feeds: dict[tuple[str, str | None], EventFeed] = field(default_factory=dict)
    shown_key: tuple[object, ...] = ()
    shown_chain: str = ""


def build(gui: viser.GuiApi) -> EventsScreen:
    log = gui.add_dropdown("Log", LOGS)
    kind = gui.add_dropdown("By kind", (ALL_KINDS,))
    # not "User": the login to the resource has a text field of that name
    user = gui.add_dropdown("By user", (ALL_USERS,))
    since = gui.add_dropdown("Since", tuple(SINCE))
    hint = "local time: 2026-11-24, 2026-11-24 14:05 or 2026-11-24 14:05:30; empty: open"
    start = gui.add_text("From", "", hint=hint)
    end = gui.add_text("To", "", hint=hint + " (a day or minute counts whole)")
    chain = gui.add_html("")
    table = gui.add_html("")
    return EventsScreen(log, kind, user, since, start, end, chain, table)


def _feed(
    screen: EventsScreen,
    resource: str,
    login_token: str | None,
    client_of: Callable[[str], ResourceClient],
) -> EventFeed | None:
    key = (resource, login_token)
    feed = screen.feeds.get(key)
    if feed is None:
        for other in [k for k in screen.feeds if k[0] == resource]:
            screen.feeds.pop(other).close()  # a login made or changed: read again
        try:
            feed = screen.feeds[key] = EventFeed(client_of(resource))
        except Refusal:  # gone from the router
            return None
    return feed


def refresh(
    screen: EventsScreen,
    resource: str | None,
    login_token: str | None,
    client_of: Callable[[str], ResourceClient],
) -> None:
    feed = _feed(screen, resource, login_token, client_of) if resource is not None else None
    if feed is None:
        if screen.shown_key != ("none",):
            _update(screen, ("none",), "", "<p>Select a resource.</p>")
        return
    feed.pump()
    long_term = screen.log.value == LOGS[1]
    from_ns, from_error = parse_moment(screen.start.value, end=False)
    to_ns, to_error = parse_moment(screen.end.value, end=True)
    chosen = Filter(
        screen.kind.value, screen.user.value, SINCE.get(screen.since.value), from_ns, to_ns
    )
    now = time.time_ns()
    # a "since" window moves: then render again once a second even without a new event
    moving = now // 10**9 if chosen.since_s is not None else 0
    named = (("From", from_error), ("To", to_error))
    errors = [f"{name}: {error}" for name, error in named if error]
    key = (resource, login_token, feed.version, long_term, chosen, moving, tuple(errors))
    if key == screen.shown_key:
        return  # ten times a second: nothing to copy or render unless something changed
    events, chain, loaded, error, _ = feed.snapshot(long_term)
    _options(screen.kind, (ALL_KINDS, *sorted({x.kind for x in events})))
    users = sorted({x.user for x in events if x.user is not None})
    _options(screen.user, (ALL_USERS, *users, NO_USER))
    if not loaded:
        text = html.escape(error or "reading the event log ...")
        _update(screen, key, "", f'<p data-testid="events-note" style="{_GREY}">{text}</p>')
        return
    shown, matched = select(events, chosen, now)
    name = "long-term" if long_term else "short-term"
    broken = chain.broken_seq if long_term else None
    table = render(shown, matched, len(events), name, broken)
    _update(screen, key, render_chain(chain, loaded), _range_errors(errors) + table)


def newest(screen: EventsScreen, resource: str | None, count: int) -> list[dict[str, object]]:
    """The newest events of the resource's short-term log as this screen read them, newest
    first, as rows for the editor's bottom panel (plain values: the page escapes them);
    none before the log is read."""
    feeds = [feed for (name, _), feed in screen.feeds.items() if name == resource]
    if not feeds:
        return []
    events, _, loaded, _, _ = feeds[0].snapshot(long_term=False)
    if not loaded:
        return []
    return [
        {
            "seq": event.seq,
            "time": local_time(event.time_ns),
            "kind": event.kind,
            "color": KIND_COLORS.get(event.kind, "#212529"),
            "user": event.user or "-",
            "message": event.message,
        }
        for event in reversed(events[-count:])
    ]


def _range_errors(errors: list[str]) -> str:
    """A range field that is no moment is said in red; it filters nothing meanwhile."""
    lines = "".join(f"<div>{html.escape(error)}</div>" for error in errors)
    style = "color:#c92a2a;font-size:0.9em"
    return f'<div data-testid="range-errors" style="{style}">{lines}</div>' if errors else ""


def live_count(screen: EventsScreen, resource: str | None, kind: str) -> int:
    """How many events of a kind came live for the resource: another screen reads again
    what they changed (the Parameters screen after a `parameter` event from anyone)."""
    feeds = [feed for (name, _), feed in screen.feeds.items() if name == resource]
    return feeds[0].live_count(kind) if feeds else 0


def _options(dropdown: viser.GuiDropdownHandle[str], options: tuple[str, ...]) -> None:
    """New options; viser keeps the filter chosen while it is offered. Writing the value
    read before back would undo a choice the browser made meanwhile."""
    if tuple(dropdown.options) != options:
        dropdown.options = options


def _update(screen: EventsScreen, key: tuple[object, ...], chain: str, table: str) -> None:
    screen.shown_key = key
    if chain != screen.shown_chain:
        screen.chain.content = chain
        screen.shown_chain = chain
    screen.table.content = table


class Events(Screen):
    name = "Events"
    icon = viser.Icon.LIST_DETAILS

    def __init__(self, work: Work) -> None:
        super().__init__(work)
        self.screen = build(work.gui)

    def follow(self, now: Now) -> None:
        # always: its live counts tell the Parameters screen what others changed
        refresh(self.screen, now.resource, now.token, self.work.client_of)
