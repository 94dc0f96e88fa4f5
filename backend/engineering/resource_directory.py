"""The resources on the bus: which are online (found by their liveliness tokens), the
status each last published, and a client for one of them. The API answers for a resource
only while it is online, so a request for an unknown name is a quick 404 instead of a
command that times out."""

from __future__ import annotations

import threading

import zenoh

from backend.engineering.resource_client import ResourceClient
from runtime.contract.keyspace import alive_key, any_resource, resource_of, status_key
from runtime.contract.protocol import Status, decode_publication
from runtime.contract.refusal import Refusal


class ResourceDirectory:
    def __init__(self, session: zenoh.Session) -> None:
        self._session = session
        self._lock = threading.Lock()
        self._online: set[str] = set()
        self._status: dict[str, Status] = {}
        self._alive = session.liveliness().declare_subscriber(
            any_resource(alive_key), self._on_alive, history=True
        )
        self._statuses = session.declare_subscriber(any_resource(status_key), self._on_status)

    def _on_alive(self, sample: zenoh.Sample) -> None:
        name = resource_of(str(sample.key_expr))
        with self._lock:
            if sample.kind == zenoh.SampleKind.PUT:
                self._online.add(name)
            else:
                self._online.discard(name)
                self._status.pop(name, None)

    def _on_status(self, sample: zenoh.Sample) -> None:
        try:
            status = decode_publication(Status, sample.payload.to_bytes())
        except Refusal:
            return  # not from a runtime of ours
        name = resource_of(str(sample.key_expr))
        with self._lock:
            if name in self._online:
                self._status[name] = status

    def online(self) -> list[tuple[str, Status | None]]:
        """Each online resource (sorted by name) with its last published status, if any."""
        with self._lock:
            return [(name, self._status.get(name)) for name in sorted(self._online)]

    def client(self, name: str) -> ResourceClient:
        """A client of an online resource; Refusal `unknown_resource` for any other."""
        if not self.is_online(name):
            raise Refusal("unknown_resource", f"no resource '{name}' is online")
        return ResourceClient(self._session, name)

    def is_online(self, name: str) -> bool:
        with self._lock:
            return name in self._online

    def close(self) -> None:
        self._alive.undeclare()
        self._statuses.undeclare()
