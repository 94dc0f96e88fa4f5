"""Keeping CPython's cycle collector off the cycles' path.

A full collection walks every object in the collector's sight while holding the
interpreter lock, on whichever thread happened to allocate, the cycle thread included.
With 10,000 variables the runtime holds about 100,000 objects (its modules, Zenoh, the
configuration): a walk of 12-26 ms; with 100,000 variables, 70 ms. So the runtime
process, once up (`manage`), keeps everything frozen (`gc.freeze`: out of sight, still
freed by its reference counts), and what a configuration brings is frozen as soon as it
arrives (`arrived`: loaded, or prepared for a reload), a constant-time splice. Other
processes that run a resource (tests, tools) leave the collector as it is.

What freezing costs: a configuration replaced by a reload holds reference cycles (its
generated classes and their namespace), and only a full collection over everything frees
those once frozen, since CPython cannot unfreeze a part. Doing that after every reload
stalled a running cycle for the whole walk (45-115 ms seen while the next reload
prepared). So the replaced configurations' cycles wait, frozen, and are freed all at once
(`reclaim`): at once whenever the resource is in STOP, and in RUN only after
`RECLAIM_AFTER` arrivals (a reload brings two: prepared, then taken), which bounds what
waits to that many sets of classes (a few kB per POU type), not to any data: instances
are freed by their reference counts.

While a reload prepares (`held_back`), the collector makes no collection at all, young
ones included, and what was made meanwhile is frozen when the preparation ends: that is
the new configuration's arrival. Full collections would walk the new configuration,
growing on the worker thread, many times over; and the plan's lists and maps of every
variable are young when they are made: with 100,000 variables, one young collection
walking three of them took 8 ms, the next one 10 ms, each a stall of the cycle thread."""

from __future__ import annotations

import gc
import threading
from collections.abc import Iterator
from contextlib import contextmanager

RECLAIM_AFTER = 32  # arrivals whose reference cycles may wait, frozen, in RUN


class Collector:
    """Process-wide, as the collector is; `arrived` and `held_back` may be used on a
    reload's worker thread (two at once: the last to end freezes), the rest on the cycle
    thread."""

    def __init__(self) -> None:
        self.managed = False
        self.arrivals = 0  # freezes of new configurations since the last reclaim
        self._lock = threading.Lock()
        self._holding = 0  # how many `held_back` blocks are running
        self._arriving = False  # one of them is an arrival
        self._threshold: tuple[int, int, int] | None = None

    def manage(self) -> None:
        """From now on, in this process: what start-up left collected, the rest frozen."""
        self.managed = True
        self.reclaim()

    def release(self) -> None:
        """Everything back in sight, the collector as CPython leaves it (tests)."""
        self.managed = False
        self.arrivals = 0
        gc.unfreeze()

    def arrived(self) -> None:
        """A new configuration's objects out of sight now (before the switch-over of a
        reload, whose collections would walk them); the one it replaces waits."""
        if self.managed:
            self.arrivals += 1
            gc.freeze()

    def settled(self) -> None:
        """What a long-lived part just made (a field I/O server's monitored items) out of
        sight now, without counting as an arrival: it replaces nothing."""
        if self.managed:
            gc.freeze()

    def between_cycles(self, running: bool = True) -> None:
        """Free what replaced configurations left when no cycle waits for it (STOP), or,
        running, once enough of them wait."""
        if self.arrivals and (not running or self.arrivals >= RECLAIM_AFTER):
            self.reclaim()

    def reclaim(self) -> None:
        """One full collection over everything: frees the replaced configurations'
        reference cycles; then all is frozen again."""
        gc.unfreeze()
        gc.collect()
        gc.freeze()
        self.arrivals = 0

    @contextmanager
    def held_back(self, arrival: bool = True) -> Iterator[None]:
        """A reload's preparation: no collection meanwhile, in the whole process; at the
        end, what it made (and what the cycles made meanwhile) frozen, one arrival.
        `arrival` False: what a long-lived part makes (a field I/O server starting, its
        address space growing), frozen at the end without counting as an arrival, since
        it replaces nothing whose reference cycles wait."""
        if not self.managed:
            yield
            return
        with self._lock:
            if not self._holding:
                self._threshold = gc.get_threshold()
                gc.set_threshold(0)  # CPython: no automatic collection
            self._holding += 1
            self._arriving = self._arriving or arrival
        try:
            yield
        finally:
            with self._lock:
                self._holding -= 1
                if not self._holding and self._threshold is not None:
                    # the young objects' count starts again at 0 with the freeze: the next
                    # young collection walks only what is made from now on
                    if self._arriving:
                        self.arrived()
                    else:
                        gc.freeze()
                    self._arriving = False
                    gc.set_threshold(*self._threshold)
                    self._threshold = None


COLLECTOR = Collector()
