"""One subscription of the exchange: another resource's publication taken into globals of
this resource, as a remote device of the driver (`RemoteDevices`).

Zenoh calls `_take` on its own threads with each message: it is checked whole (size,
signature, stamp newer than the last taken, the publisher's pinned key, every value of the
type its variable has) and becomes one immutable `Delivery` of all the subscription's
variables, handed over with one reference assignment. `run`, on the I/O thread, wakes
when the last message taken goes stale: no message taken for `timeout_ms` puts the safe
values in place then. A message of a publisher that does not run (STOP, ERROR STOP) is
taken as stale at once. The cycle never waits for either.
"""

from __future__ import annotations

import asyncio
import threading
import time
from typing import Any

import zenoh

from runtime.contract.exchange import MAX_MESSAGE_BYTES, Subscription
from runtime.contract.keyspace import exchange_key
from runtime.contract.signatures import Freshness, verified_stamp
from runtime.field_io.delivery import Delivery
from runtime.field_io.peer_exchange.message import MessageRefused, decode, point_value
from runtime.field_io.peer_exchange.peer_keys import PeerKeys

NS_PER_MS = 1_000_000


class PeerSubscription:
    """`state` connecting | connected | lost, `delivery`, `last_error`, `requests`
    (messages taken), `failures` (messages refused and times it went stale),
    `round_trip_ms` (the time between the last two messages taken), as `RemoteDevices`
    reads a device; `sent` stays empty (a subscription sends nothing)."""

    def __init__(
        self,
        subscription: Subscription,
        session: zenoh.Session,
        keys: PeerKeys,
        freshness: Freshness,
    ) -> None:
        """`keys` and `freshness` outlive the driver: a reload that makes a new one takes
        no message older than one taken before, and no other key."""
        self.device = subscription
        self._session, self._keys, self._freshness = session, keys, freshness
        self._key = exchange_key(subscription.resource, subscription.publication)
        self._safe = {p.variable: p.input_safe_value for p in subscription.points}
        self._lock = threading.Lock()  # Zenoh's threads and the I/O thread; never the cycle
        self._seq = 1
        self._taken_ns = 0  # when the last message was taken (0: none yet)
        self._refused: str | None = None  # why the last message was refused, since one taken
        self.delivery = Delivery(self._seq, dict(self._safe), False)  # safe until a message
        self.state = "connecting"
        self.sent: dict[str, Any] = {}
        self.last_error: str | None = None
        self.requests = 0
        self.failures = 0
        self.round_trip_ms = 0.0

    async def run(self) -> None:
        subscriber = self._session.declare_subscriber(self._key, self._take)
        timeout_ns = self.device.timeout_ms * NS_PER_MS
        started = time.monotonic_ns()
        try:
            while True:
                with self._lock:
                    since, now = self._taken_ns or started, time.monotonic_ns()
                    stale = now - since >= timeout_ns
                    if stale and self.state != "lost":
                        why = f"no message for {self.device.timeout_ms} ms"
                        if self._refused is not None:
                            why = f"{why}; the last one was refused: {self._refused}"
                        self.failures += 1
                        self._lose(why)
                # wake when the last message taken goes stale, so that the safe values are
                # in place by then (lost: a timeout later, never past a new message's end)
                await asyncio.sleep((timeout_ns if stale else since + timeout_ns - now) / 1e9)
        finally:
            subscriber.undeclare()

    def _take(self, sample: zenoh.Sample) -> None:
        payload = sample.payload.to_bytes()
        attachment = sample.attachment.to_bytes() if sample.attachment is not None else None
        with self._lock:
            try:
                values, running = self._checked(payload, attachment)
            except MessageRefused as exc:
                self.failures += 1
                self._refused = str(exc)
                self.last_error = self._refused
                return
            now = time.monotonic_ns()
            if self._taken_ns:
                self.round_trip_ms = (now - self._taken_ns) / NS_PER_MS
            self._taken_ns, self._refused = now, None
            self.requests += 1
            if not running:
                if self.state != "lost":
                    self._lose(f"{self.device.resource} does not run")
                return
            self._seq += 1
            self.delivery = Delivery(self._seq, values, True)  # the delivery before the state
            self.state, self.last_error = "connected", None

    def _checked(self, payload: bytes, attachment: bytes | None) -> tuple[dict[str, Any], bool]:
        if len(payload) > MAX_MESSAGE_BYTES:
            raise MessageRefused(f"the message is larger than {MAX_MESSAGE_BYTES:,} bytes")
        message = decode(payload)
        if message.resource != self.device.resource or message.publication != (
            self.device.publication
        ):
            raise MessageRefused("the message names another resource or publication")
        stamp = verified_stamp(message.key, payload, attachment)
        if stamp is None:
            raise MessageRefused("the message's signature does not verify")
        problem = self._keys.problem(message.resource, message.key)
        if problem is not None:
            raise MessageRefused(problem)
        if not self._freshness.newer(self._key, stamp):
            raise MessageRefused("the message is older than one taken (a replay)")
        values = {p.variable: point_value(message, p) for p in self.device.points}
        return values, message.running

    def _lose(self, why: str) -> None:
        """Safe values in place (under the lock): the delivery before the state."""
        self._seq += 1
        self.delivery = Delivery(self._seq, dict(self._safe), False)
        self.state, self.last_error = "lost", why
