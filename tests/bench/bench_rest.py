"""REST API benchmark: what the HTTP layer adds to a command, what a login costs, and the
live values over the WebSocket.

Against the plant of the REST tests (router, runtime process, API server on a real port):
a `status` command sent straight over Zenoh and the same through `GET .../status`
(p50 / p99 and their ratio), a write through `PUT .../values/...`, a PADT login (scrypt),
and the messages per second a WebSocket client gets from a watch set at 10 Hz.

Run with `python -m tests.bench.bench_rest`; prints figures, asserts nothing about time.
"""

from __future__ import annotations

import json
import statistics
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

from websockets.sync.client import connect

from tests.support.rest_plant import PADT_PASSWORDS, plant

ROUNDS = 300
LIVE_SECONDS = 10


def _percentiles_ms(samples_ns: list[int]) -> tuple[float, float]:
    ordered = sorted(samples_ns)
    return ordered[len(ordered) // 2] / 1e6, ordered[int(len(ordered) * 0.99)] / 1e6


def _timed(action: Callable[[], object], rounds: int = ROUNDS) -> list[int]:
    samples = []
    for _ in range(rounds):
        started = time.perf_counter_ns()
        action()
        samples.append(time.perf_counter_ns() - started)
    return samples


def main() -> None:
    with tempfile.TemporaryDirectory() as folder, plant(Path(folder)) as site:
        token = site.session("builder", "engineer")
        site.zenoh_client.login("engineer", "Change-3")
        direct = _timed(lambda: site.zenoh_client.command("status"))
        rest = _timed(lambda: site.call("GET", "/api/resources/Plant/status", token))
        value = "/api/resources/Plant/values/P.limit"
        write = _timed(lambda: site.call("PUT", value, token, json={"value": 9}))
        reader = {"user": "reader", "password": PADT_PASSWORDS["reader"]}
        login = _timed(lambda: site.http.post(f"{site.url}/api/login", json=reader), rounds=20)
        d50, d99 = _percentiles_ms(direct)
        r50, r99 = _percentiles_ms(rest)
        w50, w99 = _percentiles_ms(write)
        print(f"REST API, {ROUNDS} requests each (one client, keep-alive)")
        print(f"  status over Zenoh directly: p50 {d50:.2f} ms, p99 {d99:.2f} ms")
        print(f"  GET status through the API: p50 {r50:.2f} ms, p99 {r99:.2f} ms")
        print(f"  ratio API / direct (p50): {r50 / d50:.1f}")
        print(f"  PUT a value through the API: p50 {w50:.2f} ms, p99 {w99:.2f} ms")
        print(f"  PADT login (scrypt): mean {statistics.mean(login) / 1e6:.0f} ms")

        ws_url = site.url.replace("http://", "ws://") + "/api/resources/Plant/live"
        with connect(ws_url) as ws:
            subscription = {"token": token, "variables": ["P.n", "P.limit", "P.flag"]}
            ws.send(json.dumps({**subscription, "period_ms": 100}))
            json.loads(ws.recv(timeout=10))
            received = 0
            started = time.monotonic()
            while time.monotonic() - started < LIVE_SECONDS:
                json.loads(ws.recv(timeout=10))
                received += 1
        rate = received / LIVE_SECONDS
        print(f"  WebSocket live values at 10 Hz: {rate:.2f} messages/s over {LIVE_SECONDS} s")


if __name__ == "__main__":
    main()
