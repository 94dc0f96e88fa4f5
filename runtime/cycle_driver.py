"""Drives a resource in real time: a CPU cycle, then housekeeping (commands, publishing)
until the next cycle is due. In STOP the loop goes on: it still serves communication."""

from __future__ import annotations

import queue
import threading

from runtime.clock import Clock
from runtime.commands import execute
from runtime.link import ResourceLink
from runtime.resource import Resource

STATUS_PERIOD_NS = 1_000_000_000


class CycleDriver:
    def __init__(self, resource: Resource, clock: Clock, link: ResourceLink) -> None:
        self.resource = resource
        self.clock = clock
        self.link = link
        self._last_status: dict[str, object] | None = None
        self._last_status_ns = 0

    def run(self, stop: threading.Event) -> None:
        next_cycle = self.clock.now_ns()
        while not stop.is_set():
            cycle_before = self.resource.cycle_count
            self.resource.cycle()
            if self.resource.cycle_count != cycle_before:
                self.link.publish_values(self.resource.cycle_count, self.resource.values())
            self._publish_status()
            next_cycle += self.resource.cycle_ns
            self._housekeeping(next_cycle, stop)
            now = self.clock.now_ns()
            if now > next_cycle + self.resource.cycle_ns:
                next_cycle = now  # an overrun: start afresh instead of racing to catch up

    def _housekeeping(self, deadline_ns: int, stop: threading.Event) -> None:
        while not stop.is_set():
            remaining = deadline_ns - self.clock.now_ns()
            if remaining <= 0:
                return
            try:
                query = self.link.inbox.get(timeout=min(remaining / 1e9, 0.2))
            except queue.Empty:
                continue
            cycle_before = self.resource.cycle_count
            self.link.reply(query, execute(self.resource, self.link.payload(query)))
            del query  # a Zenoh query is finalised when its last reference goes
            if self.resource.cycle_count != cycle_before:  # a single step ran
                self.link.publish_values(self.resource.cycle_count, self.resource.values())
            self._publish_status()

    def _publish_status(self) -> None:
        """Publish on change (cycle statistics aside) and at least every second."""
        status = self.resource.status()
        significant = {k: v for k, v in status.items() if k not in ("stats", "cycle")}
        now = self.clock.now_ns()
        if significant != self._last_status or now - self._last_status_ns >= STATUS_PERIOD_NS:
            self.link.publish_status(status)
            self._last_status = significant
            self._last_status_ns = now
