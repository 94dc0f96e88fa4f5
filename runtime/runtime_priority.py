"""The runtime before everything else on the machine. A PES that shares its computer with
the PADT, browsers and builds must not see its cycle stretched by them: the runtime asks
the operating system for a higher priority (a lower nice value; it takes CAP_SYS_NICE,
which root and a container granted it have) before it starts any thread, so that every
thread of it has it: a thread of normal priority that holds the GIL and waits for a CPU
would hold up the cycle all the same. Without it the resource runs at normal priority and
says so in its log. The cycle thread asks for more: the real-time class while it waits for
and runs its cycles (`CycleScheduling`)."""

from __future__ import annotations

import os
import threading

DEFAULT_NICE = -10
NICE_RANGE = range(-20, 20)
DEFAULT_CYCLE_PRIORITY = 10  # SCHED_FIFO, 1 (lowest) to 99; 0: the thread keeps its nice
CYCLE_PRIORITY_RANGE = range(0, 100)
_REAL_TIME = os.SCHED_FIFO | os.SCHED_RESET_ON_FORK


def raise_priority(nice: int) -> str:
    """Give the calling thread `nice` (Linux: per thread); what came of it, for the log."""
    if nice == 0:
        return "normal priority (nice 0)"
    try:
        os.setpriority(os.PRIO_PROCESS, threading.get_native_id(), nice)
    except OSError as exc:
        return f"normal priority: nice {nice} was refused ({exc.strerror}; needs CAP_SYS_NICE)"
    return f"nice {nice}"


class CycleScheduling:
    """The cycle thread's scheduling class. Real-time (SCHED_FIFO at `priority`) while it
    waits for its next cycle at a fixed target and runs it: a thread that wakes for its
    cycle then takes a CPU from any other at once, where at a nice value it waited for one
    by more than 1 ms in 1% of the cycles (10,000 watched values, a client decoding them on
    the other CPU). Woken for its cycle it stays real-time into it: a hand-over to the
    ordinary class just then let other busy threads have the CPU first. Cycles run back to
    back have no wait to be late from and stay ordinary: a switch and back costs two system
    calls, 4 us.

    Ordinary (SCHED_OTHER at its nice value) while it answers commands and keeps house:
    Linux gives a new thread or process its creator's class, and a reload's worker, the
    compile worker, a recording's writer or the I/O thread are started then. (One
    started in a real-time stretch anyway starts ordinary: SCHED_RESET_ON_FORK.) A program
    looping endlessly on it still yields the interpreter lock to the watchdog thread, on
    another CPU or in the time Linux keeps for other threads (5% by default)."""

    def __init__(self, priority: int) -> None:
        self.priority = priority  # 0: ordinary throughout
        self._real_time = False

    def begin(self) -> str:
        """Whether the real-time class may be had, tried once on the cycle thread; what
        came of it, for the log. Refused (no CAP_SYS_NICE), the thread stays ordinary."""
        if self.priority == 0:
            return "normal scheduling (real-time priority 0)"
        try:
            os.sched_setscheduler(0, _REAL_TIME, os.sched_param(self.priority))
            os.sched_setscheduler(0, os.SCHED_OTHER, os.sched_param(0))
        except OSError as exc:
            priority, self.priority = self.priority, 0
            return f"normal scheduling: real-time priority {priority} was refused ({exc.strerror})"
        return f"SCHED_FIFO priority {self.priority} for cycles at a fixed target"

    def real_time(self) -> None:
        if self.priority and not self._real_time:
            self._real_time = self._set(_REAL_TIME, self.priority)

    def ordinary(self) -> None:
        if self._real_time:
            self._real_time = not self._set(os.SCHED_OTHER, 0)  # the nice value stays

    def _set(self, policy: int, priority: int) -> bool:
        """Never raises: a class taken away later (a container's real-time budget, say)
        leaves the thread ordinary from then on."""
        try:
            os.sched_setscheduler(0, policy, os.sched_param(priority))
        except OSError:
            self.priority = 0
            return False
        return True
