"""The variable exchange between resources (runtime/field_io/peer_exchange/, docs/exchange.md)
with real runtime processes on one router: a value written in one resource arrives in the
other; a publisher that stops or dies puts the safe values in place, marked bad, with an
event, and the subscriber recovers by itself; a message signed with another key, or a
replayed one, is refused."""

from __future__ import annotations

import contextlib
import subprocess
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import zenoh

from backend.engineering.resource_client import ResourceClient
from runtime.contract.keyspace import exchange_key
from runtime.contract.protocol import (
    DeviceStatus,
    GetEvents,
    GetIo,
    GetStatus,
    GetValues,
    ResourceState,
    Start,
    Stop,
    Write,
)
from runtime.contract.signatures import stamp_bytes, stamped
from runtime.field_io.peer_exchange.message import encode
from runtime.identity import Identity
from tests.runtime.test_modbus_server import wait_for
from tests.support.ports import free_port
from tests.support.runtime_process import (
    client_session,
    router,
    runtime_process,
    stored_project,
    wait_until_answering,
)

GLOBALS = """
VAR_GLOBAL
    gCount : DINT;
    gSetpoint : REAL := 1.5;
    gName : STRING[16] := 'tank';
    gRemoteCount : DINT;
    gRemoteSetpoint : REAL;
    gRemoteName : STRING[16];
END_VAR
"""
PRODUCER_ST = (
    GLOBALS
    + """
PROGRAM Count
VAR_EXTERNAL gCount : DINT; END_VAR
gCount := gCount + 1;
END_PROGRAM
"""
)
CONSUMER_ST = (
    GLOBALS
    + """
PROGRAM Use
VAR_EXTERNAL gRemoteCount : DINT; END_VAR
VAR seen : DINT; END_VAR
seen := gRemoteCount;
END_PROGRAM
"""
)
PRODUCER_TOML = """
[project]
name = "producer"
[resource]
name = "Producer"
autostart = "cold"
safety_operation = false  # the test writes a published value online
[[exchange.publish]]
name = "levels"
variables = ["gCount", "gSetpoint", "gName"]
period_ms = 20
"""
CONSUMER_TOML = """
[project]
name = "consumer"
[resource]
name = "Consumer"
autostart = "cold"
[[exchange.subscribe]]
resource = "Producer"
publication = "levels"
timeout_ms = 300
[[exchange.subscribe.variable]]
variable = "gRemoteCount"
from = "gCount"
safe_value = -1
[[exchange.subscribe.variable]]
variable = "gRemoteSetpoint"
from = "gSetpoint"
safe_value = -2.5
[[exchange.subscribe.variable]]
variable = "gRemoteName"
from = "gName"
safe_value = "lost"
"""
SAFE = {"gRemoteCount": -1, "gRemoteSetpoint": -2.5, "gRemoteName": "lost"}


@contextlib.contextmanager
def _resource(
    name: str, state: Path, endpoint: str, session: zenoh.Session
) -> Iterator[tuple[subprocess.Popen[bytes], ResourceClient]]:
    # the Python tier: the exchange is the same on both, and no C build slows the start
    with runtime_process(name, state, endpoint, "--no-native-code") as process:
        client = ResourceClient(session, name)
        wait_until_answering(client)
        yield process, client
        client.close()


def _values(client: ResourceClient) -> dict[str, Any]:
    found = client.ask(GetValues()).values
    return {name: found[name] for name in SAFE}


def _subscription(client: ResourceClient) -> DeviceStatus:
    io = client.ask(GetStatus()).status.io
    assert io is not None
    return io.devices[0]


def _events(client: ResourceClient) -> list[str]:
    return [e.message for e in client.ask(GetEvents(limit=1000)).events if e.kind == "io"]


def _flowing(consumer: ResourceClient) -> bool:
    """Fresh values arrive: the publisher's counter moves on in the subscriber."""
    first = _values(consumer)["gRemoteCount"]
    return bool(first > 0 and wait_for(lambda: _values(consumer)["gRemoteCount"] > first))


