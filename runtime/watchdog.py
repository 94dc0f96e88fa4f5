"""The resource watchdog: a CPU cycle that runs longer than the watchdog time ends in
ERROR STOP, even when a program never returns (`WHILE TRUE DO END_WHILE;`).

One watchdog thread per process sleeps until the earliest armed deadline, on the real
monotonic clock (also in simulation: an endless loop must end there too). When a deadline
passes, it raises `WatchdogExpired` in the thread that armed it; CPython delivers such an
asynchronous exception at the next bytecode boundary, and generated code is plain Python
bytecode. Arming and disarming are a few assignments, with no system call and, as long as
the watchdog has not struck, no lock: a deadline is claimed with one atomic `dict.pop`,
by the thread that disarms it in time or by the watchdog that fires it, never by both
(the lock cost a fifth of an empty CPU cycle).

While cycles run, the thread wakes about once per watchdog time: at a deadline that has
passed the cycle has long disarmed it and armed a later one. It used to look every
millisecond; each look takes the interpreter lock, and on a machine kept busy by other
programs the operating system now and then took the CPU from the thread while it held
the lock. The real-time cycle thread then waited for the lock: with ten browsers on the
2-core development machine, a cycle started 8 ms late.

A fired exception is never taken back by clearing it (`PyThreadState_SetAsyncExc` with
NULL): CPython 3.11 then keeps the interpreter's "asynchronous exception pending" signal
on, since only delivering an exception turns it off. Every function call and loop pass
then stops to look for one, and under a trace function (a breakpoint's) the interpreter
looks again and again at the start of the first function it enters, never running it:
every later debug run in the process spun there until the watchdog struck again. `disarm`
replaces the exception with one of its own and lets it arrive, which turns the signal off.
"""

from __future__ import annotations

import ctypes
import threading
from threading import get_ident
from time import monotonic_ns

FIRST_BUDGET_NS = 1_000_000_000  # how long the thread sleeps before anything was armed


class WatchdogExpired(BaseException):
    """Raised into the cycle thread. A BaseException, so that no `except Exception` around
    a program run can swallow it."""


class _TakenBack(BaseException):
    """Stands in for a WatchdogExpired taken back; it never leaves `_take_back`."""


def _raise_in(thread_id: int, exception: type[BaseException]) -> bool:
    """Make `exception` the asynchronous exception pending in a thread (replacing one
    pending there); False when no such thread runs Python."""
    found = ctypes.pythonapi.PyThreadState_SetAsyncExc(
        ctypes.c_ulong(thread_id), ctypes.py_object(exception)
    )
    return bool(found)


def _take_back() -> None:
    """Take back the exception the watchdog raised into this thread, delivered already or
    still pending, and leave no pending signal behind (see the module's text)."""
    try:
        if _raise_in(get_ident(), _TakenBack):
            while True:  # delivered at once, at the latest at the loop's jump back
                pass
    except _TakenBack:
        pass


class Watchdog:
    # slots: the CPU cycle in C reads them at their offsets (padt_cycle.c)
    __slots__ = (
        "_budget_ns",
        "_fired",
        "_lock",
        "_next_look_ns",
        "_thread",
        "_wake",
        "deadlines",
    )

    def __init__(self) -> None:
        # a plain lock (a C object: `with` costs no Python call) for the armed deadlines,
        # and an event that wakes the thread for a deadline earlier than it sleeps to
        self._lock = threading.Lock()
        self._wake = threading.Event()
        # thread id -> monotonic ns. The CPU cycle in C (padt_cycle.c) arms and disarms
        # as `arm` and `disarm` do, through it, `_budget_ns`, `_next_look_ns` and `_wake`:
        # a change of either side is a change of both
        self.deadlines: dict[int, int] = {}
        self._fired: set[int] = set()
        self._next_look_ns = 0  # when the thread looks next (0 while it looks)
        # the last budget armed: nothing armed, the thread sleeps that long, since an
        # arming meanwhile has its deadline no earlier than that (with the same budget)
        self._budget_ns = FIRST_BUDGET_NS
        self._thread = threading.Thread(target=self._watch, name="padt-watchdog", daemon=True)
        self._thread.start()

    def arm(self, budget_ns: int) -> None:
        """The calling thread must disarm within `budget_ns`, or WatchdogExpired."""
        # no lock: one dict store is atomic, and `_fired` never holds this thread here
        # (`disarm` took it out), so the watching thread sees the old deadline or the new
        deadline = monotonic_ns() + budget_ns
        self.deadlines[get_ident()] = deadline
        self._budget_ns = budget_ns
        if deadline < self._next_look_ns:  # a shorter budget than the thread sleeps for
            self._wake.set()

    def disarm(self) -> bool:
        """True when the watchdog fired; a still pending exception is taken back."""
        thread_id = get_ident()
        if self.deadlines.pop(thread_id, None) is not None:
            return False  # claimed in time: the watchdog can no longer fire it
        with self._lock:  # the watchdog claimed it: wait until it fired, or put it back
            self.deadlines.pop(thread_id, None)
            if thread_id not in self._fired:
                return False
            self._fired.discard(thread_id)
            _take_back()
            return True

    def _watch(self) -> None:
        while True:
            # `arm` stores its deadline before it reads `_next_look_ns`, and this thread
            # sets `_next_look_ns` before it reads the deadlines again: one of the two
            # sees the other, and no deadline is slept through
            self._next_look_ns = 0
            self._wake.clear()
            with self._lock:
                self._fire_expired()
            now = monotonic_ns()
            next_look = min(self.deadlines.values(), default=now + self._budget_ns)
            self._next_look_ns = next_look
            if min(self.deadlines.values(), default=next_look) < next_look:
                continue
            self._wake.wait(max(0, next_look - now) / 1e9)

    def _fire_expired(self) -> None:
        now = monotonic_ns()
        for thread_id, deadline in list(self.deadlines.items()):
            if now <= deadline:
                continue
            claimed = self.deadlines.pop(thread_id, None)  # atomic, as in `disarm`
            if claimed is None:
                continue  # disarmed in time meanwhile
            if now > claimed:
                self._fired.add(thread_id)
                _raise_in(thread_id, WatchdogExpired)
            else:  # disarmed and armed afresh meanwhile: not due; `disarm` waits for this
                self.deadlines[thread_id] = claimed


_shared: Watchdog | None = None
_shared_lock = threading.Lock()


def process_watchdog() -> Watchdog:
    """The one watchdog of this process (started on first use)."""
    global _shared
    with _shared_lock:
        if _shared is None:
            _shared = Watchdog()
        return _shared
