"""The fixture most browser tests use: `padt demo` in its own process, with the URL and the
administrator password it printed."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.conftest import REPO, free_port
from tests.ui.browser_steps import Demo

URL_LINE = re.compile(r"padt demo: open (http://\S+)")
PASSWORD_LINE = re.compile(r"administrator 'admin', password (\S+)")


@pytest.fixture
def demo(tmp_path: Path) -> Iterator[Demo]:
    command = [sys.executable, "-m", "padt.cli", "demo", "--state-dir", str(tmp_path)]
    command += ["--port", str(free_port()), "--zenoh-port", str(free_port()), "--api-port", "0"]
    process = subprocess.Popen(
        command, cwd=REPO, stdout=subprocess.PIPE, text=True, env=dict(os.environ)
    )
    assert process.stdout is not None
    url = password = None
    started = time.monotonic()
    for line in process.stdout:
        password = password or _group(PASSWORD_LINE, line)
        url = _group(URL_LINE, line)
        if url:
            break
    assert url is not None, "padt demo printed no URL"
    assert password is not None, "padt demo printed no administrator password"
    assert time.monotonic() - started < 60
    try:
        yield Demo(url, password)
    finally:
        process.send_signal(signal.SIGINT)  # Ctrl-C
        assert process.wait(timeout=15) == 0


def _group(pattern: re.Pattern[str], line: str) -> str | None:
    match = pattern.search(line)
    return match.group(1) if match else None
