"""The Trends screen as a user sees it, through the demo: variables chosen by search are
charted live (the chart's data grows as the demo runs, the level moves, the pump is a
0/1 step), the cursor's legend shows the values under it, and a pause holds the chart;
the charted variables recorded on the resource, listed, charted from the file, saved as an
.mcap file that an MCAP reader opens and deleted; a recording with a trigger waits for it;
a user without Operator at the resource sees Record greyed out with the reason."""

from __future__ import annotations

import math
import re
from typing import Any

import pytest
from playwright.sync_api import Page

from runtime.contract.recording import read_recording
from tests.support.browser import chromium
from tests.ui.browser_steps import (
    PASSWORD,
    Demo,
    Plant,
    choose,
    confirm,
    field,
    log_in_to_resource,
    open_as,
    open_demo_as_admin,
    open_tab,
    shoot,
    shoot_both,
    text_of,
    wait_until,
)

pytestmark = pytest.mark.browser
NOTE = '[data-testid="record-note"]'
TRIGGER_ERROR = '[data-testid="trigger-error"]'


def charts(page: Page) -> list[dict[str, Any]]:
    """What the page's uPlot charts in view hold (the other tab's are hidden): their
    series' labels, how many points, the first and the last point."""
    found: list[dict[str, Any]] = page.evaluate(
        """() => Object.values(window.__viserTestpoints?.uplots ?? {}).map(c => c.chart)
            .filter(u => u.root.offsetParent !== null)
            .map(u => ({series: u.series.map(s => s.label), points: u.data[0].length,
                        first: u.data.map(d => d[0]), last: u.data.map(d => d[d.length - 1])}))"""
    )
    return found


def scales(page: Page) -> list[str]:
    """The scale of each series of the chart in view: x for the time, b for the BOOLs, y
    for the numbers on one axis, y0, y1, ... for each on its own."""
    found: list[str] = page.evaluate(
        """() => Object.values(window.__viserTestpoints?.uplots ?? {}).map(c => c.chart)
            .filter(u => u.root.offsetParent !== null)
            .map(u => u.series.map(s => s.scale))[0] ?? []"""
    )
    return found


def chart(page: Page) -> dict[str, Any]:
    """The chart in view; none yet (a tab just brought to the front draws it a moment
    later): no series, no points, and a first and last point earlier than any."""
    found = charts(page)
    none = [-math.inf]
    return found[0] if found else {"series": [], "points": 0, "first": none, "last": none}


def close_notifications(page: Page) -> None:
    """Close the toasts in the top left corner (commands done). One may close by itself
    between being found and being clicked (the page closes viser's WebGL note as it comes),
    so they are clicked in the page, never waited for one by one."""
    buttons = page.locator(".mantine-Notification-closeButton")
    for _ in range(20):  # a new toast may come while the others fade
        if not buttons.count():
            return
        page.evaluate(
            "document.querySelectorAll('.mantine-Notification-closeButton').forEach(b => b.click())"
        )
        page.wait_for_timeout(300)  # their fade


def chart_variable(page: Page, path: str) -> None:
    """`path` found, chosen and added; once the chart shows it, as a user sees. A press
    followed at once by another (Record) can be dropped in viser's sender, which keeps
    only the newest message within 50 ms (CI run 64): pressed again, as a user does."""
    field(page, "Find variable").fill(path)
    choose(page, "Found", path)

    def shown() -> bool:  # a label may say more: a time's unit
        return any(label.startswith(path) for label in chart(page)["series"])

    def charted() -> bool:
        if shown():
            return True
        page.get_by_role("button", name="Add to chart").click()
        page.wait_for_timeout(1_500)
        return shown()

    wait_until(f"{path} is charted", charted)


