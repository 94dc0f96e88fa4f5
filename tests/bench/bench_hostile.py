"""The cost of hostile clients: a runtime process at a 20 ms target cycle, its longest period
measured quietly (the baseline, before and after the attacks), then under each class of
attack, and its resident memory after each window. The goal: no period over twice the
target. Prints a table; asserts nothing (the machine is shared: run it twice).

The longest period is the target plus the largest deviation from it the resource reports
(`stats.jitter_max_ms`, reset before each window by `reset_stats`)."""

from __future__ import annotations

import json
import os
import socket
import struct
import tempfile
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import ExitStack, contextmanager
from dataclasses import dataclass
from pathlib import Path

import zenoh

from backend.engineering.resource_client import ResourceClient
from runtime.contract.keyspace import status_key, watcher_key
from runtime.contract.protocol import MAX_SETS_PER_SESSION, MAX_VALUES_PER_SECOND
from tests.runtime.test_hostile_clients import (
    PASSWORD,
    RESOURCE,
    RUNTIMES,
    TARGET_MS,
    raw,
    rss_kib,
    target,
)
from tests.support.ports import free_port
from tests.support.runtime_process import client_session

SECONDS = 3.0  # per window
ENDPOINT = "tcp/127.0.0.1:7931"
KNOWN_RESOURCES = "PADT_KNOWN_RESOURCES"
WATCHER_TOKENS = 3000
PAYLOAD_MB = (1, 5, 10, 25, 50)
READERS = 8
READER_PERIOD_MS = 100
MODBUS_CONNECTIONS = 8


@dataclass(frozen=True)
class Window:
    name: str
    messages: int
    longest_ms: float
    overruns: int
    cycles_per_s: float
    rss_mib: float  # the runtime's resident memory after the window


Flood = Callable[[float], int]  # runs until the deadline (monotonic s); messages sent


def _message_floods(rogue: zenoh.Session) -> dict[str, Flood]:
    deep = b"[" * 900
    wrong = json.dumps({"cmd": "events", "limit": -1, "after": "x"}).encode()
    login = json.dumps({"cmd": "login_begin", "user": "admin", "nonce": "n" * 24}).encode()
    forged = json.dumps({"cmd": "stop", "token": "t" * 48, "seq": 1}).encode()
    grow = json.dumps({"cmd": "watch", "id": "w", "variables": ["Main.counter"] * 3000})

    def repeated(send: Callable[[], object]) -> Flood:
        def flood(deadline: float) -> int:
            sent = 0
            while time.monotonic() < deadline:
                send()
                sent += 1
            return sent

        return flood

    return {
        "nested JSON (900 deep)": repeated(lambda: raw(rogue, deep)),
        "wrong types and ranges": repeated(lambda: raw(rogue, wrong)),
        "login challenges (one source)": repeated(lambda: raw(rogue, login)),
        "forged session tokens": repeated(lambda: raw(rogue, forged)),
        "watch set of 3,000 paths": repeated(lambda: raw(rogue, grow.encode())),
        "forged status publications": repeated(lambda: rogue.put(status_key(RESOURCE), b"{}")),
    }


def _watcher_tokens(rogue: zenoh.Session) -> Flood:
    """Liveliness tokens of watch sets nobody registered (no login needed), held, then
    withdrawn."""

    def flood(deadline: float) -> int:
        liveliness = rogue.liveliness()
        tokens = [
            liveliness.declare_token(watcher_key(RESOURCE, f"rogue{n}"))
            for n in range(WATCHER_TOKENS)
        ]
        time.sleep(max(0.0, deadline - time.monotonic() - 0.5))
        for token in tokens:
            token.undeclare()
        return len(tokens)

    return flood


def _large_payloads(rogue: zenoh.Session) -> Flood:
    """Requests of 1 to 50 MB, refused for their size, and one as large an attachment."""

    def flood(deadline: float) -> int:
        sent = 0
        while sent == 0 or time.monotonic() < deadline:
            for megabytes in PAYLOAD_MB:
                raw(rogue, b" " * (megabytes << 20))
                sent += 1
            raw(rogue, b'{"cmd": "status"}', attachment=b"m" * (PAYLOAD_MB[-1] << 20))
            sent += 1
        return sent

    return flood


@contextmanager
def _readers(endpoint: str) -> Iterator[int]:
    """8 reader logins, each with as many watch sets of as many values as its quota allows
    (their liveliness tokens held; nobody subscribes to the values); yields the sets."""
    paths = ["Main.counter"] * (
        MAX_VALUES_PER_SECOND * READER_PERIOD_MS // 1000 // MAX_SETS_PER_SESSION
    )
    registered = 0
    with ExitStack() as stack:
        for reader in range(READERS):
            session = stack.enter_context(client_session(endpoint))
            client = ResourceClient(session, RESOURCE)
            client.login("reader", PASSWORD)
            for number in range(MAX_SETS_PER_SESSION):
                watch_id = f"reader{reader}set{number}"
                session.liveliness().declare_token(watcher_key(RESOURCE, watch_id))
                reply = client.command(
                    "watch", id=watch_id, variables=paths, period_ms=READER_PERIOD_MS
                )
                registered += bool(reply.get("ok"))
        yield registered


