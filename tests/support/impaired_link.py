"""A TCP link with a network's latency and losses, between two Zenoh routers on one host,
for the benches of the exchange between resources (tests/bench/bench_exchange.py).

The kernels we run on have no `sch_netem` (`tc qdisc add ... netem` answers "Specified
qdisc kind is unknown"), so the link is a proxy in user space on its own thread:

- **Delay**: every chunk read on one side is written to the other `delay_ms` later, in
  order (one way; a round trip costs twice that).
- **Loss**, as TCP makes it look to Zenoh: a segment lost on the wire is sent again by the
  sender's TCP after its retransmission timeout (Linux: at least 200 ms) and everything
  behind it waits (head-of-line blocking). So a chunk is "lost" with probability `loss`,
  and it and every chunk after it on that side are held `RETRANSMIT_MS` longer. This is a
  model of TCP's recovery for sparse traffic, not of the wire; a real link recovers
  faster with fast retransmit when many segments are in flight.
- **Down**: `down()` closes every connection and refuses new ones until `up()`, as a cable
  pulled and plugged in again.
"""

from __future__ import annotations

import asyncio
import contextlib
import random
import threading
import time
from collections.abc import Iterator

RETRANSMIT_MS = 200.0


class ImpairedLink:
    def __init__(
        self, listen_port: int, target_port: int, delay_ms: float = 0.0, loss: float = 0.0
    ) -> None:
        self.listen_port, self.target_port = listen_port, target_port
        self.delay_ms, self.loss = delay_ms, loss
        self._random = random.Random(20261203)  # the same losses in every run
        self._loop = asyncio.new_event_loop()
        self._server: asyncio.Server | None = None
        self._writers: set[asyncio.StreamWriter] = set()
        self._ready = threading.Event()
        self._thread = threading.Thread(target=self._run, name="impaired-link", daemon=True)
        self._thread.start()
        self._ready.wait(10)

    def _run(self) -> None:
        asyncio.set_event_loop(self._loop)
        self._loop.run_until_complete(self._listen())
        self._ready.set()
        self._loop.run_forever()

    async def _listen(self) -> None:
        self._server = await asyncio.start_server(self._accept, "127.0.0.1", self.listen_port)

    async def _accept(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        try:
            target_reader, target_writer = await asyncio.open_connection(
                "127.0.0.1", self.target_port
            )
        except OSError:
            writer.close()
            return
        self._writers.update((writer, target_writer))
        await asyncio.gather(
            self._carry(reader, target_writer), self._carry(target_reader, writer),
            return_exceptions=True,
        )  # fmt: skip
        for side in (writer, target_writer):
            self._writers.discard(side)
            side.close()

    async def _carry(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        """One direction: each chunk written when its time comes, in order."""
        queue: asyncio.Queue[tuple[float, bytes]] = asyncio.Queue()
        sender = asyncio.create_task(self._send(queue, writer))
        held_until = 0.0  # a lost chunk holds back everything behind it
        try:
            while chunk := await reader.read(65536):
                due = time.monotonic() + self.delay_ms / 1000
                if self.loss and self._random.random() < self.loss:
                    due += RETRANSMIT_MS / 1000
                held_until = max(held_until, due)
                await queue.put((held_until, chunk))
        finally:
            await queue.put((0.0, b""))
            await sender
            writer.close()

    async def _send(
        self, queue: asyncio.Queue[tuple[float, bytes]], writer: asyncio.StreamWriter
    ) -> None:
        while True:
            due, chunk = await queue.get()
            if not chunk:
                return
            wait = due - time.monotonic()
            if wait > 0:
                await asyncio.sleep(wait)
            writer.write(chunk)
            with contextlib.suppress(ConnectionError):
                await writer.drain()

    def down(self) -> None:
        """Every connection closed, new ones refused."""
        asyncio.run_coroutine_threadsafe(self._down(), self._loop).result(10)

    async def _down(self) -> None:
        if self._server is not None:
            self._server.close()
            await self._server.wait_closed()
            self._server = None
        for writer in list(self._writers):
            writer.transport.abort()
        self._writers.clear()

    def up(self) -> None:
        asyncio.run_coroutine_threadsafe(self._listen(), self._loop).result(10)

    def close(self) -> None:
        self.down()
        self._loop.call_soon_threadsafe(self._loop.stop)
        self._thread.join(10)


@contextlib.contextmanager
def impaired_link(
    listen_port: int, target_port: int, delay_ms: float = 0.0, loss: float = 0.0
) -> Iterator[ImpairedLink]:
    link = ImpairedLink(listen_port, target_port, delay_ms, loss)
    try:
        yield link
    finally:
        link.close()
