"""Logins in the event log without letting them crowd it (spec section 13).

Failed logins go to the short-term log only, the first of each name in an interval as an
event of its own, the others of that interval counted and reported with the next event of
that name (or its next successful login), with the sources the requests claimed (Zenoh
session ids: a sender names its own, so they tell who claimed to be whom, not who was).
A flood of failures therefore costs one event per name and interval, however many sources
it claims, and never a place in the long-term log, which keeps the user actions.

Successful logins are events of both logs, the first of an account in an interval only;
the others of that interval are counted and reported with its next one (by account alone:
a client may take a new source for every login). The long-term log keeps a bounded share
for logins besides (`event_recorder.LONG_TERM_SHARES`), and an account logs in at most at
a steady rate after a burst, so that a flood of logins neither displaces the actions nor
holds the resource.
"""

from __future__ import annotations

from collections import OrderedDict
from dataclasses import dataclass, field

INTERVAL_NS = 10 * 10**9
MAX_TRACKED = 10_000  # names; the oldest are forgotten
MAX_SOURCES = 16  # claimed sources listed with an event (the others are counted)
SUCCESS_INTERVAL_NS = 60 * 10**9  # one event per account and interval for its logins
LOGIN_BURST = 30  # logins of one account at once, then one per LOGIN_EVERY_NS
LOGIN_EVERY_NS = 500_000_000


@dataclass
class _Window:
    started_ns: int
    unreported: int = 0
    sources: list[str] = field(default_factory=list)  # claimed since the last report

    def claimed(self, source: str) -> None:
        if source not in self.sources and len(self.sources) < MAX_SOURCES:
            self.sources.append(source)


@dataclass(frozen=True)
class Failures:
    """What an event of failed logins reports: the failures counted before it, and the
    sources they and it claimed."""

    earlier: int
    sources: list[str]


@dataclass
class _Allowance:
    logins: float  # how many the account may begin now
    at_ns: int


class LoginAudit:
    def __init__(self) -> None:
        self._windows: OrderedDict[str, _Window] = OrderedDict()  # failures by name
        # by account (only the configuration's accounts: their number is bounded)
        self._successes: dict[str, _Window] = {}
        self._allowances: dict[str, _Allowance] = {}

    def may_begin(self, account: str, now_ns: int) -> bool:
        """Whether an account may begin another login now: LOGIN_BURST at once, then one
        every LOGIN_EVERY_NS (a flood of one account's logins is refused, `busy`)."""
        allowance = self._allowances.setdefault(account, _Allowance(LOGIN_BURST, now_ns))
        earned = (now_ns - allowance.at_ns) / LOGIN_EVERY_NS
        allowance.logins = min(LOGIN_BURST, allowance.logins + max(earned, 0))
        allowance.at_ns = now_ns
        if allowance.logins < 1:
            return False
        allowance.logins -= 1
        return True

    def logged_in(self, account: str, now_ns: int) -> int | None:
        """A successful login: None when it is only counted; otherwise it is to be an
        event, which also reports the logins of the account counted before it."""
        window = self._successes.get(account)
        if window is not None and now_ns - window.started_ns < SUCCESS_INTERVAL_NS:
            window.unreported += 1
            return None
        self._successes[account] = _Window(now_ns)
        return window.unreported if window is not None else 0

    def failed(self, name: str, source: str, now_ns: int) -> Failures | None:
        """A failed login: None when it is only counted; otherwise it is to be an event,
        which also reports the failures counted before it and the sources claimed."""
        window = self._windows.get(name)
        if window is not None and now_ns - window.started_ns < INTERVAL_NS:
            window.unreported += 1
            window.claimed(source)
            return None
        self._windows[name] = _Window(now_ns)
        self._windows.move_to_end(name)
        while len(self._windows) > MAX_TRACKED:
            self._windows.popitem(last=False)
        if window is None:
            return Failures(0, [source])
        window.claimed(source)
        return Failures(window.unreported, window.sources)

    def succeeded(self, name: str) -> Failures:
        """A successful login ends the counting: the failures not yet reported."""
        window = self._windows.pop(name, None)
        if window is None:
            return Failures(0, [])
        return Failures(window.unreported, window.sources)