def test_variables_chosen_are_charted_live_with_their_values(demo: Demo) -> None:
    with chromium() as browser:
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        open_demo_as_admin(page, demo)
        open_tab(page, "Trends")
        assert "Choose variables" in text_of(page, '[data-testid="trend-empty"]')

        chart_variable(page, "TankControl.level")
        chart_variable(page, "TankControl.pump")
        wait_until(
            "a chart of both",
            lambda: chart(page)["series"] == ["time", "TankControl.level", "TankControl.pump"],
        )
        # the demo runs: the chart's data grows, the level it shows moves
        first = chart(page)
        wait_until("the chart grows", lambda: chart(page)["points"] > first["points"] + 10)
        level = text_of(page, '[data-trend="TankControl.level"]')
        wait_until(
            "the level moves",
            lambda: text_of(page, '[data-trend="TankControl.level"]') != level,
        )
        assert text_of(page, '[data-trend="TankControl.pump"]') in ("TRUE", "FALSE")
        assert "live" in text_of(page, '[data-testid="trend-status"]')

        # the cursor: the legend shows the values under it

        def legend_shows_the_newest_sample() -> bool:
            # the legend follows the cursor on the next frame, and a live update in between
            # may redraw it: hover again until it has caught up, as a user's hand would
            # (the time and the value read from one text: a redraw may come between two reads;
            # the chart's area is found anew each time: a redraw may replace it)
            area = page.locator(".u-over").first.bounding_box()
            if area is None:
                return False
            page.mouse.move(area["x"] + area["width"] - 3, area["y"] + area["height"] / 2)
            legend = text_of(page, ".u-legend")
            return bool(
                re.search(r"TankControl\.level:?\s*\d+", legend)
                and re.search(r"time:?\s*\d\d:\d\d:\d\d\.\d{3}", legend)
            )

        wait_until(
            "the legend shows the time and values under the cursor", legend_shows_the_newest_sample
        )
        shoot(page, "trends-cursor-1400x900")
        shoot_both(page, "trends-live")

        # a pause holds the chart while the history goes on
        page.get_by_role("button", name="Pause").click()
        wait_until("paused", lambda: "paused" in text_of(page, '[data-testid="trend-status"]'))
        held = chart(page)["last"][0]  # the time of the newest point
        page.wait_for_timeout(1500)
        assert chart(page)["last"][0] == held
        page.get_by_role("button", name="Resume").click()
        wait_until("it goes on", lambda: chart(page)["last"][0] > held)

        # another tab in front: the chart is not drawn, its history goes on
        left = chart(page)["last"][0]
        close_notifications(page)  # they lie over the tabs' left end
        open_tab(page, "Resources")
        page.wait_for_timeout(3000)
        open_tab(page, "Trends")
        wait_until("drawn again", lambda: chart(page)["last"][0] > left + 2.5)
        meanwhile = page.evaluate(
            """([from, to]) => Object.values(window.__viserTestpoints.uplots)
                .map(c => c.chart).filter(u => u.root.offsetParent !== null)[0]
                .data[0].filter(x => x > from && x < to).length""",
            [left, left + 2.5],
        )
        assert meanwhile >= 15, meanwhile  # ten a second while the tab was away

        # a third variable, and each number on an axis of its own
        chart_variable(page, "TankControl.refillDelay.ET")
        page.get_by_role("button", name="Axis per variable").click()
        wait_until("an axis each", lambda: scales(page) == ["x", "y0", "b", "y1"])
        shoot(page, "trends-axes-1400x900")
        page.get_by_role("button", name="One axis").click()
        wait_until("one axis", lambda: scales(page) == ["x", "y", "b", "y"])


