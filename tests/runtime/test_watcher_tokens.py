"""The liveliness tokens of watch sets as the runtime's link follows them
(runtime/link.py `follow_watchers`), on a real Zenoh router and sessions."""

from __future__ import annotations

import contextlib
import threading
from typing import Any, cast

import zenoh

from runtime.clock import RealClock
from runtime.contract.keyspace import watcher_key
from runtime.contract.session import open_client, open_router
from runtime.link import ResourceLink
from runtime.resource import Resource


class _HistoryFirst:
    """A Zenoh session whose liveliness subscribers return only once their first sample
    has been handled: the order Zenoh may take on its own threads (the token already
    there, its history, before `declare_subscriber` returns), made certain here."""

    def __init__(self, session: zenoh.Session) -> None:
        self._session = session

    def __getattr__(self, name: str) -> Any:
        return getattr(self._session, name)

    def liveliness(self) -> _HistoryFirst:
        return self

    def declare_token(self, key: str) -> zenoh.LivelinessToken:
        return self._session.liveliness().declare_token(key)

    def declare_subscriber(
        self, key: str, handler: Any, history: bool = False
    ) -> zenoh.Subscriber[None]:
        handled = threading.Event()

        def first_then_on(sample: zenoh.Sample) -> None:
            handler(sample)
            handled.set()

        subscriber = self._session.liveliness().declare_subscriber(
            key, first_then_on, history=history
        )
        assert handled.wait(30), "the token's sample never came"
        return subscriber


def test_a_token_delivered_before_its_subscriber_is_declared_counts(
    zenoh_endpoint: str,
) -> None:
    """The history of a set's token handled before `declare_subscriber` returned was taken
    for a sample of a subscriber no longer followed: the client's set seemed to have no
    token and was dropped after its grace, the client still watching (CI run 79)."""
    resource = Resource("R", RealClock())
    with (
        open_router(zenoh_endpoint),
        contextlib.closing(open_client(zenoh_endpoint)) as runtime_side,
        contextlib.closing(open_client(zenoh_endpoint)) as client,
    ):
        token = client.liveliness().declare_token(watcher_key("R", "w1"))
        session = cast(zenoh.Session, _HistoryFirst(runtime_side))
        link = ResourceLink(session, resource.name, resource.identity)
        try:
            link.follow_watchers({"w1": None}.keys())
            assert link.watchers == {"w1"}
        finally:
            link.close()
            token.undeclare()
