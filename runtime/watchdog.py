"""The resource watchdog: a CPU cycle that runs longer than the watchdog time ends in
ERROR STOP, even when a program never returns (`WHILE TRUE DO END_WHILE;`).

One watchdog thread per process polls the armed deadlines every millisecond on the real
monotonic clock (also in simulation: an endless loop must end there too). When a deadline
passes, it raises `WatchdogExpired` in the thread that armed it; CPython delivers such an
asynchronous exception at the next bytecode boundary, and generated code is plain Python
bytecode. Arming and disarming are a few assignments under a lock, with no system call per
cycle; after a second with nothing armed the thread sleeps until the next arming.
"""

from __future__ import annotations

import ctypes
import threading
import time
from types import TracebackType

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
        self._lock = threading.Condition()
        self._deadlines: dict[int, int] = {}  # thread id -> monotonic ns
        self._fired: set[int] = set()
        self._last_armed_ns = 0
        self._idle = True
        self._thread = threading.Thread(target=self._watch, name="padt-watchdog", daemon=True)
        self._thread.start()

    def guard(self, budget_ns: int) -> _Guard:
        """`with watchdog.guard(ns):` the block must end within `ns`, or WatchdogExpired."""
        return _Guard(self, budget_ns)

    def _arm(self, budget_ns: int) -> None:
        with self._lock:
            now = time.monotonic_ns()
            self._deadlines[threading.get_ident()] = now + budget_ns
            self._fired.discard(threading.get_ident())
            self._last_armed_ns = now
            if self._idle:
                self._lock.notify()

    def _disarm(self) -> bool:
        """True when the watchdog fired; a still pending exception is taken back."""
        thread_id = threading.get_ident()
        with self._lock:
            self._deadlines.pop(thread_id, None)
            fired = thread_id in self._fired
            if fired:
                self._fired.discard(thread_id)
                _raise_in(thread_id, None)
            return fired

    def _watch(self) -> None:
        with self._lock:
            while True:
                recently = time.monotonic_ns() - self._last_armed_ns < IDLE_AFTER_NS
                self._idle = not self._deadlines and not recently
                self._lock.wait(None if self._idle else POLL_S)
                now = time.monotonic_ns()
                for thread_id, deadline in list(self._deadlines.items()):
                    if now > deadline:
                        del self._deadlines[thread_id]
                        self._fired.add(thread_id)
                        _raise_in(thread_id, WatchdogExpired)


class _Guard:
    def __init__(self, watchdog: Watchdog, budget_ns: int) -> None:
        self._watchdog = watchdog
        self._budget_ns = budget_ns

    def __enter__(self) -> None:
        self._watchdog._arm(self._budget_ns)

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        fired = self._watchdog._disarm()
        if fired and exc_type is None:
            # it fired just as the block ended: the cycle was too long all the same
            raise WatchdogExpired()


_shared: Watchdog | None = None
_shared_lock = threading.Lock()


def process_watchdog() -> Watchdog:
    """The one watchdog of this process (started on first use)."""
    global _shared
    with _shared_lock:
        if _shared is None:
            _shared = Watchdog()
        return _shared
