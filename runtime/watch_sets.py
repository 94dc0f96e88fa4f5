"""Watch sets: what each client views, so that only that is sent (spec section 12).

A client registers a set of variables and a period; after the CPU cycle in which a period
has passed, the runtime sends the set's values (those of that cycle) in one message, each
with its quality. A client holds a liveliness token for each of its sets; when the client
goes away, Zenoh withdraws the token and the runtime drops the set.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from runtime.contract.values import jsonable

MAX_SETS = 64


@dataclass
class WatchSet:
    watch_id: str
    paths: tuple[str, ...]  # canonical variable paths, in the client's order
    period_ns: int
    next_due_ns: int = 0  # clock time after which it is sent again


@dataclass(frozen=True)
class WatchSnapshot:
    """A set's values as one cycle left them, read between two cycles; the message is
    built from it elsewhere (on the link's publisher thread)."""

    cycle: int
    entries: list[tuple[str, Any, str]]  # (path, value, quality)

    def message(self) -> dict[str, Any]:
        return {
            "cycle": self.cycle,
            "values": {
                path: {"value": jsonable(value), "quality": quality}
                for path, value, quality in self.entries
            },
        }


class WatchSets:
    def __init__(self) -> None:
        self._sets: dict[str, WatchSet] = {}

    def set(self, watch_set: WatchSet) -> None:
        """Register (or replace) a set; it is due at once."""
        self._sets[watch_set.watch_id] = watch_set

    def drop(self, watch_id: str) -> bool:
        return self._sets.pop(watch_id, None) is not None

    def ids(self) -> list[str]:
        return sorted(self._sets)

    def full(self, watch_id: str) -> bool:
        return watch_id not in self._sets and len(self._sets) >= MAX_SETS

    def get(self, watch_id: str) -> WatchSet | None:
        return self._sets.get(watch_id)

    def due(self, now_ns: int, all_of_them: bool = False) -> list[WatchSet]:
        """The sets to send now (`all_of_them`: after a command, which may have changed
        what they show). A set that was due is next due one period after it was due, so
        the rate does not drift by the part of a cycle it waited; one that fell a whole
        period behind starts afresh."""
        sending = []
        for _, watch_set in sorted(self._sets.items()):
            if now_ns >= watch_set.next_due_ns:
                following = watch_set.next_due_ns + watch_set.period_ns
                watch_set.next_due_ns = (
                    following if following > now_ns else now_ns + watch_set.period_ns
                )
                sending.append(watch_set)
            elif all_of_them:
                sending.append(watch_set)
        return sending
