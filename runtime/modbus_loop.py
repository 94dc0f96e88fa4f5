"""The Modbus thread of a resource: one asyncio event loop that runs the served image's
server and the polling of every remote device, never the cycle thread."""

from __future__ import annotations

import asyncio
import concurrent.futures
import logging
import threading
from collections.abc import Coroutine
from typing import Any, TypeVar

T = TypeVar("T")


class ModbusLoop:
    def __init__(self) -> None:
        # a lost device would log a failed connection every period: what goes wrong on the
        # bus is reported as events and in the status instead
        logging.getLogger("pymodbus").setLevel(logging.CRITICAL)
        self.loop = asyncio.new_event_loop()
        self._thread = threading.Thread(target=self._run, name="padt-modbus", daemon=True)
        self._thread.start()

    def _run(self) -> None:
        asyncio.set_event_loop(self.loop)
        self.loop.run_forever()

    def submit(self, work: Coroutine[Any, Any, T]) -> concurrent.futures.Future[T]:
        return asyncio.run_coroutine_threadsafe(work, self.loop)

    def run(self, work: Coroutine[Any, Any, T], timeout_s: float = 5.0) -> T:
        """Run `work` on the loop and wait for it (never from the cycle thread)."""
        return self.submit(work).result(timeout_s)

    def close(self) -> None:
        self.loop.call_soon_threadsafe(self.loop.stop)
        self._thread.join(timeout=5)
