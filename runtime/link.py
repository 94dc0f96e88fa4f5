"""The runtime's side of Zenoh: command queryable, status publisher, watch-set values,
liveliness.

Zenoh calls back on its own threads; the callbacks only queue a query or note a watcher
coming or going, and the cycle driver handles them in the housekeeping part of the cycle
(so commands never race the cycle).
"""

from __future__ import annotations

import json
import queue
import threading

import zenoh

from runtime.contract.accounts import ANONYMOUS
from runtime.contract.keyspace import (
    alive_key,
    command_key,
    events_key,
    status_key,
    watch_id_of,
    watch_key,
    watchers_key_expr,
)
from runtime.contract.protocol import Event, Status
from runtime.contract.wire import encode
from runtime.identity import Identity
from runtime.watch_sets import WatchSnapshot


class ResourceLink:
    def __init__(self, session: zenoh.Session, resource: str, identity: Identity) -> None:
        self._identity = identity  # every publication is signed with its key
        self.inbox: queue.Queue[zenoh.Query] = queue.Queue()
        self._queryable = session.declare_queryable(command_key(resource), self.inbox.put)
        self._status = session.declare_publisher(
            status_key(resource), congestion_control=zenoh.CongestionControl.BLOCK
        )
        # events must all arrive, in order: the publisher waits rather than drop one
        self._events = session.declare_publisher(
            events_key(resource), congestion_control=zenoh.CongestionControl.BLOCK
        )
        self._session = session
        self._resource = resource
        self._pending: dict[str, WatchSnapshot] = {}
        self._pending_lock = threading.Condition()
        self._closing = False
        self._publisher = threading.Thread(
            target=self._publish_loop, name="padt-watch-publisher", daemon=True
        )
        self._publisher.start()
        # the watch sets whose client holds its liveliness token (Zenoh's threads add and
        # remove ids; the cycle thread only asks)
        self.watchers: set[str] = set()
        self._watchers = session.liveliness().declare_subscriber(
            watchers_key_expr(resource), self._on_watcher, history=True
        )
        self._token = session.liveliness().declare_token(alive_key(resource))

    def _on_watcher(self, sample: zenoh.Sample) -> None:
        watch_id = watch_id_of(str(sample.key_expr))
        if sample.kind == zenoh.SampleKind.PUT:
            self.watchers.add(watch_id)
        else:
            self.watchers.discard(watch_id)

    def publish_status(self, status: Status) -> None:
        payload = json.dumps(encode(status)).encode()
        self._status.put(payload, attachment=self._identity.sign(payload))

    def publish_event(self, event: Event) -> None:
        payload = json.dumps(encode(event)).encode()
        self._events.put(payload, attachment=self._identity.sign(payload))

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
                while not self._pending and not self._closing:
                    self._pending_lock.wait()
                if self._closing:
                    return
                watch_id, snapshot = next(iter(self._pending.items()))
                del self._pending[watch_id]
            payload = json.dumps(snapshot.message()).encode()
            self._session.put(
                watch_key(self._resource, watch_id),
                payload,
                attachment=self._identity.sign(payload),
                congestion_control=zenoh.CongestionControl.DROP,
            )

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
        self._watchers.undeclare()
        self._queryable.undeclare()
        self._status.undeclare()
        self._events.undeclare()
