"""The force table: the prepared force values, their switches, and the levels where forcing
is started (with their time limits).

Two levels: global forcing (globals and I/O, allowed per resource) and local forcing (the
variables of one user program, allowed per program). A variable is forced only while its
force switch is ON *and* forcing has been started at its level. Starting may set a time
limit; what happens when it runs out is the level's timeout reaction, carried out by the
resource. The table holds no variable values of its own besides the forced ones: applying
them to the program data is the resource's job.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

GLOBAL = ""  # the level key of global forcing; local levels are keyed by program name


@dataclass
class ForceEntry:
    path: str  # canonical variable path
    level: str  # GLOBAL or a program name
    value: Any  # in the run-time representation of the variable's type
    switch: bool = True


@dataclass
class ForceLevel:
    started_ns: int
    deadline_ns: int | None  # None: no time limit


class ForceTable:
    # slots: the CPU cycle in C reads them at their offsets (padt_cycle.c)
    __slots__ = (
        "_entries",
        "levels",
    )

    def __init__(self) -> None:
        self._entries: dict[str, ForceEntry] = {}  # by upper-case path
        self.levels: dict[str, ForceLevel] = {}  # levels where forcing is started

    # ---- entries
    def set(self, entry: ForceEntry) -> ForceEntry | None:
        """Prepare (or change) a force value; returns the entry it replaces."""
        previous = self._entries.get(entry.path.upper())
        self._entries[entry.path.upper()] = entry
        return previous

    def remove(self, path: str) -> ForceEntry | None:
        return self._entries.pop(path.upper(), None)

    def entry(self, path: str) -> ForceEntry | None:
        return self._entries.get(path.upper())

    def entries(self) -> list[ForceEntry]:
        return [self._entries[key] for key in sorted(self._entries)]

    def remove_level(self, level: str) -> None:
        """Forget the entries of a level (its program is gone after a load)."""
        for key in [k for k, e in sorted(self._entries.items()) if e.level == level]:
            del self._entries[key]

    # ---- levels
    def start(self, level: str, now_ns: int, timeout_ns: int | None) -> None:
        deadline = now_ns + timeout_ns if timeout_ns is not None else None
        self.levels[level] = ForceLevel(now_ns, deadline)

    def stop(self, level: str) -> bool:
        """End forcing at a level; True when it was started."""
        return self.levels.pop(level, None) is not None

    def stop_all(self) -> list[str]:
        """End forcing everywhere; the levels that were started."""
        stopped = sorted(self.levels)
        self.levels.clear()
        return stopped

    def started(self, level: str) -> bool:
        return level in self.levels

    def started_levels(self) -> list[str]:
        return sorted(self.levels)

    def remaining_ns(self, level: str, now_ns: int) -> int | None:
        """Time left at a started level with a limit; None without a limit or not started."""
        state = self.levels.get(level)
        if state is None or state.deadline_ns is None:
            return None
        return max(0, state.deadline_ns - now_ns)

    def expired(self, now_ns: int) -> list[str]:
        """Started levels whose time limit has run out."""
        return [
            level
            for level, state in sorted(self.levels.items())
            if state.deadline_ns is not None and now_ns >= state.deadline_ns
        ]

    def active(self) -> list[ForceEntry]:
        """The entries in force now: switch ON and forcing started at their level."""
        if not self.levels:  # the usual case, checked twice per cycle
            return []
        return [e for e in self.entries() if e.switch and e.level in self.levels]

    def is_forced(self, path: str) -> bool:
        entry = self._entries.get(path.upper())
        return entry is not None and entry.switch and entry.level in self.levels
