"""Keeping the cycle collector's full collections short: the objects of the running
configuration (instances, generated classes, their namespace) are taken out of its sight
with `gc.freeze()`. With 10,000 variables a full collection walked them for 46 ms, on
whatever thread happened to allocate, the cycle thread included.

The freeze waits for the first full collection after a configuration arrives (load,
reload, cold start): the configuration it replaces holds reference cycles (its classes
and their namespace), which only that collection frees. Frozen before, they would never
be freed: a leak on every reload. Instances themselves are freed by their reference
counts, frozen or not. In STOP (after a load) that collection is made at once: no cycle
waits for it there, while a running one would meet it later on whatever thread allocated,
a stall of up to 70 ms seen in the first seconds of watching 10,000 values."""

from __future__ import annotations

import gc

_OLDEST = 2


class CollectorFreeze:
    """Process-wide, as the collector is; the cycle thread calls it."""

    def __init__(self) -> None:
        self._waiting_since: int | None = None  # full collections when a change came

    def configuration_changed(self) -> None:
        """New objects came and old ones may be garbage: all of them back in sight."""
        gc.unfreeze()
        self._waiting_since = _full_collections()

    def between_cycles(self, running: bool = True) -> None:
        """Freeze once a full collection has run since the change, made here when no
        cycle runs (cheap otherwise)."""
        if self._waiting_since is None:
            return
        if not running:
            gc.collect()
        if _full_collections() > self._waiting_since:
            gc.freeze()
            self._waiting_since = None

    @property
    def frozen(self) -> bool:
        return self._waiting_since is None and gc.get_freeze_count() > 0


def _full_collections() -> int:
    return int(gc.get_stats()[_OLDEST]["collections"])


COLLECTOR = CollectorFreeze()
