"""The resources on the bus: which are online (found by their liveliness tokens), the
status each last published, and a client for one of them. The API answers for a resource
only while it is online, so a request for an unknown name is a quick 404 instead of a
command that times out.

A status counts only when the resource signed it with the key a login to it proved
(`trust`), and when it is newer than the last one taken (a status put again later is
not the resource's now); until someone logged in to a resource, its status is unknown
here rather than possibly forged."""

from __future__ import annotations

import threading

import zenoh

from backend.engineering.known_resources import KnownResources
from backend.engineering.resource_client import ResourceClient
from runtime.contract import signatures
from runtime.contract.keyspace import alive_key, any_resource, resource_of, status_key
from runtime.contract.protocol import Status, decode_publication
from runtime.contract.refusal import Refusal


class ResourceDirectory:
    def __init__(self, session: zenoh.Session, known: KnownResources | None = None) -> None:
        self._session = session
        self._known = known  # where its clients pin the resources' keys (None: the user's)
        self._lock = threading.Lock()
        self._online: set[str] = set()
        self._status: dict[str, Status] = {}
        self._keys: dict[str, str] = {}  # resource -> the publication key a login proved
        self._freshness = signatures.Freshness()  # the newest status stamp of each resource
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
        name, payload = resource_of(str(sample.key_expr)), sample.payload.to_bytes()
        signed = sample.attachment.to_bytes() if sample.attachment is not None else None
        with self._lock:
            key = self._keys.get(name)
        stamp = signatures.verified_stamp(key, payload, signed) if key is not None else None
        if stamp is None:
            return  # not known to be the resource's own
        if not self._freshness.newer(name, stamp):
            return  # one it published before (a replay): not its status now
        try:
            status = decode_publication(Status, payload)
        except Refusal:
            return
        with self._lock:
            if name in self._online:
                self._status[name] = status

    def online(self) -> list[tuple[str, Status | None]]:
        """Each online resource (sorted by name) with its last published status, if any."""
        with self._lock:
            return [(name, self._status.get(name)) for name in sorted(self._online)]

    def trust(self, name: str, publication_key: str) -> None:
        """The key a login to `name` proved: its publications verify with it."""
        with self._lock:
            self._keys[name] = publication_key

    def client(self, name: str) -> ResourceClient:
        """A client of an online resource; Refusal `unknown_resource` for any other."""
        if not self.is_online(name):
            raise Refusal("unknown_resource", f"no resource '{name}' is online")
        client = ResourceClient(self._session, name, self._known)
        with self._lock:
            client.trusted_key = self._keys.get(name)
        return client

    def is_online(self, name: str) -> bool:
        with self._lock:
            return name in self._online

    def close(self) -> None:
        self._alive.undeclare()
        self._statuses.undeclare()
