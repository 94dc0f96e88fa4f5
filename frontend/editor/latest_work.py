"""Work done off viser's event thread, one job at a time, where only the newest job of a
kind matters: diagnostics of the text as it is now, the answer to the newest completion.
A job handed in while an older one of its kind waits replaces it (the older is never run),
so typing faster than the services answer costs no queue."""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable

log = logging.getLogger("padt.ui")


class LatestWork:
    def __init__(self, name: str) -> None:
        self._name = name
        self._waiting: dict[str, Callable[[], None]] = {}  # kind -> newest job, in order
        self._wake = threading.Condition()
        self._stopped = False
        self._thread: threading.Thread | None = None

    def submit(self, kind: str, job: Callable[[], None]) -> None:
        with self._wake:
            if self._stopped:
                return
            self._waiting.pop(kind, None)  # to the end: handed in now
            self._waiting[kind] = job
            if self._thread is None:
                self._thread = threading.Thread(target=self._run, name=self._name, daemon=True)
                self._thread.start()
            self._wake.notify()

    def stop(self) -> None:
        with self._wake:
            self._stopped = True
            self._waiting.clear()
            self._wake.notify()

    def _run(self) -> None:
        while True:
            with self._wake:
                while not self._waiting and not self._stopped:
                    self._wake.wait()
                if self._stopped:
                    return
                kind = next(iter(self._waiting))
                job = self._waiting.pop(kind)
            try:
                job()
            except Exception:  # a job's failure must not end the editor's services
                log.exception("editor job %s failed", kind)
