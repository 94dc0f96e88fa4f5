"""A mend of viser 1.1's message buffer for GUIs written from other threads, as ours are
(the refresher, Zenoh's callbacks). Each queued message sets the buffer's asyncio.Event
directly as well as through `call_soon_threadsafe`. From a foreign thread, the direct set
walks the event's waiters while the event loop adds and removes them: under load viser
then fails with "deque mutated during iteration" and a browser's workspace is left half
built. An asyncio.Event belongs to its loop; off that loop the direct set is skipped here,
and the thread-safe call that viser makes right after it wakes the loop all the same."""

from __future__ import annotations

import asyncio
from typing import Any

from viser.infra._async_message_buffer import AsyncMessageBuffer


class LoopEvent(asyncio.Event):
    """An asyncio.Event whose `set()` from outside its own loop does nothing; the owner
    also sets it through `loop.call_soon_threadsafe`."""

    def set(self) -> None:
        loop = getattr(self, "_loop", None)  # bound when a task first waits on it
        if loop is not None:
            try:
                running = asyncio.get_running_loop()
            except RuntimeError:
                running = None
            if running is not loop:
                return
        super().set()


_ORIGINAL_INIT = AsyncMessageBuffer.__init__


def _init(self: AsyncMessageBuffer, *args: Any, **kwargs: Any) -> None:
    _ORIGINAL_INIT(self, *args, **kwargs)
    self.message_event = LoopEvent()


def install() -> None:
    """For every message buffer made from now on (idempotent)."""
    AsyncMessageBuffer.__init__ = _init  # type: ignore[method-assign]
