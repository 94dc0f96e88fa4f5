"""The live-values WebSocket against hostile first messages and chatter: each bad first
message gets a structured refusal before the socket closes, and chatter after a good one
(binary, nested a hundred thousand deep) does not end the stream of values."""

from __future__ import annotations

import json
from collections.abc import Iterator

import pytest
from websockets.exceptions import ConnectionClosed
from websockets.sync.client import connect

from tests.support.rest_plant import Plant, plant

POLICY_VIOLATION = 1008


@pytest.fixture(scope="module")
def site(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Plant]:
    with plant(tmp_path_factory.mktemp("live-hostile")) as found:
        yield found


def live_url(site: Plant) -> str:
    return site.url.replace("http://", "ws://") + "/api/resources/Plant/live"


@pytest.mark.parametrize(
    "first",
    [
        b"[" * 100_000,
        "[" * 100_000,
        "[" * 17 + "]" * 17,
        "{" * 5_000,
        b"\x00binary",
        "x" * 2_000_000,
    ],
    ids=["deep-binary", "deep-text", "17-deep", "deep-objects", "binary", "two-megabytes"],
)
def test_a_hostile_first_message_gets_a_refusal_then_the_socket_closes(
    site: Plant, first: str | bytes
) -> None:
    with connect(live_url(site), max_size=None) as ws:
        ws.send(first)
        reply = json.loads(ws.recv(timeout=20))
        assert reply["error"]["code"] == "bad_request", reply
        with pytest.raises(ConnectionClosed) as closed:
            ws.recv(timeout=20)
    assert closed.value.rcvd is not None and closed.value.rcvd.code == POLICY_VIOLATION


def test_chatter_after_the_first_message_does_not_end_the_values(site: Plant) -> None:
    token = site.session("builder", "op")
    with connect(live_url(site), max_size=None) as ws:
        ws.send(json.dumps({"token": token, "variables": ["P.n"], "period_ms": 50}))
        assert json.loads(ws.recv(timeout=10)) == {"variables": ["P.n"]}
        for chatter in (b"\x00binary", "[" * 100_000, "not json"):
            ws.send(chatter)
        cycles = [json.loads(ws.recv(timeout=10))["cycle"] for _ in range(5)]
        assert cycles == sorted(cycles) and len(set(cycles)) == 5
