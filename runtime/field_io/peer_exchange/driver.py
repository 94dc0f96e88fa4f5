"""The exchange between resources as a field I/O driver: its publications and its
subscriptions of one `[exchange]` configuration, between the cycle and the I/O thread.

Before a cycle the values of fresh publications of other resources go into the process
image (safe values, marked bad, for those gone stale), and a subscription that went stale
or came back becomes an event; after it each publication whose period came takes the
values of its variables.
"""

from __future__ import annotations

import asyncio
from typing import Any

import zenoh

from runtime.contract.exchange import ExchangeConfig, Subscription
from runtime.contract.keyspace import exchange_key
from runtime.contract.protocol import IoPoint, IoStatus, ServerStatus
from runtime.contract.signatures import Freshness
from runtime.field_io.driver import DriverContext
from runtime.field_io.peer_exchange.peer_keys import PeerKeys
from runtime.field_io.peer_exchange.publication import PublicationSender
from runtime.field_io.peer_exchange.subscription import PeerSubscription
from runtime.field_io.remote_devices import RemoteDevices
from runtime.identity import Identity

PROTOCOL = "zenoh"


class PeerExchangeDriver:
    def __init__(
        self,
        config: ExchangeConfig,
        context: DriverContext,
        session: zenoh.Session,
        identity: Identity,
        keys: PeerKeys,
        freshness: Freshness,
    ) -> None:
        self._context = context
        self.publications = [
            PublicationSender(p, context.resource, session, identity) for p in config.publications
        ]
        self.subscriptions = [
            PeerSubscription(s, session, keys, freshness) for s in config.subscriptions
        ]
        self._devices = RemoteDevices(
            self.subscriptions, context, PROTOCOL, "Exchange", _subscription_address,
            only_changes=True,
        )  # fmt: skip
        self._tasks: list[asyncio.Task[None]] = []

    @property
    def bad(self) -> frozenset[str]:
        return self._devices.bad

    # ---- the I/O thread
    async def start(self) -> None:
        self._devices.start()
        self._tasks = [asyncio.create_task(p.run()) for p in self.publications]

    async def stop(self) -> None:
        for task in self._tasks:
            task.cancel()
        await asyncio.gather(*self._tasks, return_exceptions=True)
        await self._devices.stop()

    # ---- the cycle thread
    def rebind(self) -> None:
        variables = self._context.variables
        for sender in self.publications:
            found = (variables.find(v.variable) for v in sender.publication.variables)
            sender.bound = [bound for bound in found if bound is not None]
        self._devices.rebind()

    def before_cycle(self) -> None:
        self._devices.before_cycle()

    def after_cycle(self) -> None:
        read = self._context.variables.read
        running = None
        for sender in self.publications:
            if not sender.wanted:
                continue
            sender.wanted = False
            if running is None:
                running = self._context.running()
            values = [(b.path.path, b.path.type, read(b)) for b in sender.bound]
            sender.hand_over(values, running)

    # ---- what the status and the `io` command show (cycle thread)
    def status(self) -> IoStatus:
        servers = [
            ServerStatus(
                exchange_key(self._context.resource, sender.publication.name),
                0,
                listening=sender.error is None,
                error=sender.error,
                requests=sender.sent,
                exceptions=0,
                writes=0,
                protocol=PROTOCOL,
            )
            for sender in self.publications
        ]
        return IoStatus(None, self._devices.statuses(), servers)

    def points(self) -> list[IoPoint]:
        points = [
            _point(name, point.variable, point.type, value, quality, f"{name}.{point.source}")
            for name, point, value, quality in self._devices.point_values()
        ]
        for sender in self.publications:
            name, last = sender.publication.name, sender.last
            for published in sender.publication.variables:
                value = last.get(published.variable)
                quality = "good" if published.variable in last else "waiting"
                points.append(
                    _point(name, published.variable, published.type, value, quality, name)
                )
        return points


def _point(source: str, variable: str, kind: str, value: Any, quality: str, place: str) -> IoPoint:
    return IoPoint(
        source, variable, "", kind, area="", address=0, writable=False, value=value,
        quality=quality, protocol=PROTOCOL, place=place,
    )  # fmt: skip


def _subscription_address(subscription: Subscription) -> tuple[str, int, int]:
    return exchange_key(subscription.resource, subscription.publication), 0, 0