def _modbus_flood(port: int) -> Flood:
    """Read requests of one holding register on several connections, each sent as soon
    as the last was answered (pymodbus answers only the first of requests sent together)."""
    frame = struct.pack(">HHHBBHH", 1, 0, 6, 1, 3, 1024, 1)  # MBAP, read holding 1024 x1

    def connection(deadline: float, counts: list[int]) -> None:
        sent = 0
        with socket.create_connection(("127.0.0.1", port), timeout=10) as sock:
            while time.monotonic() < deadline:
                sock.sendall(frame)
                if not sock.recv(256):
                    break
                sent += 1
        counts.append(sent)

    def flood(deadline: float) -> int:
        counts: list[int] = []
        threads = [
            threading.Thread(target=connection, args=(deadline, counts))
            for _ in range(MODBUS_CONNECTIONS)
        ]
        for thread in threads:
            thread.start()
        for thread in threads:
            thread.join()
        return sum(counts)

    return flood


def _window(admin: ResourceClient, pid: int, name: str, flood: Flood) -> Window:
    assert admin.command("reset_stats")["ok"]
    first = int(admin.command("status")["status"]["cycle"])
    begun = time.monotonic()
    sent = flood(begun + SECONDS)
    elapsed = time.monotonic() - begun
    status = admin.command("status")["status"]
    stats = status["stats"]
    return Window(
        name,
        sent,
        TARGET_MS + float(stats["jitter_max_ms"]),
        int(stats["overruns"]),
        (int(status["cycle"]) - first) / elapsed,
        rss_kib(pid) / 1024,
    )


def _quiet(deadline: float) -> int:
    time.sleep(max(0.0, deadline - time.monotonic()))
    return 0


def _print(window: Window, quiet: Window) -> None:
    print(
        f"  {window.name:34} {window.messages:9,} {window.longest_ms:8.1f} "
        f"{window.longest_ms / quiet.longest_ms:6.2f} {window.overruns:8} "
        f"{window.cycles_per_s:8.1f} {window.rss_mib:7.1f}"
    )


def main() -> None:
    print(
        f"hostile clients: a runtime at a {TARGET_MS} ms target cycle, {SECONDS:g} s per "
        f"window; longest period (goal: at most {2 * TARGET_MS} ms) against the quiet one"
    )
    print(
        f"  {'flood':34} {'messages':>9} {'longest':>8} {'x quiet':>6} {'overruns':>8} "
        f"{'cycles/s':>8} {'RSS MiB':>7}"
    )
    port = free_port()
    pinned = os.environ.get(KNOWN_RESOURCES)
    with tempfile.TemporaryDirectory() as folder:
        try:
            _floods(Path(folder) / "metered", port)
            _unmetered_modbus(Path(folder) / "unmetered")
        finally:
            if pinned is None:
                del os.environ[KNOWN_RESOURCES]
            else:
                os.environ[KNOWN_RESOURCES] = pinned


def _fresh(folder: Path) -> None:
    """A state folder for a new runtime, whose new signing key is pinned there, apart from
    the user's own resources and from the other runtime of the run."""
    folder.mkdir()
    os.environ[KNOWN_RESOURCES] = str(folder / "known_resources")


def _floods(folder: Path, port: int) -> None:
    _fresh(folder)
    with (
        target(folder, ENDPOINT, modbus_port=port) as client,
        client_session(ENDPOINT) as rogue,
    ):
        pid = RUNTIMES[id(client)]
        admin = ResourceClient(client.session, RESOURCE)
        admin.login("admin", PASSWORD)
        _window(admin, pid, "settling", _quiet)  # the native tier builds the program's C first
        quiet = _window(admin, pid, "quiet", _quiet)
        _print(quiet, quiet)
        floods: dict[str, Flood] = {
            f"{WATCHER_TOKENS:,} watcher tokens": _watcher_tokens(rogue),
            "requests of 1-50 MB": _large_payloads(rogue),
            "Modbus read flood": _modbus_flood(port),
            **_message_floods(rogue),
        }
        for name, flood in floods.items():
            _print(_window(admin, pid, name, flood), quiet)
        with _readers(ENDPOINT) as sets:
            _print(_window(admin, pid, f"{READERS} readers, {sets} watch sets", _quiet), quiet)
        _print(_window(admin, pid, "quiet again", _quiet), quiet)


def _unmetered_modbus(folder: Path) -> None:
    """The Modbus flood once more, on a runtime whose served image answers as fast as
    pymodbus can (`--modbus-rate` far above the flood): what the meter spares the cycle,
    measured in the same run."""
    _fresh(folder)
    port, endpoint = free_port(), f"tcp/127.0.0.1:{free_port()}"
    with target(folder, endpoint, port, "--modbus-rate", "1000000") as client:
        pid = RUNTIMES[id(client)]
        admin = ResourceClient(client.session, RESOURCE)
        admin.login("admin", PASSWORD)
        _window(admin, pid, "settling", _quiet)
        quiet = _window(admin, pid, "quiet (Modbus unmetered)", _quiet)
        _print(quiet, quiet)
        _print(_window(admin, pid, "Modbus read flood, unmetered", _modbus_flood(port)), quiet)


if __name__ == "__main__":
    main()