def test_values_flow_and_a_stale_publisher_gives_safe_values(tmp_path: Path) -> None:
    producer_state = stored_project(tmp_path, "producer", PRODUCER_ST, PRODUCER_TOML)
    consumer_state = stored_project(tmp_path, "consumer", CONSUMER_ST, CONSUMER_TOML)
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    with (
        router(endpoint),
        client_session(endpoint) as session,
        _resource("Consumer", consumer_state, endpoint, session) as (_, consumer),
    ):
        # before any message: the safe values, marked bad
        assert wait_for(lambda: _values(consumer) == SAFE, 20)
        with _resource("Producer", producer_state, endpoint, session) as (_, producer):
            wait_for(lambda: _flowing(consumer), 30)
            assert _values(consumer)["gRemoteName"] == "tank"
            producer.ask(Write("gSetpoint", 42.25))
            wait_for(lambda: _values(consumer)["gRemoteSetpoint"] == 42.25)
            subscription = _subscription(consumer)
            assert (subscription.state, subscription.protocol) == ("connected", "zenoh")
            assert subscription.host == "padt/v2/res/Producer/exchange/levels"
            points = {p.variable: p for p in consumer.ask(GetIo()).points}
            assert points["gRemoteSetpoint"].quality == "good"
            assert points["gRemoteSetpoint"].place == "Producer/levels.gSetpoint"
            published = {p.variable: p for p in producer.ask(GetIo()).points}
            assert published["gSetpoint"].value == 42.25

            # the publisher stops: safe values at once, marked bad, an event
            producer.ask(Stop())
            wait_for(lambda: _values(consumer) == SAFE)
            wait_for(lambda: _subscription(consumer).state == "lost")
            points = {p.variable: p for p in consumer.ask(GetIo()).points}
            assert points["gRemoteCount"].quality == "bad"
            assert any(
                "Exchange Producer/levels lost: Producer does not run" in m
                for m in _events(consumer)
            )
            producer.ask(Start())
            wait_for(lambda: _flowing(consumer), 20)
            assert "Exchange Producer/levels connected again" in _events(consumer)
            assert consumer.ask(GetStatus()).status.state == ResourceState.RUN
            publisher_key = Identity.kept_in(producer_state / "identity.key").public_key

        # the publisher's process ends: safe values within the timeout, and the cause
        wait_for(lambda: _values(consumer) == SAFE)
        assert "no message for 300 ms" in (_subscription(consumer).last_error or "")

        # someone else puts on the publication's key: a message signed with its own key
        # (not the one pinned), then one that claims the publisher's key; neither is taken
        refused_before = _subscription(consumer).failures
        _forge(session, {"gCount": ["DINT", 7]})
        wait_for(lambda: "another key" in (_subscription(consumer).last_error or ""))
        _forge(session, {"gCount": ["DINT", 8]}, claimed_key=publisher_key)
        wait_for(lambda: "does not verify" in (_subscription(consumer).last_error or ""))
        # and bytes that are no message at all: refused, and the resource cycles on
        for garbage in (b"[" * 100_000, b"\xff" * 300_000, b"{}"):
            before = _subscription(consumer).failures
            _put(session, garbage)
            wait_for(lambda: _subscription(consumer).failures > before)  # noqa: B023
        assert _subscription(consumer).failures >= refused_before + 5
        assert _values(consumer) == SAFE
        cycle = consumer.ask(GetStatus()).status.cycle
        wait_for(lambda: consumer.ask(GetStatus()).status.cycle > cycle + 10)

        # it comes back: values flow again by themselves
        with _resource("Producer", producer_state, endpoint, session) as (_, producer):
            wait_for(lambda: _flowing(consumer), 30)
            assert _subscription(consumer).state == "connected"


def _forge(session: zenoh.Session, values: dict[str, list[Any]], claimed_key: str = "") -> None:
    """A message on the publication's key, signed with a new key; it names `claimed_key`
    as its signer's (its own when empty)."""
    signer = Identity.fresh()
    entries = [(name, kind, value) for name, (kind, value) in values.items()]
    payload = encode("Producer", "levels", True, claimed_key or signer.public_key, entries)
    stamp = stamp_bytes(1 << 40, 1)  # newer than anything the publisher stamped
    attachment = stamp + signer.sign(stamped(stamp, payload))
    _put(session, payload, attachment)


def _put(session: zenoh.Session, payload: bytes, attachment: bytes | None = None) -> None:
    """On the publication's key, never dropped (Zenoh drops a put under congestion unless
    told to block: a test's message must arrive)."""
    session.put(
        exchange_key("Producer", "levels"),
        payload,
        attachment=attachment,
        congestion_control=zenoh.CongestionControl.BLOCK,
    )
