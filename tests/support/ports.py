"""Free loopback ports for tests and benchmarks (no test-only packages needed here: `make
bench` runs without them)."""

from __future__ import annotations

import socket
import time

_HANDED_OUT: set[int] = set()


def free_port() -> int:
    """A loopback port free now, and never one this process handed out before: the port
    is closed again here, so two calls in a row (a demo's UI and Zenoh ports) could
    otherwise get the same one."""
    while True:
        with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as sock:
            sock.bind(("127.0.0.1", 0))
            port: int = sock.getsockname()[1]
        if port not in _HANDED_OUT:
            _HANDED_OUT.add(port)
            return port


def wait_until_listening(port: int, timeout_s: float = 60) -> None:
    """Until something takes TCP connections on 127.0.0.1:`port` (a server a runtime
    starts after it answers on the bus)."""
    deadline = time.monotonic() + timeout_s
    while True:
        try:
            socket.create_connection(("127.0.0.1", port), timeout=1).close()
            return
        except OSError:
            assert time.monotonic() < deadline, f"nothing listens on 127.0.0.1:{port}"
            time.sleep(0.1)
