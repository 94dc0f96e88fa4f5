"""Where the runtime takes its time from: a real clock in operation, a virtual one in
simulation, single step and tests, so that runs are reproducible to the bit."""

from __future__ import annotations

import time
from typing import Protocol


class Clock(Protocol):
    virtual: bool  # True: time moves only when told to (simulation, single step, tests)

    def now_ns(self) -> int: ...

    def wall_ns(self) -> int:
        """Calendar time (Unix ns): for DATE_AND_TIME and event time stamps."""
        ...

    def sleep_until(self, deadline_ns: int) -> None: ...


class RealClock:
    """Monotonic time; immune to changes of the wall clock."""

    virtual = False
    # the C functions themselves: read twice per CPU cycle, without a Python frame
    now_ns = staticmethod(time.monotonic_ns)
    wall_ns = staticmethod(time.time_ns)

    def sleep_until(self, deadline_ns: int) -> None:
        remaining = deadline_ns - time.monotonic_ns()
        if remaining > 0:
            time.sleep(remaining / 1e9)


class VirtualClock:
    """Time that moves only when told to: exactly one cycle interval per cycle."""

    virtual = True

    def __init__(self, start_ns: int = 0, epoch_ns: int = 0) -> None:
        self._now = start_ns
        self._epoch = epoch_ns  # calendar time at virtual time 0

    def now_ns(self) -> int:
        return self._now

    def wall_ns(self) -> int:
        return self._epoch + self._now

    def sleep_until(self, deadline_ns: int) -> None:
        self._now = max(self._now, deadline_ns)

    def advance(self, delta_ns: int) -> None:
        self._now += delta_ns

    def rewind(self) -> None:
        """Back to virtual time 0 (`padt test`: every test starts there, so that its result
        does not depend on the tests before it)."""
        self._now = 0
