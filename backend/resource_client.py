"""The engineering side's handle on a running resource over Zenoh: commands with replies,
and subscriptions to its status and live values."""

from __future__ import annotations

import json
from collections.abc import Callable
from typing import Any

import zenoh

from runtime.keyspace import command_key, status_key, values_key

COMMAND_TIMEOUT_S = 5.0


class ResourceUnreachable(Exception):
    """No runtime answered the command."""


class ResourceClient:
    def __init__(self, session: zenoh.Session, resource: str) -> None:
        self.session = session
        self.resource = resource
        self._subscribers: list[zenoh.Subscriber[None]] = []

    def command(
        self, cmd: str, /, timeout_s: float = COMMAND_TIMEOUT_S, **args: Any
    ) -> dict[str, Any]:
        payload = json.dumps({"cmd": cmd, **args})
        replies = self.session.get(command_key(self.resource), payload=payload, timeout=timeout_s)
        for reply in replies:
            if reply.ok is not None:
                result: dict[str, Any] = json.loads(reply.ok.payload.to_bytes())
                return result
        raise ResourceUnreachable(f"resource '{self.resource}' did not answer '{cmd}'")

    def on_status(self, callback: Callable[[dict[str, Any]], None]) -> None:
        self._subscribe(status_key(self.resource), callback)

    def on_values(self, callback: Callable[[dict[str, Any]], None]) -> None:
        self._subscribe(values_key(self.resource), callback)

    def _subscribe(self, key_expr: str, callback: Callable[[dict[str, Any]], None]) -> None:
        def handler(sample: zenoh.Sample) -> None:
            callback(json.loads(sample.payload.to_bytes()))

        self._subscribers.append(self.session.declare_subscriber(key_expr, handler))

    def close(self) -> None:
        for subscriber in self._subscribers:
            subscriber.undeclare()
        self._subscribers.clear()