def test_the_charted_variables_recorded_listed_charted_and_saved(demo: Demo) -> None:
    with chromium() as browser:
        page = browser.new_page(viewport={"width": 1400, "height": 900}, accept_downloads=True)
        open_demo_as_admin(page, demo)
        open_tab(page, "Trends")
        chart_variable(page, "TankControl.level")
        chart_variable(page, "TankControl.pump")

        page.get_by_role("button", name="Record the charted variables").click()
        wait_until(
            "it records",
            lambda: "recording:" in text_of(page, '[data-testid="record-note"]'),
        )
        stop = page.get_by_role("button", name=re.compile("^Stop recording"))
        page.wait_for_timeout(2000)  # two seconds of the demo
        shoot(page, "trends-recording-1400x900")
        stop.click()
        wait_until("it is done", lambda: " done:" in text_of(page, '[data-testid="record-note"]'))
        note = text_of(page, '[data-testid="record-note"]')
        recording = note.split(" ")[0]
        cycles = int(note.split("done: ")[1].split(" cycles")[0].replace(",", ""))
        assert cycles >= 10, note  # 2 s of 50 ms cycles, and some

        close_notifications(page)  # they lie over the Trends screen's own tabs
        page.get_by_role("tab", name="Recorded").click()
        row = f'[data-recording="{recording}"]'
        wait_until("it is listed", lambda: text_of(page, f"{row} [data-state]") == "done")
        assert text_of(page, f"{row} [data-cycles]") == f"{cycles:,}"
        choose(page, "Recording", recording)
        page.get_by_role("button", name="Chart it").click()
        wait_until("it is charted", lambda: chart(page)["points"] > 1)
        recorded = chart(page)
        assert recorded["series"] == ["time", "TankControl.level", "TankControl.pump"]
        assert recorded["points"] >= cycles  # every cycle, pump changes doubled as steps
        span = recorded["last"][0] - recorded["first"][0]
        assert 1.5 < span < 30, span  # the cycles' log times: the seconds recorded
        assert f"{cycles:,} cycles" in text_of(page, '[data-testid="recorded-note"]')
        shoot_both(page, "trends-recorded")
        field(page, "Variables to chart").fill("level")
        wait_until(
            "the level alone", lambda: chart(page)["series"] == ["time", "TankControl.level"]
        )

        with page.expect_download() as download:
            page.get_by_role("button", name="Download .mcap").click()
        saved = download.value
        assert saved.suggested_filename == f"{recording}-1.mcap"
        path = saved.path()
        assert path.read_bytes()[:8] == b"\x89MCAP0\r\n"
        assert len(read_recording(path).rows) == cycles

        # deleted, asked first: gone from the resource
        close_notifications(page)
        page.get_by_role("button", name=f"Delete recording {recording}").click()
        confirm(page, "cannot be undone")
        wait_until(
            "it is gone",
            lambda: "No recordings" in text_of(page, '[data-testid="recordings"]'),
        )

        # with a trigger: what is no condition is said as it is typed; a recording that
        # waits for its trigger records nothing until it comes
        page.get_by_role("tab", name="Live").click()
        page.get_by_text("Recording options").click()
        field(page, "Trigger").fill("TankControl.level >")
        wait_until("it is refused", lambda: page.locator(TRIGGER_ERROR).count() == 1)
        assert "is not a trigger" in text_of(page, TRIGGER_ERROR)
        field(page, "Trigger").fill("TankControl.level > 5000")
        wait_until("it is taken", lambda: page.locator(TRIGGER_ERROR).count() == 0)
        page.get_by_role("button", name="Record the charted variables").click()
        wait_until("it waits", lambda: "waiting for its trigger" in text_of(page, NOTE))
        shoot(page, "trends-trigger-1400x900")
        close_notifications(page)
        page.get_by_role("button", name=re.compile("^Stop recording")).click()
        wait_until("it is done", lambda: " done: 0 cycles" in text_of(page, NOTE))


def test_a_read_user_charts_but_may_not_record(plant: Plant) -> None:
    with chromium() as browser:
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        open_as(page, plant, "viewer")
        log_in_to_resource(page, "viewer", PASSWORD)  # read at the resource
        open_tab(page, "Trends")
        chart_variable(page, "TankControl.level")
        wait_until("a chart", lambda: chart(page)["series"] == ["time", "TankControl.level"])
        record = page.get_by_role("button", name="Record the charted variables")
        wait_until("the reason is said", lambda: "Disabled" in text_of(page, NOTE))
        assert not record.is_enabled()
        assert "needs operator at the resource; viewer is read" in text_of(page, NOTE)
        close_notifications(page)
        page.get_by_role("tab", name="Recorded").click()  # reading them needs read only
        wait_until(
            "the recordings are listed",
            lambda: "No recordings" in text_of(page, '[data-testid="recordings"]'),
        )
