"""The engineering side's handle on a running resource over Zenoh: commands with replies,
and subscriptions to its status and live values."""

from __future__ import annotations

import json
import secrets
import time
from collections.abc import Callable
from typing import Any

import zenoh

from runtime.contract.keyspace import (
    alive_key,
    command_key,
    events_key,
    status_key,
    watch_key,
    watcher_key,
)

COMMAND_TIMEOUT_S = 5.0
WATCH_BATCH = 1000  # variable names per watch request (paths are short; 64 KiB is the limit)


class ResourceUnreachable(Exception):
    """No runtime answered the command."""


class WatchRefused(Exception):
    """The runtime did not take a watch set (unknown variable, bad period, ...)."""


class Watch:
    """A registered watch set: its values arrive until `close`."""

    def __init__(
        self, watch_id: str, token: zenoh.LivelinessToken, subscriber: zenoh.Subscriber[None]
    ) -> None:
        self.watch_id = watch_id
        self.variables: list[str] = []  # canonical paths, as the runtime names them
        self._token = token
        self._subscriber = subscriber

    def close(self) -> None:
        """Withdraw the token: the runtime drops the set."""
        self._token.undeclare()
        self._subscriber.undeclare()


class ResourceClient:
    def __init__(self, session: zenoh.Session, resource: str) -> None:
        self.session = session
        self.resource = resource
        self._subscribers: list[zenoh.Subscriber[None]] = []
        self.token: str | None = None  # the session token after `login`, sent with every command
        self._credentials: tuple[str, str] | None = None

    def command(
        self, cmd: str, /, timeout_s: float = COMMAND_TIMEOUT_S, **args: Any
    ) -> dict[str, Any]:
        reply = self._send(cmd, timeout_s, args)
        refused = reply.get("error", {}).get("code") == "unauthenticated"
        # a session ends with its expiry or a restart of the runtime: log in again
        again = refused and self._credentials is not None and cmd != "login"
        if again and self._credentials and self.login(*self._credentials).get("ok"):
            reply = self._send(cmd, timeout_s, args)
        return reply

    def wait_until_answering(self, timeout_s: float = 30) -> None:
        """Wait for the resource to answer (a runtime that is still starting)."""
        deadline = time.monotonic() + timeout_s
        while True:
            try:
                self.command("status")
                return
            except ResourceUnreachable:
                if time.monotonic() > deadline:
                    raise
                time.sleep(0.1)

    def use_credentials(self, user: str, password: str) -> None:
        """Log in whenever the resource asks for it (at the first command, after a runtime
        restart or an expired session)."""
        self._credentials = (user, password)

    def _send(self, cmd: str, timeout_s: float, args: dict[str, Any]) -> dict[str, Any]:
        token = {"token": self.token} if self.token is not None else {}
        payload = json.dumps({"cmd": cmd, **token, **args})
        replies = self.session.get(command_key(self.resource), payload=payload, timeout=timeout_s)
        for reply in replies:
            if reply.ok is not None:
                result: dict[str, Any] = json.loads(reply.ok.payload.to_bytes())
                return result
        raise ResourceUnreachable(f"resource '{self.resource}' did not answer '{cmd}'")

    def login(self, user: str, password: str) -> dict[str, Any]:
        """Log in; the token goes with every later command. The reply says the level."""
        reply = self._send("login", COMMAND_TIMEOUT_S, {"user": user, "password": password})
        if reply.get("ok"):
            self.token = str(reply["token"])
        return reply

    def on_status(self, callback: Callable[[dict[str, Any]], None]) -> None:
        self._subscribe(status_key(self.resource), callback)

    def on_alive(self, callback: Callable[[bool], None]) -> None:
        """Told True when the runtime process is (or comes back) there, False when it goes;
        at once for a runtime already running."""

        def handler(sample: zenoh.Sample) -> None:
            callback(sample.kind == zenoh.SampleKind.PUT)

        self._subscribers.append(
            self.session.liveliness().declare_subscriber(
                alive_key(self.resource), handler, history=True
            )
        )

    def on_events(self, callback: Callable[[dict[str, Any]], None]) -> None:
        """Every event of the resource's log from now on, in order."""
        self._subscribe(events_key(self.resource), callback)

    def watch(
        self,
        variables: list[str],
        callback: Callable[[dict[str, Any]], None],
        period_ms: int = 100,
    ) -> Watch:
        """Receive the values of `variables` (with their quality) once per period. The set
        lives as long as this session holds its liveliness token (until `Watch.close`)."""
        watch_id = secrets.token_hex(8)
        token = self.session.liveliness().declare_token(watcher_key(self.resource, watch_id))
        subscriber = self._declare(watch_key(self.resource, watch_id), callback)
        handle = Watch(watch_id, token, subscriber)
        # a large set goes in several requests, each well inside the request limit
        batches = [variables[i : i + WATCH_BATCH] for i in range(0, len(variables), WATCH_BATCH)]
        for number, batch in enumerate(batches or [[]]):
            reply = self.command(
                "watch", id=watch_id, variables=batch, period_ms=period_ms, append=number > 0
            )
            if not reply.get("ok"):
                handle.close()
                self.command("unwatch", id=watch_id)
                error = reply.get("error", {})
                raise WatchRefused(f"{error.get('code')}: {error.get('message')}")
        handle.variables = list(reply["variables"])
        return handle

    def _subscribe(self, key_expr: str, callback: Callable[[dict[str, Any]], None]) -> None:
        self._subscribers.append(self._declare(key_expr, callback))

    def _declare(
        self, key_expr: str, callback: Callable[[dict[str, Any]], None]
    ) -> zenoh.Subscriber[None]:
        def handler(sample: zenoh.Sample) -> None:
            callback(json.loads(sample.payload.to_bytes()))

        return self.session.declare_subscriber(key_expr, handler)

    def close(self) -> None:
        for subscriber in self._subscribers:
            subscriber.undeclare()
        self._subscribers.clear()
