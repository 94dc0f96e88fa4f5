"""The demo as a user sees it: `padt demo` in its own process, driven in headless Chromium."""

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
from playwright.sync_api import Page

from tests.conftest import REPO, free_port
from tests.support.browser import chromium

pytestmark = pytest.mark.browser
URL_LINE = re.compile(r"padt demo: open (http://\S+)")


@pytest.fixture
def demo_url(tmp_path: Path) -> Iterator[str]:
    command = [sys.executable, "-m", "padt.cli", "demo", "--state-dir", str(tmp_path)]
    command += ["--port", str(free_port()), "--zenoh-port", str(free_port()), "--api-port", "0"]
    process = subprocess.Popen(
        command, cwd=REPO, stdout=subprocess.PIPE, text=True, env=dict(os.environ)
    )
    assert process.stdout is not None
    url = None
    started = time.monotonic()
    for line in process.stdout:
        match = URL_LINE.search(line)
        if match:
            url = match.group(1)
            break
    assert url is not None, "padt demo printed no URL"
    assert time.monotonic() - started < 60
    try:
        yield url
    finally:
        process.send_signal(signal.SIGINT)  # Ctrl-C
        assert process.wait(timeout=15) == 0


def text_of(page: Page, selector: str) -> str:
    return page.locator(selector).inner_text(timeout=20_000)


def wait_for_text(page: Page, selector: str, wanted: str, timeout_s: float = 15) -> None:
    deadline = time.monotonic() + timeout_s
    while text_of(page, selector) != wanted:
        assert time.monotonic() < deadline, f"{selector} never showed {wanted!r}"
        time.sleep(0.1)


def level(page: Page) -> int:
    return int(text_of(page, '[data-var="TankControl.level"]'))


def cycle(page: Page) -> int:
    return int(text_of(page, '[data-testid="resource-cycle"]'))


def test_run_stop_step_start_in_the_browser(demo_url: str) -> None:
    with chromium() as browser:
        page = browser.new_page()
        page.goto(demo_url)
        wait_for_text(page, '[data-testid="resource-state"]', "RUN", timeout_s=30)
        assert re.fullmatch(r"[0-9A-F]{8}", text_of(page, '[data-testid="resource-crc"]'))
        first = level(page)
        deadline = time.monotonic() + 10
        while level(page) == first:
            assert time.monotonic() < deadline, "the level never changed in RUN"
            time.sleep(0.1)

        page.get_by_role("button", name="Stop").click()
        wait_for_text(page, '[data-testid="resource-state"]', "STOP/VALID CONFIGURATION")
        time.sleep(0.5)  # let the last values of RUN arrive
        frozen_level, frozen_cycle = level(page), cycle(page)
        pump = text_of(page, '[data-var="TankControl.pump"]') == "TRUE"
        time.sleep(1.0)
        assert (level(page), cycle(page)) == (frozen_level, frozen_cycle)

        page.get_by_role("button", name="Step").click()
        deadline = time.monotonic() + 10
        while cycle(page) == frozen_cycle:
            assert time.monotonic() < deadline, "Step did not run a cycle"
            time.sleep(0.05)
        assert cycle(page) == frozen_cycle + 1
        assert level(page) == frozen_level + (8 if pump else 0) - 3  # exactly one cycle
        if "PADT_SHOTS" in os.environ:  # for a person to look at
            page.screenshot(path=str(Path(os.environ["PADT_SHOTS"]) / "demo-step.png"))

        page.get_by_role("button", name="Start").click()
        wait_for_text(page, '[data-testid="resource-state"]', "RUN")
        stepped = cycle(page)
        deadline = time.monotonic() + 10
        while cycle(page) < stepped + 3:
            assert time.monotonic() < deadline, "the resource did not run again"
            time.sleep(0.1)
