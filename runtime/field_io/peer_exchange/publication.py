"""One publication of the exchange: chosen globals of this resource, put on the bus every
`period_ms`.

The I/O thread asks for the values once a period (`wanted`); the cycle thread, after the
cycle that follows, reads them (`after_cycle`) and hands them back to the I/O thread, which
encodes, signs and puts them without waiting (congestion drops a message: the next period
brings fresh values). The cycle never waits for the network or for the signature.
"""

from __future__ import annotations

import asyncio
import itertools
from typing import Any

import zenoh

from runtime.code.instances import BoundVariable
from runtime.contract.exchange import Publication
from runtime.contract.keyspace import exchange_key
from runtime.contract.signatures import stamp_bytes, stamped
from runtime.field_io.peer_exchange.message import encode
from runtime.identity import Identity


class PublicationSender:
    def __init__(
        self, publication: Publication, resource: str, session: zenoh.Session, identity: Identity
    ) -> None:
        self.publication = publication
        self._resource, self._session, self._identity = resource, session, identity
        self._key = exchange_key(resource, publication.name)
        self._numbers = itertools.count(1)  # the stamp's number within this boot, per key
        self.bound: list[BoundVariable] = []  # its variables, bound by the driver
        self.wanted = False  # set by the I/O thread, cleared by the cycle thread
        self.last: dict[str, Any] = {}  # what went out last, by variable (the status shows it)
        self.sent = 0  # messages put
        self.error: str | None = None  # why the last put failed
        self._loop: asyncio.AbstractEventLoop | None = None

    async def run(self) -> None:
        self._loop = asyncio.get_running_loop()
        period = self.publication.period_ms / 1000
        while True:
            self.wanted = True
            await asyncio.sleep(period)

    def hand_over(self, values: list[tuple[str, str, Any]], running: bool) -> None:
        """Cycle thread: the values read after a cycle, to be put by the I/O thread."""
        loop = self._loop
        if loop is not None and not loop.is_closed():
            loop.call_soon_threadsafe(self._put, values, running)

    def _put(self, values: list[tuple[str, str, Any]], running: bool) -> None:
        payload = encode(
            self._resource, self.publication.name, running, self._identity.public_key, values
        )
        stamp = stamp_bytes(self._identity.boot, next(self._numbers))
        attachment = stamp + self._identity.sign(stamped(stamp, payload))
        try:
            self._session.put(
                self._key,
                payload,
                attachment=attachment,
                congestion_control=zenoh.CongestionControl.DROP,
            )
        except Exception as exc:  # a closed session while the resource shuts down
            self.error = str(exc)
            return
        self.sent += 1
        self.error = None
        self.last = {name: value for name, _, value in values}
