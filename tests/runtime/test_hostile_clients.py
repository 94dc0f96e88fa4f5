"""A resource against hostile clients on the bus: a real router, a real runtime process, and
requests no well-behaved client sends. After each attack the resource still cycles at its
rate and answers its status."""

from __future__ import annotations

import json
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import zenoh

from backend.compiler.pipeline import compile_sources
from backend.compiler.source import SourceFile
from backend.engineering.resource_client import ResourceClient
from runtime.contract.accounts import hash_password
from runtime.contract.artifact import ProgramConfig, ResourceConfig, UserAccount
from runtime.contract.keyspace import command_key
from tests.support.runtime_process import client_session, running_resource, store_artifact

RESOURCE = "Target"
TARGET_MS = 20
PASSWORD = "Secret-1"
SOURCE = """\
PROGRAM Main
VAR counter : DINT; END_VAR
counter := counter + 1;
END_PROGRAM
"""


@contextmanager
def target(tmp_path: Path, endpoint: str) -> Iterator[ResourceClient]:
    """A running resource with a reader and an administrator, and a logged-in client."""
    config = ResourceConfig(RESOURCE, target_cycle_ms=TARGET_MS, autostart="cold")
    users = [
        UserAccount("reader", "read", hash_password(PASSWORD)),
        UserAccount("admin", "administrator", hash_password(PASSWORD)),
    ]
    result = compile_sources(
        [SourceFile("main.st", SOURCE)],
        resource=config,
        programs=[ProgramConfig("Main", "Main", 1)],
        users=users,
    )
    assert result.artifact is not None, [str(d) for d in result.diagnostics]
    store_artifact(tmp_path, result.artifact)
    with running_resource(RESOURCE, tmp_path, endpoint) as (_, client):
        client.login("reader", PASSWORD)
        yield client


def cycles_per_second(client: ResourceClient, seconds: float = 1.0) -> float:
    first = int(client.command("status")["status"]["cycle"])
    time.sleep(seconds)
    return (int(client.command("status")["status"]["cycle"]) - first) / seconds


def still_healthy(client: ResourceClient) -> None:
    """Cycling at its rate (within a generous margin: shared machines) and answering."""
    assert client.command("status")["status"]["state"] == "RUN"
    assert cycles_per_second(client) > 0.5 * 1000 / TARGET_MS


def raw(session: zenoh.Session, payload: bytes) -> dict[str, object]:
    """A request as any client on the bus may send it: bytes, not a command object."""
    for reply in session.get(command_key(RESOURCE), payload=payload, timeout=5):
        if reply.ok is not None:
            answer: dict[str, object] = json.loads(reply.ok.payload.to_bytes())
            return answer
    raise AssertionError("no answer")


def test_watch_sets_end_with_their_session_and_their_liveliness(
    tmp_path: Path, zenoh_endpoint: str
) -> None:
    with target(tmp_path, zenoh_endpoint) as client:
        # a set registered by a bare request, with no liveliness token behind it
        registered = client.command("watch", id="orphan", variables=["Main.counter"])
        assert registered["ok"], registered
        assert "orphan" in client.command("watches")["watches"]
        deadline = time.monotonic() + 10
        while "orphan" in client.command("watches")["watches"]:
            assert time.monotonic() < deadline, "a set without its client stayed"
            time.sleep(0.1)
        # a well-behaved client's set ends with its session
        with client_session(zenoh_endpoint) as other_session:
            other = ResourceClient(other_session, RESOURCE)
            other.login("reader", PASSWORD)
            watch = other.watch(["Main.counter"], lambda message: None)
            assert watch.watch_id in client.command("watches")["watches"]
            assert other.command("logout")["ok"]
            deadline = time.monotonic() + 10
            while watch.watch_id in client.command("watches")["watches"]:
                assert time.monotonic() < deadline, "a set outlived its session"
                time.sleep(0.1)
        still_healthy(client)


def test_malformed_requests_are_refused_before_anything_else(
    tmp_path: Path, zenoh_endpoint: str
) -> None:
    with target(tmp_path, zenoh_endpoint) as client:
        session = client.session
        attacks = [
            b"[" * 500 + b"]" * 500,
            json.dumps({"cmd": "events", "limit": -1, "token": "x", "seq": 1}).encode(),
            json.dumps({"cmd": "start_forcing", "timeout_ms": 10**100}).encode(),
            json.dumps(
                {
                    "cmd": "write",
                    "variable": "Main.counter",
                    "value": [[[[[[[[[[[[[[[[[1]]]]]]]]]]]]]]]]],
                }
            ).encode(),
            b"\xff" * 1000,
            b"{" * 70_000,
        ]
        for attack in attacks:
            error = raw(session, attack)["error"]
            assert isinstance(error, dict) and error["code"] in ("bad_request", "too_large")
        still_healthy(client)
