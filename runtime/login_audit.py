"""Failed logins in the event log without letting them crowd it (spec section 13): they go
to the short-term log only, the first of each name and source in an interval as an event
of its own, the others of that interval counted and reported with the next event of that
name and source (or its next successful login). A flood of failures therefore costs one
event per name, source and interval, and never a place in the long-term log, which keeps
the user actions."""

from __future__ import annotations

from collections import OrderedDict
from dataclasses import dataclass

INTERVAL_NS = 10 * 10**9
MAX_TRACKED = 10_000  # (name, source) pairs; the oldest are reported and forgotten


@dataclass
class _Window:
    started_ns: int
    unreported: int = 0


class LoginAudit:
    def __init__(self) -> None:
        self._windows: OrderedDict[tuple[str, str], _Window] = OrderedDict()

    def failed(self, name: str, source: str, now_ns: int) -> int | None:
        """A failed login: None when it is only counted; otherwise it is to be an event,
        which also reports the failures counted before it (their number)."""
        key = (name, source)
        window = self._windows.get(key)
        if window is not None and now_ns - window.started_ns < INTERVAL_NS:
            window.unreported += 1
            return None
        self._windows[key] = _Window(now_ns)
        self._windows.move_to_end(key)
        while len(self._windows) > MAX_TRACKED:
            self._windows.popitem(last=False)
        return window.unreported if window is not None else 0

    def succeeded(self, name: str, source: str) -> int:
        """A successful login ends the counting: the failures not yet reported."""
        window = self._windows.pop((name, source), None)
        return window.unreported if window is not None else 0
