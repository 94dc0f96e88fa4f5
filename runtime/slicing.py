"""Time slices: a user program with a Max. Duration for Each Cycle that has used its time in
this CPU cycle is suspended and resumes where it stopped in the next CPU cycle.

Generated code calls `_tick()` at the start of every loop pass (straight-line code between
two passes is bounded by the size of the program) when it is not None: it reads `_tick`
once before the loop. While a sliced program runs, `_tick` is a `SliceMeter`'s tick: when
the slice is used up it switches from the program's greenlet back to the CPU cycle, which
resumes the greenlet in a later CPU cycle. A greenlet keeps
the whole Python stack of the program (FB calls, loops, temporaries), so the program goes
on exactly where it stopped, in the same thread as the cycle (the watchdog's asynchronous
exception still reaches it).

On a real clock a slice is measured in monotonic time. On a virtual clock (simulation,
tests) every loop pass counts as `VIRTUAL_PASS_NS`, so where a program is suspended is the
same in every run.
"""

from __future__ import annotations

import time
from collections.abc import Callable

import greenlet

VIRTUAL_PASS_NS = 1_000  # what one loop pass costs on a virtual clock


class SliceMeter:
    """Measures the slice of the program that runs now."""

    def __init__(self, virtual: bool) -> None:
        self.virtual = virtual
        self._budget_ns: int | None = None
        self._start_ns = 0
        self._passes = 0

    def begin(self, budget_ns: int | None) -> None:
        """Start metering a slice; None: no limit (the program runs to its end)."""
        self._budget_ns = budget_ns
        self._passes = 0
        self._start_ns = time.perf_counter_ns()

    def used_ns(self) -> int:
        if self.virtual:
            return self._passes * VIRTUAL_PASS_NS
        return time.perf_counter_ns() - self._start_ns

    def tick(self) -> None:
        """A loop pass begins: suspend the program first if the pass does not fit into
        what is left of the slice (after resuming, it counts in the new slice)."""
        if self._budget_ns is not None:
            if self.virtual:
                over = (self._passes + 1) * VIRTUAL_PASS_NS > self._budget_ns
            else:
                over = time.perf_counter_ns() - self._start_ns >= self._budget_ns
            if over:
                current = greenlet.getcurrent()
                if current.parent is not None:  # inside a ProgramRun: suspend it
                    current.parent.switch(_SUSPENDED)
        self._passes += 1


_SUSPENDED = object()
_FINISHED = object()


class ProgramRun:
    """One program cycle that may span several CPU cycles."""

    def __init__(self, body: Callable[[], object]) -> None:
        def whole_cycle() -> object:
            body()
            return _FINISHED

        self._greenlet = greenlet.greenlet(whole_cycle)

    def resume(self) -> bool:
        """Run until the program cycle ends (True) or its slice is used up (False).
        Whatever the program raises comes out of here."""
        return self._greenlet.switch() is _FINISHED

    def abandon(self) -> None:
        """Drop a suspended program cycle (program stopped or in ERROR): unwind it now, in
        this thread, rather than whenever the garbage collector finds it."""
        if self._greenlet and not self._greenlet.dead:
            self._greenlet.throw(greenlet.GreenletExit)
