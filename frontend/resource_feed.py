"""What the UI knows of its resource: the last status, the variables and their types, and
the live values of one watch set of every variable (the runtime sends nothing else), each
with its quality. Zenoh callbacks write it; the UI's refresher reads it; `version` tells
the refresher whether anything changed."""

from __future__ import annotations

import logging
import threading
from dataclasses import dataclass, field
from typing import Any

from backend.engineering.resource_client import (
    ResourceClient,
    ResourceUnreachable,
    WatchHandle,
)
from runtime.contract.protocol import GetStatus, GetValues, GetVariables, Status, WatchValues
from runtime.contract.refusal import Refusal

WATCH_PERIOD_MS = 100
log = logging.getLogger("padt.ui")


@dataclass
class Latest:
    """What the runtime last told us."""

    lock: threading.Lock = field(default_factory=threading.Lock)
    status: Status | None = None
    values: dict[str, Any] = field(default_factory=dict)
    quality: dict[str, str] = field(default_factory=dict)  # live / forced / stale / deleted
    types: dict[str, str] = field(default_factory=dict)
    cycle: int = 0
    version: int = 0


class ResourceFeed:
    def __init__(self, client: ResourceClient) -> None:
        self.client = client
        self.latest = Latest()
        self._watch: WatchHandle | None = None
        self._watching = threading.Lock()
        client.on_status(self.show_status)
        client.on_alive(self._on_alive)
        self.restart()

    def restart(self) -> None:
        """Fetch everything again (after a login to the resource: what it may see now)."""
        threading.Thread(target=self._fetch_initial, daemon=True).start()
        threading.Thread(target=self._load_variables, daemon=True).start()

    def close(self) -> None:
        with self._watching:
            if self._watch is not None:
                self._watch.close()
                self._watch = None

    def show_status(self, status: Status) -> None:
        with self.latest.lock:
            crc_changed = self.latest.status is None or status.crc != self.latest.status.crc
            self.latest.status = status
            self.latest.version += 1
        if crc_changed:
            # a (new) configuration: learn its variables; ask outside Zenoh's thread
            threading.Thread(target=self._load_variables, daemon=True).start()

    def _fetch_initial(self) -> None:
        """Show the resource at once, not only after its next publication."""
        try:
            status = self.client.ask(GetStatus()).status
            values = self.client.ask(GetValues())
        except (Refusal, ResourceUnreachable) as exc:
            log.info("%s; waiting for its status", exc)
            return
        self.show_status(status)
        with self.latest.lock:
            self.latest.values, self.latest.cycle = values.values, values.cycle
            self.latest.version += 1

    def _on_alive(self, present: bool) -> None:
        """A runtime that (re)appears knows nothing of our watch set: register it again
        (outside Zenoh's thread)."""
        if present:
            threading.Thread(target=self._load_variables, daemon=True).start()

    def _load_variables(self) -> None:
        with self._watching:  # a new configuration and a restarted runtime may coincide
            try:
                variables = self.client.ask(GetVariables()).variables
            except (Refusal, ResourceUnreachable) as exc:
                log.warning("no variables: %s", exc)
                return
            types = {v.path: v.type for v in variables}
            with self.latest.lock:
                self.latest.types = types
                self.latest.version += 1
            if self._watch is not None:
                self._watch.close()
                self._watch = None
            try:
                self._watch = self.client.watch(sorted(types), self._on_watch, WATCH_PERIOD_MS)
            except (Refusal, ResourceUnreachable) as exc:
                log.warning("no live values: %s", exc)

    def _on_watch(self, message: WatchValues) -> None:
        with self.latest.lock:
            self.latest.values = {path: entry.value for path, entry in message.values.items()}
            self.latest.quality = {path: entry.quality for path, entry in message.values.items()}
            self.latest.cycle = message.cycle
            self.latest.version += 1
