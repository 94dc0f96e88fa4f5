"""The Code screen as a user sees it, through `padt demo`: the source of TankControl with
its line numbers and the live values of the variables of the lines in view; the standard
TON of its timer; paging; the values standing still once the resource is stopped."""

from __future__ import annotations

import time
from pathlib import Path

import pytest
from playwright.sync_api import Page

from tests.support.browser import chromium
from tests.ui.browser_steps import (
    Demo,
    choose,
    confirm,
    open_demo_as_admin,
    set_number,
    shoot,
    text_of,
    wait_for_text,
    wait_until,
)

pytestmark = pytest.mark.browser


# what scrolls the work panel: the first ancestor of the code that scrolls sideways
SCROLLER = """(() => {
  let e = document.querySelector('tr[data-line]');
  while (!['auto', 'scroll'].includes(getComputedStyle(e).overflowX)) e = e.parentElement;
  return e;
})()"""


def rect(page: Page, selector: str) -> dict[str, float]:
    """Where an element is now (read at once: the live values redraw the table)."""
    found: dict[str, float] = page.evaluate(
        f"(() => {{ const r = document.querySelector('{selector}').getBoundingClientRect();"
        " return {x: r.x, height: r.height}; })()"
    )
    return found


def code_value(page: Page, path: str) -> str:
    return text_of(page, f'[data-code-var="{path}"]')


def shown_lines(page: Page) -> list[int]:
    """The numbers of the lines shown (read at once: the live values redraw the table)."""
    numbers: list[str] = page.evaluate(
        "[...document.querySelectorAll('tr[data-line]')].map(r => r.dataset.line)"
    )
    return [int(n) for n in numbers]


def test_the_source_of_tankcontrol_with_live_values(demo: Demo) -> None:
    with chromium() as browser:
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        open_demo_as_admin(page, demo)
        page.get_by_role("tab", name="Code").click()
        choose(page, "Instance", "TankControl")
        wait_until(
            "the source of TankControl is shown",
            lambda: "TankControl" in text_of(page, '[data-testid="code-header"]'),
        )
        header = text_of(page, '[data-testid="code-header"]')
        assert "tank.st of project demo" in header, header
        # the lines with their numbers in the file, the source as written
        assert shown_lines(page) == list(range(6, 33))  # PROGRAM to END_PROGRAM
        wait_for_text(page, '[data-code-line="6"]', "PROGRAM TankControl")
        wait_for_text(page, '[data-code-line="20"]', "  level := tankLevel;")
        # the variables of a line with their live values: the level moves while it runs,
        # measured by the plant (the global tankLevel, read over Modbus)
        wait_until("the level is shown", lambda: code_value(page, "TankControl.level").isdigit())
        first = code_value(page, "TankControl.level")
        wait_until("the level changes", lambda: code_value(page, "TankControl.level") != first)
        assert code_value(page, "TankControl.pump") in ("TRUE", "FALSE")
        assert code_value(page, "TankControl.alarmPlant") == "FALSE"  # the plant answers
        assert code_value(page, "tankLevel").isdigit()
        assert code_value(page, "TankControl.restartDelay") == "T#2s"
        line_25 = page.locator('tr[data-line="25"]').inner_text()
        assert "refillDelay.IN =" in line_25 and "restartDelay = T#2s" in line_25, line_25
        shoot(page, "code-1400")
        # line 25 with its seven values is wider than the work area: it does not wrap, the
        # panel scrolls sideways and stays there while the values change, the line
        # numbers in view
        assert rect(page, 'tr[data-line="25"]')["height"] < 30  # one line of text
        page.evaluate(f"{SCROLLER}.scrollLeft = 400")
        time.sleep(1.0)  # ten new values
        assert page.evaluate(f"{SCROLLER}.scrollLeft") == 400
        panel = page.evaluate(f"{SCROLLER}.getBoundingClientRect().left")
        assert rect(page, 'tr[data-line="25"] td')["x"] >= panel - 1
        shoot(page, "code-1400-scrolled")
        page.evaluate(f"{SCROLLER}.scrollLeft = 0")

        # page on: from line 20, then back to the POU's first line
        set_number(page, "Lines from", 20)
        wait_until("the page starts at line 20", lambda: shown_lines(page)[:1] == [20])
        assert shown_lines(page)[-1] == 32
        page.get_by_role("button", name="Previous page").click()
        wait_until("the page starts at line 6", lambda: shown_lines(page)[:1] == [6])

        # the timer: the standard TON, its own variables as members of the instance
        choose(page, "Instance", "TankControl.refillDelay")
        wait_until(
            "the source of TON is shown",
            lambda: "TON" in text_of(page, '[data-testid="code-header"]'),
        )
        assert "standard library" in text_of(page, '[data-testid="code-header"]')
        wait_for_text(page, '[data-code-line="9"]', "FUNCTION_BLOCK TON")
        assert code_value(page, "TankControl.refillDelay.PT") == "T#2s"
        shoot(page, "code-ton-1400")
        page.set_viewport_size({"width": 1920, "height": 1080})
        shoot(page, "code-ton-1920")

        choose(page, "Instance", "TankControl")
        wait_for_text(page, '[data-code-line="6"]', "PROGRAM TankControl")
        shoot(page, "code-1920")

        # after Stop the values stand still
        page.get_by_role("tab", name="Resources").click()
        page.get_by_role("button", name="Stop", exact=True).click()
        confirm(page, "Tank1")
        wait_for_text(page, '[data-testid="resource-state"]', "STOP/VALID CONFIGURATION")
        page.get_by_role("tab", name="Code").click()
        time.sleep(0.5)  # let the last values of RUN arrive
        stopped = code_value(page, "TankControl.level")
        time.sleep(1.0)
        assert code_value(page, "TankControl.level") == stopped


def test_an_edited_project_is_not_shown_as_the_running_source(demo: Demo, tmp_path: Path) -> None:
    # the demo's project folder (the fixture's state folder is this test's tmp_path),
    # edited after the download: it now compiles to another CRC than the one running
    tank = tmp_path / "project" / "tank.st"
    tank.write_text(tank.read_text().replace("level := tankLevel", "level := tankLevel + 1"))
    with chromium() as browser:
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        open_demo_as_admin(page, demo)
        page.get_by_role("tab", name="Code").click()
        crc = text_of(page, '[data-testid="resource-crc"]')
        wanted = f"The source of configuration {crc} is not among the projects this PADT knows"
        wait_until(
            "the screen says the source is unknown",
            lambda: wanted in text_of(page, '[data-testid="code-message"]'),
        )
        assert page.locator("[data-code-line]").count() == 0
        shoot(page, "code-unknown")
