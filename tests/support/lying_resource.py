"""A hostile peer on a resource's command key, for the recording download tests: it
answers `record_list` with one recording `x` of one file, and `record_read` with that
file's bytes, or with a lie as told (a wrong offset, a file that shrinks, data that is not
base64, no bytes, a negative size, a terabyte). Real Zenoh, a real router: only the peer is not a
runtime."""

from __future__ import annotations

import base64
import json
import os
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Any

import zenoh

from backend.engineering.resource_client import ResourceClient
from runtime.contract.keyspace import command_key
from runtime.contract.protocol import MAX_RECORDING_READ
from tests.support.runtime_process import client_session, router

RESOURCE = "Fake"
FILE = os.urandom(3 * MAX_RECORDING_READ + 1234)  # four record_read


@dataclass
class Liar:
    endpoint: str
    client: ResourceClient
    lie: str = "none"
    asked: list[str] = field(default_factory=list)  # the commands that came

    def answer(self, request: dict[str, Any]) -> dict[str, Any]:
        self.asked.append(request["cmd"])
        if request["cmd"] == "record_list":
            recording = {"id": "x", "state": "done", "variables": 1, "all_inputs": False}
            recording.update(cycles=9, dropped=0, started_ns=1)
            recording["files"] = [{"name": "x-1.mcap", "size": len(FILE)}]
            return {"ok": True, "recordings": [recording]}
        if request["cmd"] != "record_read":
            return {"ok": False, "error": {"code": "forbidden", "message": "not here"}}
        offset, length = request["offset"], request["length"]
        reply: dict[str, Any] = {"ok": True, "offset": offset, "size": len(FILE)}
        reply["data"] = base64.b64encode(FILE[offset : offset + length]).decode()
        if offset > 0 and self.lie == "offset":
            reply["offset"] = offset - 10
        elif offset > 0 and self.lie == "shrinks":
            reply["size"] = offset
        elif offset > 0 and self.lie == "base64":
            reply["data"] = "not base64!"
        elif offset > 0 and self.lie == "empty":
            reply["data"] = ""
        elif self.lie == "negative":
            reply["size"] = -1
        elif self.lie == "terabyte":
            reply["size"] = 1 << 40
        return reply


@contextmanager
def lying_resource(endpoint: str) -> Iterator[Liar]:
    with router(endpoint), client_session(endpoint) as peer, client_session(endpoint) as ours:
        liar = Liar(endpoint, ResourceClient(ours, RESOURCE))

        def reply(query: zenoh.Query) -> None:
            request = json.loads(query.payload.to_bytes() if query.payload else b"{}")
            query.reply(query.key_expr, json.dumps(liar.answer(request)))

        queryable = peer.declare_queryable(command_key(RESOURCE), reply)
        try:
            liar.client.wait_until_answering()
            yield liar
        finally:
            queryable.undeclare()
