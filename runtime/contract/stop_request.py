"""How a long-running `padt` command learns that it should end: SIGINT or SIGTERM."""

from __future__ import annotations

import signal
import threading
import time
from collections.abc import Callable


class StopRequest:
    """Set by SIGINT or SIGTERM. Made first thing in a command, so that a signal that comes
    during start-up ends the command in order instead of raising KeyboardInterrupt at a
    random line and leaving threads and child processes behind."""

    def __init__(self) -> None:
        self.event = threading.Event()
        for sig in (signal.SIGINT, signal.SIGTERM):
            signal.signal(sig, lambda *_: self.event.set())

    def sleep_until_requested(self, keep_going: Callable[[], bool] = lambda: True) -> None:
        # sleep, not Event.wait(): the handler runs in this thread, and Event.set() would
        # wait for the lock that a wait() interrupted by the signal holds (a deadlock)
        while not self.event.is_set() and keep_going():
            time.sleep(0.2)
