"""Writes contexts to disk on its own thread: the cycle thread only takes the snapshot
(consistent, between two cycles); encoding, writing and fsync happen here. Only the
newest context waiting is written: an older one is worth nothing once a newer exists."""

from __future__ import annotations

import logging
import threading
from pathlib import Path

from runtime.context import Context, save_context

log = logging.getLogger(__name__)


class ContextSaver:
    def __init__(self, path: Path) -> None:
        self.path = path
        path.parent.mkdir(parents=True, exist_ok=True)
        self._lock = threading.Condition()
        self._waiting: Context | None = None
        self._busy = False
        self._closed = False
        self.saved = 0
        self._thread = threading.Thread(target=self._run, name="padt-context", daemon=True)
        self._thread.start()

    def submit(self, context: Context) -> None:
        with self._lock:
            self._waiting = context
            self._lock.notify_all()

    def flush(self) -> None:
        """Wait until everything submitted is on disk."""
        with self._lock:
            while self._waiting is not None or self._busy:
                self._lock.wait()

    def close(self) -> None:
        self.flush()
        with self._lock:
            self._closed = True
            self._lock.notify_all()
        self._thread.join()

    def _run(self) -> None:
        while True:
            with self._lock:
                while self._waiting is None and not self._closed:
                    self._lock.wait()
                if self._waiting is None:
                    return
                context, self._waiting, self._busy = self._waiting, None, True
            try:
                save_context(self.path, context)
                self.saved += 1
            except OSError as exc:  # a full disk must not stop the controller
                log.error("context not saved: %s", exc)
            with self._lock:
                self._busy = False
                self._lock.notify_all()
