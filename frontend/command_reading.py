"""A command's reply read again when what it depends on changes (the key: another
resource, configuration, login, ...), on a thread of its own: never on the refresher,
which draws every browser, nor on Zenoh's threads. A screen asks `ensure(key)` at each
refresh and shows `current()`, the last reading, while a new one is under way."""

from __future__ import annotations

import threading
from collections.abc import Callable, Hashable
from typing import Generic, TypeVar

from backend.engineering.resource_client import ResourceClient, ResourceUnreachable
from runtime.contract import protocol as p
from runtime.contract.refusal import Refusal

R = TypeVar("R")


class CommandReading(Generic[R]):
    def __init__(self, command: p.Command[R], what: str) -> None:
        """`what` the reply is, for the user ("its parameters")."""
        self._command, self._what = command, what
        self._lock = threading.Lock()
        self._key: tuple[Hashable, ...] | None = None
        self._busy = False
        self.reply: R | None = None
        self.error = ""
        self.changes = 0  # goes up with every change sent from here: read again

    def ensure(self, key: tuple[Hashable, ...], client_of: Callable[[str], ResourceClient]) -> None:
        """Read again unless `key` (its first item the resource) is what was read."""
        with self._lock:
            if key == self._key or self._busy:
                return
            self._busy = True
        threading.Thread(target=self._read, args=(key, client_of), daemon=True).start()

    def _read(self, key: tuple[Hashable, ...], client_of: Callable[[str], ResourceClient]) -> None:
        reply, error = None, ""
        try:
            reply = client_of(str(key[0])).ask(self._command)
        except Refusal as refused:
            error = (
                f"log in to the resource to see {self._what}"
                if refused.code in ("unauthenticated", "forbidden")
                else f"{refused.code}: {refused.message}"
            )
        except ResourceUnreachable as exc:
            error = str(exc)
        with self._lock:
            self._key, self._busy = key, False
            self.reply, self.error = reply, error

    def current(self, resource: str) -> tuple[R | None, str]:
        """What was read of this resource (the last reading while a new one is under way)."""
        with self._lock:
            if self._key is None or self._key[0] != resource:
                return None, ""
            return self.reply, self.error

    def changed(self) -> None:
        with self._lock:
            self.changes += 1
