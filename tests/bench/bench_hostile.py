"""The cost of hostile clients: a runtime process at a 20 ms target cycle, its cycle rate
measured quietly (the baseline), then under each class of attack sent as fast as one
client can, and its memory before and after. Prints figures and ratios; asserts nothing."""

from __future__ import annotations

import json
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import zenoh

from backend.engineering.resource_client import ResourceClient
from runtime.contract.keyspace import status_key
from tests.runtime.test_hostile_clients import RUNTIMES, TARGET_MS, raw, rss_kib, target
from tests.support.runtime_process import client_session

SECONDS = 3.0
ENDPOINT = "tcp/127.0.0.1:7931"


def _cycles(client: ResourceClient) -> int:
    return int(client.command("status")["status"]["cycle"])


def _attacks(rogue: zenoh.Session) -> dict[str, Callable[[int], object]]:
    deep = b"[" * 900
    wrong = json.dumps({"cmd": "events", "limit": -1, "after": "x"}).encode()
    login = json.dumps({"cmd": "login_begin", "user": "admin", "nonce": "n" * 24}).encode()
    forged = json.dumps({"cmd": "stop", "token": "t" * 48, "seq": 1}).encode()
    grow = json.dumps({"cmd": "watch", "id": "w", "variables": ["Main.counter"] * 3000})
    return {
        "nested JSON (900 deep)": lambda n: raw(rogue, deep),
        "wrong types and ranges": lambda n: raw(rogue, wrong),
        "login challenges (one source)": lambda n: raw(rogue, login),
        "forged session tokens": lambda n: raw(rogue, forged),
        "watch set of 3,000 paths": lambda n: raw(rogue, grow.encode()),
        "forged status publications": lambda n: rogue.put(status_key("Target"), b"{}"),
    }


def main() -> None:
    print(f"hostile clients: a runtime at a {TARGET_MS} ms target cycle, {SECONDS:g} s per attack")
    with tempfile.TemporaryDirectory() as folder, target(Path(folder), ENDPOINT) as client:
        pid = RUNTIMES[id(client)]
        with client_session(ENDPOINT) as rogue:
            start = _cycles(client)
            time.sleep(SECONDS)
            baseline = (_cycles(client) - start) / SECONDS
            before = rss_kib(pid)
            print(f"  quiet: {baseline:.1f} cycles/s; runtime RSS {before / 1024:.1f} MiB")
            for name, attack in _attacks(rogue).items():
                start, begun, sent = _cycles(client), time.monotonic(), 0
                while time.monotonic() - begun < SECONDS:
                    attack(sent)
                    sent += 1
                elapsed = time.monotonic() - begun
                rate = (_cycles(client) - start) / elapsed
                print(
                    f"  {name:30} {sent:9,} messages ({sent / elapsed:7,.0f}/s): "
                    f"{rate:5.1f} cycles/s = {rate / baseline:.2f} of quiet; "
                    f"RSS {rss_kib(pid) / 1024:.1f} MiB"
                )
            after = rss_kib(pid)
            stats = client.command("status")["status"]["stats"]
        print(
            f"  runtime RSS after: {after / 1024:.1f} MiB ({after / before:.2f} of before); "
            f"overruns {stats['overruns']}, watch sets deferred {stats['watch_deferred']}"
        )


if __name__ == "__main__":
    main()
