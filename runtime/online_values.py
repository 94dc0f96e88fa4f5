"""Online values (spec section 12): what clients view, as watch sets, and the values of a
set as one cycle left them, each with its quality. Only the reading happens between two
cycles; the message is built on the link's publisher thread (`WatchSnapshot.message`)."""

from __future__ import annotations

from typing import Any

from runtime.contract.protocol import ProgramState, Quality
from runtime.force_table import ForceTable
from runtime.variables import Variables
from runtime.watch_sets import WatchSet, WatchSets, WatchSnapshot

# plain strings: an enum member's lookup costs more than the rest of a value's work
_QUALITIES = tuple(
    str(q.value)
    for q in (Quality.LIVE, Quality.FORCED, Quality.STALE, Quality.DELETED, Quality.BAD)
)
_RUNNING = (ProgramState.RUN, ProgramState.RUN_FREEZE)


class OnlineValues:
    def __init__(self, variables: Variables) -> None:
        self._variables = variables
        self.watches = WatchSets()

    def watch(
        self,
        watch_id: str,
        names: list[str],
        period_ms: int,
        append: bool,
        owner: str | None,
        now_ns: int,
    ) -> list[str]:
        """Register what a client views, for the session `owner`; returns the canonical
        paths (all names must exist: a typo gets an error, not a silently empty field).
        `append` adds to a set (a large set arrives in several requests)."""
        paths = tuple(self._variables.lookup(name).path.path for name in names)
        existing = self.watches.get(watch_id) if append else None
        if existing is not None:
            paths = existing.paths + paths
        self.watches.set(WatchSet(watch_id, paths, period_ms * 1_000_000, owner, now_ns))
        return list(paths)

    def snapshot(
        self,
        watch_set: WatchSet,
        cycle: int,
        running: bool,
        forces: ForceTable,
        bad: frozenset[str] = frozenset(),
    ) -> WatchSnapshot:
        """A set's values now: live; forced; stale when nothing that could change it runs;
        deleted by a reload; bad: an input of a lost remote device (`bad`: upper-case
        paths), holding its safe value."""
        forcing = bool(forces.started_levels())
        halted = {id(p) for p in self._variables.programs if p.state not in _RUNNING}
        # this runs between two cycles for every watched value: names looked up once
        find, read, is_forced = self._variables.find, self._variables.read, forces.is_forced
        live, forced, stale, deleted, lost = _QUALITIES
        entries: list[tuple[str, Any, str]] = []
        append = entries.append
        for path in watch_set.paths:
            bound = find(path)
            if bound is None:
                append((path, None, deleted))
                continue
            if forcing and is_forced(path):
                quality = forced
            elif bad and path.upper() in bad:
                quality = lost
            elif not running or (bound.program is not None and id(bound.program) in halted):
                quality = stale
            else:
                quality = live
            append((path, read(bound), quality))
        return WatchSnapshot(cycle, entries)
