"""What a new user saw in the demo and was misled by (issue 30, item 16), as that user sees
it now: a frozen program's values grey (stale) as the legend says, its state named as the
docs name it, only the commands its state allows enabled, each step in the event log, the
confirmations naming the configuration's CRC, "1 request", the I/O points' Writable
column filled, and BOOLs in a lane of their own under the numbers in Trends."""

from __future__ import annotations

import re

import pytest
from playwright.sync_api import Page

from tests.runtime.test_modbus_server import wait_for
from tests.support.browser import chromium
from tests.support.modbus_device import modbus_client, reachable
from tests.ui.browser_steps import (
    Demo,
    button_enabled,
    confirm,
    edit_value,
    open_demo_as_admin,
    open_tab,
    shoot_both,
    text_of,
    value,
    wait_for_text,
    wait_until,
)
from tests.ui.test_trends import chart, chart_variable, close_notifications

pytestmark = pytest.mark.browser
STALE_GREY = "rgb(134, 142, 150)"  # #868e96, as the legend shows "stale"


def enabled(page: Page, *names: str) -> list[bool]:
    return [button_enabled(page, name) for name in names]


def quality(page: Page, variable: str) -> tuple[str, str]:
    """The quality a value cell of the Online test says, and its colour."""
    cell = page.locator(f'[data-var="{variable}"]').first
    found: tuple[str, str] = cell.evaluate("c => [c.dataset.quality, getComputedStyle(c).color]")
    return found[0], found[1]


def event_messages(page: Page) -> list[str]:
    found: list[str] = page.evaluate(
        """() => [...document.querySelectorAll('[data-testid="events"] tr[data-kind]')]
            .map(row => row.innerText)"""
    )
    return found


def dialog_text_and_cancel(page: Page) -> str:
    dialog = page.get_by_role("dialog")
    dialog.wait_for(timeout=20_000)
    text = dialog.inner_text()
    dialog.get_by_role("button", name="Cancel").click()
    dialog.wait_for(state="detached", timeout=20_000)
    return text


def test_freeze_step_and_unfreeze_as_a_new_user_sees_them(demo: Demo) -> None:
    with chromium() as browser:
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        open_demo_as_admin(page, demo)
        crc = text_of(page, '[data-testid="resource-crc"]')

        # in RUN, Start, Cold start and Init would do nothing: greyed out, saying why beside
        # them
        wait_until("Start is greyed out in RUN", lambda: not button_enabled(page, "Start"))
        assert enabled(page, "Stop", "Cold start", "Init") == [True, False, False]
        assert enabled(page, "Start program", "Stop program") == [False, True]
        reasons = text_of(page, '[data-testid="commands-disabled"]')
        assert "Start: the resource runs already" in reasons, reasons
        assert "Init: only in ERROR STOP" in reasons, reasons

        open_tab(page, "Single step")
        wait_until("Freeze is enabled", lambda: button_enabled(page, "Freeze"))
        assert enabled(page, "Unfreeze", "Step", "Step N", "Step resource") == [False] * 4
        page.get_by_role("button", name="Freeze", exact=True).click()
        confirm(page, f"configuration {crc}")  # the confirmation names the CRC
        wait_for_text(page, '[data-step="Program state"]', "RUN (frozen)")
        wait_until("Freeze is greyed out", lambda: not button_enabled(page, "Freeze"))
        assert enabled(page, "Unfreeze", "Step", "Step N") == [True, True, True]
        cycles = int(text_of(page, '[data-step="Program cycles"]'))
        page.get_by_role("button", name="Step", exact=True).click()
        wait_for_text(page, '[data-step="Program cycles"]', str(cycles + 1))
        shoot_both(page, "new-user-single-step")
        assert "RUN_FREEZE" not in page.inner_text("body")

        open_tab(page, "Resources")
        wait_until(
            "the program is named frozen",
            lambda: text_of(page, '[data-program="TankControl"]') == "TankControl: RUN (frozen)",
        )
        shoot_both(page, "new-user-resources")

        # the frozen program's values are stale (grey); the plant's level, a global the I/O
        # keeps writing while the resource runs, is live
        open_tab(page, "Online test")
        value(page, "TankControl.level")
        wait_until(
            "the frozen program's level is grey",
            lambda: quality(page, "TankControl.level") == ("stale", STALE_GREY),
        )
        assert quality(page, "tankLevel")[0] == "live"
        # Write and Force name the configuration they change
        edit_value(page, "TankControl.lowLevel", "301")
        wait_until("Write is enabled", lambda: button_enabled(page, "Write"))
        page.get_by_role("button", name="Write", exact=True).click()
        assert f"configuration {crc}" in dialog_text_and_cancel(page)
        page.get_by_role("button", name="Force", exact=True).click()
        assert f"configuration {crc}" in dialog_text_and_cancel(page)
        shoot_both(page, "new-user-online-test")

        # each step is in the event log, as freeze and unfreeze are
        open_tab(page, "Events")
        wait_until(
            "the step is listed",
            lambda: any("TankControl stepped one cycle" in row for row in event_messages(page)),
        )
        assert any("TankControl frozen" in row for row in event_messages(page))
        shoot_both(page, "new-user-events")

        open_tab(page, "Single step")
        page.get_by_role("button", name="Unfreeze", exact=True).click()
        wait_for_text(page, '[data-step="Program state"]', "RUN")
        wait_until("Unfreeze is greyed out", lambda: not button_enabled(page, "Unfreeze"))
        assert enabled(page, "Freeze", "Step") == [True, False]
        reasons = text_of(page, '[data-testid="step-disabled"]')
        assert "Unfreeze: freeze TankControl first" in reasons, reasons


