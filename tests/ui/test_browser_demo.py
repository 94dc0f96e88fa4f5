"""The demo as a user sees it: `padt demo` in its own process, driven in headless Chromium.
Log in with the password the demo printed, log in to the resource, stop it, step it, start
it, freeze and step one program, log out."""

from __future__ import annotations

import re
import socket
import time

import pytest
from playwright.sync_api import Page

from tests.support.browser import chromium
from tests.ui.browser_steps import (
    Demo,
    button_enabled,
    confirm,
    cycle,
    log_in,
    log_in_to_resource,
    shoot,
    text_of,
    value,
    wait_for_text,
    wait_until,
)

pytestmark = pytest.mark.browser


def level(page: Page) -> int:
    return int(value(page, "TankControl.level"))


def test_an_anonymous_browser_reaches_no_control(demo: Demo) -> None:
    with chromium() as browser:
        page = browser.new_page()
        page.goto(demo.url)
        page.get_by_role("button", name="Log in", exact=True).wait_for(timeout=30_000)
        log_in(page, "admin", "not-the-password")
        wait_for_text(page, '[data-testid="login-message"]', "unknown user or wrong password")
        for control in ("Start", "Stop", "Step resource", "Log out"):
            assert page.get_by_role("button", name=control, exact=True).count() == 0
        assert page.get_by_role("tab").count() == 0
        assert page.locator("[data-var]").count() == 0


def test_log_in_stop_step_start_freeze_and_log_out(demo: Demo) -> None:
    with chromium() as browser:
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        page.goto(demo.url)
        page.get_by_role("button", name="Log in", exact=True).wait_for(timeout=30_000)
        log_in(page, "admin", demo.password)
        wait_for_text(page, '[data-testid="user"]', "admin")
        assert re.fullmatch(
            r"session ends in (7 h 59|8 h 0) min", text_of(page, '[data-testid="session-left"]')
        )
        # before the resource login, the commands are greyed out and say why
        disabled = text_of(page, '[data-testid="commands-disabled"]')
        assert "log in to the resource first" in disabled
        assert not button_enabled(page, "Stop")
        log_in_to_resource(page, "admin", demo.password)
        wait_for_text(page, '[data-testid="resource-state"]', "RUN", timeout_s=30)
        assert re.fullmatch(r"[0-9A-F]{8}", text_of(page, '[data-testid="resource-crc"]'))
        # the Resources table names the machine each resource runs on (its status says)
        wait_for_text(page, '[data-host="Tank1"]', socket.gethostname())
        shoot(page, "resources")

        page.get_by_role("button", name="Stop", exact=True).click()
        confirm(page, "Tank1")
        wait_for_text(page, '[data-testid="resource-state"]', "STOP/VALID CONFIGURATION")

        page.get_by_role("tab", name="Online test").click()
        time.sleep(0.5)  # let the last values of RUN arrive
        frozen_level, frozen_cycle = level(page), cycle(page)
        # the outputs went to their safe values: the plant's pump stops, the tank drains,
        # and the level the plant measures goes on arriving while the program stands still
        wait_until("the plant's pump stops", lambda: value(page, "pumpRunning") == "FALSE")
        wait_until(
            "the plant's level falls below the program's",
            lambda: int(value(page, "tankLevel")) < frozen_level,
        )
        assert (level(page), cycle(page)) == (frozen_level, frozen_cycle)
        shoot(page, "online-test")

        page.get_by_role("tab", name="Single step").click()
        page.get_by_role("button", name="Step resource").click()
        wait_until("Step resource ran a cycle", lambda: cycle(page) != frozen_cycle)
        assert cycle(page) == frozen_cycle + 1
        page.get_by_role("tab", name="Online test").click()
        # one cycle took in the plant's measurement: the program's level follows the tank
        wait_until("the stepped level is the plant's", lambda: level(page) < frozen_level)
        stepped = level(page)
        time.sleep(0.5)
        assert level(page) == stepped  # and stands still again until the next step

        page.get_by_role("tab", name="Resources").click()
        page.get_by_role("button", name="Start", exact=True).click()
        confirm(page, "Tank1")
        wait_for_text(page, '[data-testid="resource-state"]', "RUN")

        # one program frozen and stepped while the resource runs on
        page.get_by_role("tab", name="Single step").click()
        assert "freeze TankControl first" in text_of(page, '[data-testid="step-disabled"]')
        page.get_by_role("button", name="Freeze", exact=True).click()
        confirm(page, "TankControl")
        wait_for_text(page, '[data-step="Program state"]', "RUN (frozen)")
        program_cycles = int(text_of(page, '[data-step="Program cycles"]'))
        page.get_by_role("button", name="Step", exact=True).click()
        wait_for_text(page, '[data-step="Program cycles"]', str(program_cycles + 1))
        shoot(page, "single-step")
        page.get_by_role("button", name="Unfreeze", exact=True).click()
        wait_for_text(page, '[data-step="Program state"]', "RUN")

        page.get_by_role("button", name="Log out").click()
        page.get_by_role("button", name="Log in", exact=True).wait_for(timeout=20_000)
        assert page.get_by_role("button", name="Stop", exact=True).count() == 0
