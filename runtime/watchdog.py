"""The resource watchdog: a CPU cycle that runs longer than the watchdog time ends in
ERROR STOP, even when a program never returns (`WHILE TRUE DO END_WHILE;`).

One watchdog thread per process polls the armed deadlines every millisecond on the real
monotonic clock (also in simulation: an endless loop must end there too). When a deadline
passes, it raises `WatchdogExpired` in the thread that armed it; CPython delivers such an
asynchronous exception at the next bytecode boundary, and generated code is plain Python
bytecode. Arming and disarming are a few assignments, with no system call and, as long as
the watchdog has not struck, no lock: a deadline is claimed with one atomic `dict.pop`,
by the thread that disarms it in time or by the watchdog that fires it, never by both
(the lock cost a fifth of an empty CPU cycle). After a second with nothing armed the
thread sleeps until the next arming.
"""

from __future__ import annotations

import ctypes
import threading
import time
from threading import get_ident
from time import monotonic_ns

POLL_S = 0.001
IDLE_AFTER_NS = 1_000_000_000


class WatchdogExpired(BaseException):
    """Raised into the cycle thread. A BaseException, so that no `except Exception` around
    a program run can swallow it."""


def _raise_in(thread_id: int, exception: type[BaseException] | None) -> None:
    """Set (or, with None, clear) the asynchronous exception pending in a thread."""
    target = ctypes.py_object(exception) if exception is not None else None
    ctypes.pythonapi.PyThreadState_SetAsyncExc(ctypes.c_ulong(thread_id), target)


class Watchdog:
    def __init__(self) -> None:
        # a plain lock (a C object: `with` costs no Python call) for the armed deadlines,
        # and an event that wakes the thread from its idle sleep
        self._lock = threading.Lock()
        self._wake = threading.Event()
        self._deadlines: dict[int, int] = {}  # thread id -> monotonic ns
        self._fired: set[int] = set()
        self._idle = False  # the thread sleeps until `arm` wakes it
        self._thread = threading.Thread(target=self._watch, name="padt-watchdog", daemon=True)
        self._thread.start()

    def arm(self, budget_ns: int) -> None:
        """The calling thread must disarm within `budget_ns`, or WatchdogExpired."""
        # no lock: one dict store is atomic, and `_fired` never holds this thread here
        # (`disarm` took it out), so the watching thread sees the old deadline or the new
        self._deadlines[get_ident()] = monotonic_ns() + budget_ns
        if self._idle:
            self._wake.set()

    def disarm(self) -> bool:
        """True when the watchdog fired; a still pending exception is taken back."""
        thread_id = get_ident()
        if self._deadlines.pop(thread_id, None) is not None:
            return False  # claimed in time: the watchdog can no longer fire it
        with self._lock:  # the watchdog claimed it: wait until it fired, or put it back
            self._deadlines.pop(thread_id, None)
            if thread_id not in self._fired:
                return False
            self._fired.discard(thread_id)
            _raise_in(thread_id, None)
            return True

    def _watch(self) -> None:
        last_armed_ns = monotonic_ns()
        while True:
            if self._deadlines:
                last_armed_ns = monotonic_ns()
            elif monotonic_ns() - last_armed_ns >= IDLE_AFTER_NS:
                # idle: `arm` stores its deadline before it reads `_idle`, and this thread
                # sets `_idle` before it looks at the deadlines again, so one of the two
                # sees the other and no arming is missed
                self._wake.clear()
                self._idle = True
                if not self._deadlines:
                    self._wake.wait()
                self._idle = False
                last_armed_ns = monotonic_ns()
                continue
            time.sleep(POLL_S)
            with self._lock:
                self._fire_expired()

    def _fire_expired(self) -> None:
        now = monotonic_ns()
        for thread_id, deadline in list(self._deadlines.items()):
            if now <= deadline:
                continue
            claimed = self._deadlines.pop(thread_id, None)  # atomic, as in `disarm`
            if claimed is None:
                continue  # disarmed in time meanwhile
            if now > claimed:
                self._fired.add(thread_id)
                _raise_in(thread_id, WatchdogExpired)
            else:  # disarmed and armed afresh meanwhile: not due; `disarm` waits for this
                self._deadlines[thread_id] = claimed


_shared: Watchdog | None = None
_shared_lock = threading.Lock()


def process_watchdog() -> Watchdog:
    """The one watchdog of this process (started on first use)."""
    global _shared
    with _shared_lock:
        if _shared is None:
            _shared = Watchdog()
        return _shared
