"""The engineering side's session with a running resource over Zenoh: typed commands with
their checked replies, the login it keeps, and subscriptions to the resource's status,
events, liveliness and watch sets. The CLI, the REST API and the UI reach resources only
through this client."""

from __future__ import annotations

import contextlib
import json
import logging
import secrets
import time
from collections.abc import Callable
from typing import Any, TypeVar

import zenoh

from runtime.contract.keyspace import (
    alive_key,
    command_key,
    events_key,
    status_key,
    watch_key,
    watcher_key,
)
from runtime.contract.protocol import (
    MAX_WATCHED,
    Command,
    Event,
    GetStatus,
    Login,
    LoginReply,
    Status,
    Unwatch,
    Watch,
    WatchValues,
    decode_publication,
    decode_reply,
    encode_request,
)
from runtime.contract.refusal import Refusal

COMMAND_TIMEOUT_S = 5.0
WATCH_BATCH = 1000  # variable names per watch request (paths are short; 64 KiB is the limit)
R = TypeVar("R")
P = TypeVar("P")
log = logging.getLogger("padt.client")


class ResourceUnreachable(Exception):
    """No runtime answered the command."""


class WatchHandle:
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

    def ask(self, command: Command[R], timeout_s: float = COMMAND_TIMEOUT_S) -> R:
        """Send a command; its reply, checked against the protocol. Raises the resource's
        Refusal, or ResourceUnreachable when no runtime answered."""
        reply = self._exchange(
            command.NAME,
            lambda: encode_request(command, self.token),
            timeout_s,
            relogin=not isinstance(command, Login),
        )
        return decode_reply(command, reply)

    def command(
        self, cmd: str, /, timeout_s: float = COMMAND_TIMEOUT_S, **args: Any
    ) -> dict[str, Any]:
        """The wire form, for tools and tests that speak JSON: a command by its name and
        arguments as they are (unchecked), the reply as JSON data with its `ok`."""

        def payload() -> bytes:
            token = {"token": self.token} if self.token is not None else {}
            return json.dumps({"cmd": cmd, **token, **args}).encode()

        reply: dict[str, Any] = json.loads(
            self._exchange(cmd, payload, timeout_s, relogin=cmd != "login")
        )
        return reply

    def login(self, user: str, password: str) -> LoginReply:
        """Log in; the token goes with every later command. Raises Refusal when refused."""
        login = Login(user, password)
        reply = self._exchange(login.NAME, lambda: encode_request(login, None), relogin=False)
        logged_in = decode_reply(login, reply)
        self.token = logged_in.token
        return logged_in

    def use_credentials(self, user: str, password: str) -> None:
        """Log in whenever the resource asks for it (at the first command, after a runtime
        restart or an expired session)."""
        self._credentials = (user, password)

    def wait_until_answering(self, timeout_s: float = 30) -> None:
        """Wait for the resource to answer (a runtime that is still starting)."""
        deadline = time.monotonic() + timeout_s
        while True:
            try:
                self.ask(GetStatus())
                return
            except Refusal:  # an answer all the same
                return
            except ResourceUnreachable:
                if time.monotonic() > deadline:
                    raise
                time.sleep(0.1)

    def _exchange(
        self,
        name: str,
        payload: Callable[[], bytes],
        timeout_s: float = COMMAND_TIMEOUT_S,
        relogin: bool = True,
    ) -> bytes:
        """Send a request; log in again once when the session is gone (its expiry or a
        restart of the runtime) and the client has credentials. `payload` makes the request
        with the token of the moment."""
        reply = self._send(name, payload(), timeout_s)
        if not relogin or self._credentials is None or not _unauthenticated(reply):
            return reply
        try:
            self.login(*self._credentials)
        except Refusal:
            return reply
        return self._send(name, payload(), timeout_s)

    def _send(self, name: str, payload: bytes, timeout_s: float) -> bytes:
        replies = self.session.get(command_key(self.resource), payload=payload, timeout=timeout_s)
        for reply in replies:
            if reply.ok is not None:
                return bytes(reply.ok.payload.to_bytes())
        raise ResourceUnreachable(f"resource '{self.resource}' did not answer '{name}'")

    # ---- publications
    def on_status(self, callback: Callable[[Status], None]) -> None:
        self._subscribers.append(self._declare(status_key(self.resource), Status, callback))

    def on_events(self, callback: Callable[[Event], None]) -> None:
        """Every event of the resource's log from now on, in order."""
        self._subscribers.append(self._declare(events_key(self.resource), Event, callback))

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

    def watch(
        self,
        variables: list[str],
        callback: Callable[[WatchValues], None],
        period_ms: int = 100,
    ) -> WatchHandle:
        """Receive the values of `variables` (with their quality) once per period. The set
        lives as long as this session holds its liveliness token (until `close`). Raises
        the resource's Refusal (an unknown variable, a bad period) or ResourceUnreachable."""
        watch_id = secrets.token_hex(8)
        token = self.session.liveliness().declare_token(watcher_key(self.resource, watch_id))
        subscriber = self._declare(watch_key(self.resource, watch_id), WatchValues, callback)
        handle = WatchHandle(watch_id, token, subscriber)
        # a large set goes in several requests, each well inside the request limit
        size = min(WATCH_BATCH, MAX_WATCHED)
        batches = [variables[i : i + size] for i in range(0, len(variables), size)]
        try:
            for number, batch in enumerate(batches or [[]]):
                reply = self.ask(Watch(watch_id, batch, period_ms, append=number > 0))
                handle.variables = reply.variables
        except (Refusal, ResourceUnreachable):
            handle.close()
            with contextlib.suppress(Refusal, ResourceUnreachable):  # only tidying up
                self.ask(Unwatch(watch_id))
            raise
        return handle

    def _declare(
        self, key_expr: str, kind: type[P], callback: Callable[[P], None]
    ) -> zenoh.Subscriber[None]:
        def handler(sample: zenoh.Sample) -> None:
            try:
                message = decode_publication(kind, sample.payload.to_bytes())
            except Refusal as wrong:  # not from a runtime that speaks our protocol
                log.warning("%s on %s dropped: %s", kind.__name__, key_expr, wrong.message)
                return
            callback(message)

        return self.session.declare_subscriber(key_expr, handler)

    def close(self) -> None:
        for subscriber in self._subscribers:
            subscriber.undeclare()
        self._subscribers.clear()


def _unauthenticated(reply: bytes) -> bool:
    if b"unauthenticated" not in reply:  # most replies, some of them large: not parsed twice
        return False
    try:
        data = json.loads(reply)
    except ValueError:
        return False
    return isinstance(data, dict) and data.get("error", {}).get("code") == "unauthenticated"
