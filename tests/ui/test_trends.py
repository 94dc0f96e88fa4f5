"""The Trends screen as a user sees it, through the demo: variables chosen by search are
charted live (the chart's data grows as the demo runs, the level moves, the pump is a
0/1 step), the cursor's legend shows the values under it, and a pause holds the chart."""

from __future__ import annotations

import re
from typing import Any

import pytest
from playwright.sync_api import Page

from tests.support.browser import chromium
from tests.ui.browser_steps import (
    Demo,
    choose,
    field,
    open_demo_as_admin,
    open_tab,
    shoot,
    shoot_both,
    text_of,
    wait_until,
)

pytestmark = pytest.mark.browser


def chart(page: Page) -> dict[str, Any]:
    """What the page's uPlot chart holds: its series' labels and how many points."""
    found: dict[str, Any] = page.evaluate(
        """() => {
            const charts = Object.values(window.__viserTestpoints?.uplots ?? {});
            if (charts.length === 0) return {series: [], points: 0, charts: 0};
            const u = charts[0].chart;
            return {series: u.series.map(s => s.label), points: u.data[0].length,
                    charts: charts.length, last: u.data.map(d => d[d.length - 1])};
        }"""
    )
    return found


def chart_variable(page: Page, path: str) -> None:
    field(page, "Find variable").fill(path)
    choose(page, "Found", path)
    page.get_by_role("button", name="Add to chart").click()


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
        area = page.locator(".u-over").first.bounding_box()
        assert area is not None
        page.mouse.move(area["x"] + area["width"] - 3, area["y"] + area["height"] / 2)
        legend = text_of(page, ".u-legend")
        assert re.search(r"TankControl\.level:?\s*\d+", legend), legend  # at the newest sample
        assert re.search(r"time:?\s*\d\d:\d\d:\d\d\.\d{3}", legend), legend
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