def bool_lane(page: Page) -> tuple[float, float]:
    """In the chart in view: the lowest pixel the numbers reach, their values or the ticks
    of their axis, and the highest a BOOL's TRUE reaches (pixels count down from the
    top). uPlot keeps an axis' ticks in `_splits`."""
    found: tuple[float, float] = page.evaluate(
        """() => {
            const u = Object.values(window.__viserTestpoints.uplots).map(c => c.chart)
                .filter(u => u.root.offsetParent !== null)[0];
            let lowest = -Infinity;
            const reach = (v, scale) => {
                if (v !== null && Number.isFinite(v))
                    lowest = Math.max(lowest, u.valToPos(v, scale));
            };
            u.series.forEach((s, i) => {
                if (i > 0 && s.scale !== 'b') u.data[i].forEach(v => reach(v, s.scale));
            });
            u.axes.forEach(a => {
                if (a.scale !== 'x' && a.scale !== 'b') (a._splits || []).forEach(
                    v => reach(v, a.scale));
            });
            return [lowest, u.valToPos(1, 'b')];
        }"""
    )
    return found[0], found[1]


def test_io_counts_and_writable_and_trends_bools_in_their_own_lane(demo: Demo) -> None:
    wait_for(lambda: reachable(demo.modbus_port), 30)
    with chromium() as browser:
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        open_demo_as_admin(page, demo)
        open_tab(page, "I/O")
        wait_until(
            "the server listens",
            lambda: "listening" in text_of(page, '[data-testid="io-server"]'),
        )
        assert re.search(r"· 0 requests ·", text_of(page, '[data-testid="io-server"]'))
        with modbus_client(demo.modbus_port) as modbus:
            modbus.read_input_registers(0, count=1)
        wait_until(
            "one request, in the singular",
            lambda: "· 1 request ·" in text_of(page, '[data-testid="io-server"]'),
        )
        writable = page.locator('[data-testid="io-points"] [data-writable]').all_inner_texts()
        assert writable and all(text in ("yes", "no", "no (device)") for text in writable)
        assert "no (device)" in writable  # the plant's points
        shoot_both(page, "new-user-io")

        open_tab(page, "Trends")
        chart_variable(page, "TankControl.level")
        chart_variable(page, "TankControl.pump")
        wait_until(
            "a chart of both",
            lambda: chart(page)["series"] == ["time", "TankControl.level", "TankControl.pump"],
        )
        wait_until("the chart has points", lambda: chart(page)["points"] > 20)
        numbers_lowest, bool_true = bool_lane(page)
        assert bool_true > numbers_lowest, (numbers_lowest, bool_true)  # under the numbers
        close_notifications(page)
        shoot_both(page, "new-user-trends")
