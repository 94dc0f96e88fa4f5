"""The runtime's side of Zenoh: command queryable, status publisher, watch-set values,
liveliness.

Zenoh calls back on its own threads; the callbacks only hand a query to the request intake
(`request_intake.py`: refused by size at once, decoded on a thread of its own) or note a
watcher coming or going, and the cycle driver answers the decoded requests in the
housekeeping part of the cycle (so commands never race the cycle).

Everything the resource publishes is encoded, signed and put by one publisher thread: the
status and the events must reach every subscriber (Zenoh then blocks while a subscriber is
slow, as a busy PADT with ten browsers was), and the cycle must never wait for that.
"""

from __future__ import annotations

import functools
import itertools
import json
import threading
from collections import deque
from collections.abc import KeysView

import zenoh

from runtime.contract.accounts import ANONYMOUS
from runtime.contract.keyspace import (
    alive_key,
    command_key,
    events_key,
    status_key,
    watch_key,
    watcher_key,
)
from runtime.contract.protocol import Event, Request, Status, decode_request
from runtime.contract.signatures import stamp_bytes, stamped
from runtime.contract.wire import encode
from runtime.identity import Identity
from runtime.request_intake import RequestIntake
from runtime.watch_sets import WatchSnapshot


class ResourceLink:
    def __init__(self, session: zenoh.Session, resource: str, identity: Identity) -> None:
        self._identity = identity  # every publication is signed with its key
        self._numbers = itertools.count(1)  # and stamped: its boot, and its number in it
        self.intake = RequestIntake(self._decode)
        self._queryable = session.declare_queryable(command_key(resource), self.intake.receive)
        self._status = session.declare_publisher(
            status_key(resource), congestion_control=zenoh.CongestionControl.BLOCK
        )
        # events must all arrive, in order: the publisher waits rather than drop one
        self._events = session.declare_publisher(
            events_key(resource), congestion_control=zenoh.CongestionControl.BLOCK
        )
        self._session = session
        self._resource = resource
        # what the publisher thread has yet to put: every event in order, the newest
        # status (an older one not yet sent is outdated), each watch set's newest values
        self._pending: dict[str, WatchSnapshot] = {}
        self._pending_events: deque[Event] = deque()
        self._pending_status: Status | None = None
        self._pending_lock = threading.Condition()
        self._closing = False
        self._publisher = threading.Thread(
            target=self._publish_loop, name="padt-publisher", daemon=True
        )
        self._publisher.start()
        # the watch sets whose client holds its liveliness token (Zenoh's threads add and
        # remove ids; the cycle thread only asks). Only the tokens of the sets the resource
        # has are followed, each by a subscriber of its own (`follow_watchers`): tokens of
        # made-up ids (anyone may declare them, no login needed) never reach this process
        self.watchers: set[str] = set()
        self._followed: dict[str, zenoh.Subscriber[None]] = {}
        # the ids whose tokens count, each in it before its subscriber is declared: Zenoh
        # may deliver the token already there (the history) on its own thread before
        # `declare_subscriber` returns; taken for a stray sample then, the set was dropped
        # 2 s after it came (WATCHER_GRACE_NS) with its client still there (CI run 79)
        self._following: set[str] = set()
        self._token = session.liveliness().declare_token(alive_key(resource))

    def follow_watchers(self, ids: KeysView[str]) -> None:
        """Follow the liveliness tokens of the sets `ids` (the resource's, on the cycle
        thread), and no others; Zenoh is told only when the sets changed."""
        if ids == self._followed.keys():
            return
        liveliness = self._session.liveliness()
        for watch_id in self._followed.keys() - ids:
            self._following.discard(watch_id)
            self._followed.pop(watch_id).undeclare()
            self.watchers.discard(watch_id)
        for watch_id in ids - self._followed.keys():
            self._following.add(watch_id)
            self._followed[watch_id] = liveliness.declare_subscriber(
                watcher_key(self._resource, watch_id),
                functools.partial(self._on_watcher, watch_id),
                history=True,
            )

    def _on_watcher(self, watch_id: str, sample: zenoh.Sample) -> None:
        if sample.kind == zenoh.SampleKind.PUT and watch_id in self._following:
            self.watchers.add(watch_id)
        else:
            self.watchers.discard(watch_id)

    def publish_status(self, status: Status) -> None:
        """Sent by the publisher thread; a newer status replaces one not yet sent."""
        with self._pending_lock:
            self._pending_status = status
            self._pending_lock.notify()

    def publish_event(self, event: Event) -> None:
        """Sent by the publisher thread, every one, in order."""
        with self._pending_lock:
            self._pending_events.append(event)
            self._pending_lock.notify()

    def publish_watch(self, watch_id: str, snapshot: WatchSnapshot) -> None:
        """A watch set's values, read in this cycle; the message is built, encoded and put
        on the publisher thread (for 10,000 values that is most of the work), and may drop
        under congestion: the next period brings fresh ones. A snapshot not yet sent is
        replaced by a newer one of the same set."""
        with self._pending_lock:
            self._pending[watch_id] = snapshot
            self._pending_lock.notify()

    def _publish_loop(self) -> None:
        while True:
            with self._pending_lock:
                while not (self._pending or self._pending_events or self._pending_status):
                    if self._closing:
                        return
                    self._pending_lock.wait()
                events, self._pending_events = list(self._pending_events), deque()
                status, self._pending_status = self._pending_status, None
                watched = next(iter(self._pending.items()), None)
                if watched is not None:
                    del self._pending[watched[0]]
                if self._closing:
                    watched = None  # the last events and status go out, values no more
            for event in events:
                self._put(self._events, encode(event))
            if status is not None:
                self._put(self._status, encode(status))
            if watched is not None:
                watch_id, snapshot = watched
                payload = snapshot.message()
                self._session.put(
                    watch_key(self._resource, watch_id),
                    payload,
                    attachment=self._signed(payload),
                    congestion_control=zenoh.CongestionControl.DROP,
                )

    def _put(self, publisher: zenoh.Publisher, message: object) -> None:
        payload = json.dumps(message).encode()
        publisher.put(payload, attachment=self._signed(payload))

    def _signed(self, payload: bytes) -> bytes:
        """The attachment of a publication (runtime/contract/signatures.py): its stamp and
        the signature of stamp and payload. Only the publisher thread numbers them."""
        stamp = stamp_bytes(self._identity.boot, next(self._numbers))
        return stamp + self._identity.sign(stamped(stamp, payload))

    def _decode(self, query: zenoh.Query) -> Request:
        """On the intake's thread: the request checked whole (Refusal otherwise)."""
        return decode_request(self.payload(query), self.source(query), self.mac(query))

    @staticmethod
    def payload(query: zenoh.Query) -> bytes:
        return query.payload.to_bytes() if query.payload is not None else b"{}"

    @staticmethod
    def source(query: zenoh.Query) -> str:
        """The Zenoh session the sender names as its own (clients of this project do); the
        same for all that name none. It tells callers apart for the login lock, no more."""
        info = query.source_info
        return str(info.source_id.zid) if info is not None else ANONYMOUS

    @staticmethod
    def mac(query: zenoh.Query) -> bytes | None:
        """The MAC a request of a session carries as its attachment."""
        return query.attachment.to_bytes() if query.attachment is not None else None

    @staticmethod
    def reply(query: zenoh.Query, reply: bytes) -> None:
        query.reply(query.key_expr, reply)

    def close(self) -> None:
        with self._pending_lock:
            self._closing = True
            self._pending_lock.notify()
        self._publisher.join()
        self._token.undeclare()
        for subscriber in self._followed.values():
            subscriber.undeclare()
        self._queryable.undeclare()
        self.intake.close()
        self._status.undeclare()
        self._events.undeclare()
