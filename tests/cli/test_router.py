"""`padt router`: two router processes meshed on loopback carry a runtime on one to the
command line on the other; SIGTERM ends a router cleanly; a bad configuration or endpoint
is one line and exit code 2."""

from __future__ import annotations

import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from tests.conftest import REPO, free_port, padt
from tests.support.runtime_process import runtime_process, write_demo_artifact


@contextmanager
def router_process(*options: str) -> Iterator[subprocess.Popen[str]]:
    """A `padt router` process, once it has said that it listens."""
    process = subprocess.Popen(
        [sys.executable, "-m", "padt.cli", "router", *options],
        cwd=REPO,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert process.stdout is not None and process.stderr is not None
        line = process.stdout.readline()  # its one line, or "" when it ended instead
        assert line.startswith("padt router: listening on "), line + process.stderr.read()
        yield process
    finally:
        if process.poll() is None:
            process.kill()
        process.wait()


def stopped_cleanly(process: subprocess.Popen[str]) -> None:
    process.send_signal(signal.SIGTERM)
    _, errors = process.communicate(timeout=30)
    assert process.returncode == 0, errors
    assert "Traceback" not in errors


def test_a_runtime_on_one_router_is_seen_through_the_other(tmp_path: Path) -> None:
    a, b = f"tcp/127.0.0.1:{free_port()}", f"tcp/127.0.0.1:{free_port()}"
    write_demo_artifact(tmp_path / "state")
    with (
        router_process("--listen", a) as router_a,
        router_process("--listen", b, "--connect", a) as router_b,
    ):
        with runtime_process("Tank1", tmp_path / "state", a):
            # the runtime needs a while to start and to be routed from A to B: ask again
            # until it answers, with a deadline no machine should reach
            deadline = time.monotonic() + 90
            while True:
                shown = padt("status", "--resource", "Tank1", "--zenoh", b)
                if shown.returncode == 0 or time.monotonic() > deadline:
                    break
                time.sleep(0.5)
            assert shown.returncode == 0, shown.stderr
            assert "resource Tank1: RUN" in shown.stdout
        stopped_cleanly(router_b)
        stopped_cleanly(router_a)


def test_the_listening_line_names_every_endpoint() -> None:
    first, second = f"tcp/127.0.0.1:{free_port()}", f"tcp/127.0.0.1:{free_port()}"
    peer = f"tcp/127.0.0.1:{free_port()}"  # nobody there: a router retries in the background
    process = subprocess.Popen(
        [sys.executable, "-m", "padt.cli", "router", "--listen", first, "--listen", second,
         "--connect", peer],
        cwd=REPO, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    try:
        assert process.stdout is not None
        line = process.stdout.readline()
        assert line == f"padt router: listening on {first}, {second}, connecting to {peer}\n"
        stopped_cleanly(process)
    finally:
        if process.poll() is None:
            process.kill()
            process.wait()


def refused(*options: str) -> str:
    shown = padt("router", *options, timeout=60)
    assert shown.returncode == 2, shown.stdout + shown.stderr
    assert shown.stdout == ""
    assert len(shown.stderr.splitlines()) == 1, shown.stderr
    assert shown.stderr.startswith("padt router: ")
    return shown.stderr


def test_a_bad_configuration_or_endpoint_is_one_line_and_code_2(tmp_path: Path) -> None:
    broken = tmp_path / "broken.json5"
    broken.write_text("{ transport: ")
    assert "cannot read the Zenoh configuration" in refused("--zenoh-config", str(broken))
    assert str(tmp_path / "absent.json5") in refused(
        "--zenoh-config", str(tmp_path / "absent.json5")
    )
    assert "cannot open the router" in refused("--listen", "carrier-pigeon/127.0.0.1:1")
