"""The runtime's side of Zenoh: command queryable, status and value publishers, liveliness.

Zenoh calls back on its own threads; the callback only queues the query, and the cycle
driver answers it in the housekeeping part of the cycle (so commands never race the cycle).
"""

from __future__ import annotations

import json
import queue
from typing import Any

import zenoh

from runtime.keyspace import alive_key, command_key, status_key, values_key


class ResourceLink:
    def __init__(self, session: zenoh.Session, resource: str) -> None:
        self.inbox: queue.Queue[zenoh.Query] = queue.Queue()
        self._queryable = session.declare_queryable(command_key(resource), self.inbox.put)
        self._status = session.declare_publisher(
            status_key(resource), congestion_control=zenoh.CongestionControl.BLOCK
        )
        # live values may drop under congestion: the next cycle brings fresh ones
        self._values = session.declare_publisher(values_key(resource))
        self._token = session.liveliness().declare_token(alive_key(resource))

    def publish_status(self, status: dict[str, Any]) -> None:
        self._status.put(json.dumps(status))

    def publish_values(self, cycle: int, values: dict[str, Any]) -> None:
        self._values.put(json.dumps({"cycle": cycle, "values": values}))

    @staticmethod
    def payload(query: zenoh.Query) -> bytes:
        return query.payload.to_bytes() if query.payload is not None else b"{}"

    @staticmethod
    def reply(query: zenoh.Query, reply: dict[str, Any]) -> None:
        query.reply(query.key_expr, json.dumps(reply))

    def close(self) -> None:
        self._token.undeclare()
        self._queryable.undeclare()
        self._status.undeclare()
        self._values.undeclare()
