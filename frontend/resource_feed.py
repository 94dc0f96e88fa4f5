"""What the UI knows of its resource: the last status, the variables and their types, and
the live values, each with its quality, of the variables the screens show now. Only those
are watched: a browser looking at 25 rows of a 10,000-variable resource costs the runtime
25 values per publication. Zenoh callbacks and one worker thread write it; the UI's
refresher reads it; `version` tells the refresher whether anything changed."""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from typing import Any

from backend.engineering.resource_client import (
    ResourceClient,
    ResourceUnreachable,
    WatchHandle,
)
from runtime.contract.protocol import GetStatus, GetVariables, Status, WatchValues
from runtime.contract.refusal import Refusal

WATCH_PERIOD_MS = 100
RETRY_S = 1.0  # an unreachable runtime: try again this much later
log = logging.getLogger("padt.ui")


@dataclass(frozen=True)
class Reach:
    """Whether the runtime process is on the bus (its liveliness token), and the last time
    it was not: the status bar says so, as the values shown meanwhile are the last known."""

    away_since_ns: int | None = None  # gone since (wall clock); None: there
    last_outage: tuple[int, int] | None = None  # (gone, back) of the last time it was away


@dataclass
class Latest:
    """What the runtime last told us."""

    lock: threading.Lock = field(default_factory=threading.Lock)
    status: Status | None = None
    values: dict[str, Any] = field(default_factory=dict)
    quality: dict[str, str] = field(default_factory=dict)  # live / forced / stale / deleted
    types: dict[str, str] = field(default_factory=dict)
    types_version: int = 0  # changes with the set of variables (a new configuration)
    cycle: int = 0
    version: int = 0  # changes with anything above
    values_version: int = 0  # changes with the values (and their qualities) only
    reach: Reach = field(default_factory=Reach)


class ResourceFeed:
    def __init__(
        self,
        client: ResourceClient,
        on_news: Callable[[], None] = lambda: None,
        clock: Callable[[], int] = time.time_ns,
    ) -> None:
        """`on_news` is called after every change of `latest` (from Zenoh's threads: it
        must not wait); `clock`: the wall clock in ns, for when the runtime went and came."""
        self.client = client
        self._on_news = on_news
        self._clock = clock
        self.latest = Latest()
        self._wanted: tuple[str, ...] = ()
        self._watch: WatchHandle | None = None
        self._registered: tuple[str, ...] | None = None  # what the runtime's set holds
        self._variables_known = False
        self._generation = 0  # counts the reasons to register again (alive, new CRC, login)
        self._closed = False
        self._wake = threading.Event()
        client.on_status(self.show_status)
        client.on_alive(self._on_alive)
        threading.Thread(target=self._keep_watching, daemon=True).start()
        self.restart()

    def show(self, paths: Iterable[str]) -> None:
        """The variables the screens show now: from the next publication on, only these
        arrive. Cheap when nothing changed (called ten times a second)."""
        wanted = tuple(sorted(set(paths)))
        if wanted != self._wanted:
            self._wanted = wanted
            self._wake.set()

    def restart(self) -> None:
        """Fetch everything again (after a login to the resource: what it may see now)."""
        threading.Thread(target=self._fetch_status, daemon=True).start()
        self._forget_registration(variables_too=True)

    def close(self) -> None:
        self._closed = True
        self._wake.set()

    def show_status(self, status: Status) -> None:
        with self.latest.lock:
            crc_changed = self.latest.status is None or status.crc != self.latest.status.crc
            self.latest.status = status
            self.latest.version += 1
        self._on_news()
        if crc_changed:  # a (new) configuration: learn its variables
            self._forget_registration(variables_too=True)

    def _fetch_status(self) -> None:
        """Show the resource at once, not only after its next publication."""
        try:
            status = self.client.ask(GetStatus()).status
        except (Refusal, ResourceUnreachable) as exc:
            log.info("%s; waiting for its status", exc)
            return
        self.show_status(status)

    def _on_alive(self, present: bool) -> None:
        """A runtime that (re)appears knows nothing of our watch set: register it again.
        Its going and coming are noted for the status bar."""
        now = self._clock()
        with self.latest.lock:
            reach = self.latest.reach
            if not present and reach.away_since_ns is None:
                self.latest.reach = Reach(now, reach.last_outage)
            elif present and reach.away_since_ns is not None:
                self.latest.reach = Reach(None, (reach.away_since_ns, now))
            changed = self.latest.reach is not reach
            if changed:
                self.latest.version += 1
        if changed:
            self._on_news()
        if present:
            self._forget_registration(variables_too=False)

    def _forget_registration(self, variables_too: bool) -> None:
        if variables_too:
            self._variables_known = False
        self._registered = None
        self._generation += 1
        self._wake.set()

    def _keep_watching(self) -> None:
        """The one thread that talks to the runtime about the watch set, so that Zenoh's
        and viser's threads never wait for an answer, and changes come in order."""
        while not self._closed:
            self._wake.wait()
            self._wake.clear()
            if self._closed:
                break
            try:
                if not self._variables_known:
                    self._load_variables()
                self._register()
            except Refusal as refused:  # e.g. not logged in: again at the next reason
                log.info("watch of %s: %s", self.client.resource, refused.message)
            except ResourceUnreachable as exc:
                log.info("watch of %s: %s; trying again", self.client.resource, exc)
                self._wake.wait(RETRY_S)  # a pause before the retry, cut short by a change
                self._wake.set()
        if self._watch is not None:
            self._watch.close()
            self._watch = None

    def _load_variables(self) -> None:
        generation = self._generation
        variables = self.client.ask(GetVariables()).variables
        with self.latest.lock:
            self.latest.types = {v.path: v.type for v in variables}
            self.latest.types_version += 1
            self.latest.version += 1
        self._variables_known = generation == self._generation  # else: a newer configuration
        self._registered = None

    def _register(self) -> None:
        generation = self._generation
        with self.latest.lock:
            known = self.latest.types
        # a watch list may name variables this configuration lacks: the runtime would
        # refuse the whole set for one of them; the screen says they are unknown
        wanted = tuple(path for path in self._wanted if path in known)
        if wanted == self._registered:
            return
        if self._watch is None:
            self._watch = self.client.watch(list(wanted), self._on_watch, WATCH_PERIOD_MS)
        else:
            self.client.change_watch(self._watch, list(wanted), WATCH_PERIOD_MS)
        if generation == self._generation:  # else a reason came meanwhile: once more
            self._registered = wanted

    def _on_watch(self, message: WatchValues) -> None:
        with self.latest.lock:
            self.latest.values = {path: entry.value for path, entry in message.values.items()}
            self.latest.quality = {path: entry.quality for path, entry in message.values.items()}
            self.latest.cycle = message.cycle
            self.latest.version += 1
            self.latest.values_version += 1
        self._on_news()


def latest_values(
    feed: ResourceFeed | None,
) -> tuple[dict[str, Any], dict[str, str], dict[str, str]]:
    """The feed's latest values, types and qualities, read together (empty without one)."""
    if feed is None:
        return {}, {}, {}
    _, values, types, quality = latest_reading(feed)
    return values, types, quality


def latest_reading(
    feed: ResourceFeed,
) -> tuple[Status | None, dict[str, Any], dict[str, str], dict[str, str]]:
    """The feed's last status with its values, types and qualities, read together (the
    values belong to the configuration the status names)."""
    latest = feed.latest
    with latest.lock:
        return latest.status, latest.values, latest.types, latest.quality
