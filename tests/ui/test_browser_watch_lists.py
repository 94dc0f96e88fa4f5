"""Watch lists in the Online test: a user composes a named list by search and from the
instance tree, sees its live values page by page with their qualities, finds it again in
another browser session; and only what the screens show travels on the bus."""

from __future__ import annotations

import json
import threading

import pytest
import zenoh
from playwright.sync_api import Page

from runtime.contract.keyspace import watches_key_expr
from tests.support.browser import chromium
from tests.ui.browser_steps import (
    Plant,
    choose,
    field,
    open_online_test,
    shoot,
    text_of,
    value,
    wait_for_text,
    wait_until,
)

pytestmark = pytest.mark.browser


class WireWatch:
    """What the resource publishes on its watch keys: a third party on the bus."""

    def __init__(self, session: zenoh.Session, resource: str) -> None:
        self.lock = threading.Lock()
        self.sizes: list[int] = []
        self.subscriber = session.declare_subscriber(watches_key_expr(resource), self._take)

    def _take(self, sample: zenoh.Sample) -> None:
        message = json.loads(sample.payload.to_bytes())
        with self.lock:
            self.sizes.append(len(message["values"]))

    def last_size(self) -> int:
        with self.lock:
            return self.sizes[-1] if self.sizes else -1


def rows(page: Page) -> list[str]:
    """The variables of the table, read in one go (the table is redrawn as values come)."""
    found: list[str] = page.eval_on_selector_all(
        "[data-var]", "cells => cells.map(c => c.dataset.var)"
    )
    return found


def code_variables(page: Page) -> list[str]:
    found: list[str] = page.eval_on_selector_all(
        "[data-code-var]", "cells => cells.map(c => c.dataset.codeVar)"
    )
    return found


def test_compose_a_watch_list_and_find_it_again(plant: Plant) -> None:
    wire = WireWatch(plant.client.session, "Tank1")
    with chromium() as browser:
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        open_online_test(page, plant)
        # every variable of the resource at first, with the legend of the qualities
        wait_until("all variables are listed", lambda: "TankControl.level" in rows(page))
        assert "forced" in text_of(page, '[data-testid="quality-legend"]')
        everything = len(rows(page))
        assert text_of(page, '[data-testid="olt-range"]') == (
            f"rows 1 to {everything} of {everything}"
        )
        wait_until("all of them watched", lambda: wire.last_size() == everything)
        # a list of one's own: made, filled by search and from an instance
        page.get_by_text("Compose watch lists", exact=True).click()
        field(page, "New list").fill("Pump")
        page.get_by_role("button", name="Create list").click()
        wait_for_text(
            page,
            '[data-testid="olt-note"]',
            ("List 'Pump' created: add variables by search or from an instance."),
        )
        assert page.get_by_label("Watch list", exact=True).input_value() == "Pump"
        field(page, "Search").fill("lev")
        wait_until(
            "the best match is offered first",
            lambda: page.get_by_label("Matches", exact=True).input_value() == "TankControl.level",
        )
        page.get_by_role("button", name="Add to list").click()
        wait_until("the row is shown", lambda: rows(page) == ["TankControl.level"])
        first = value(page, "TankControl.level")
        wait_until("its value is live", lambda: value(page, "TankControl.level") != first)
        # only what the screens show travels: this list's row and the variables of the
        # Code tab's page (viser does not say which tab is in front)
        page.get_by_role("tab", name="Code").click()
        wait_until("the code shows values", lambda: len(code_variables(page)) > 0)
        shown = set(code_variables(page)) | {"TankControl.level"}
        page.get_by_role("tab", name="Online test").click()
        wait_until("only what is shown is watched", lambda: wire.last_size() == len(shown))
        assert len(shown) < everything
        choose(page, "Instance", "TankControl.refillDelay")
        page.get_by_role("button", name="Add the instance's variables").click()
        wait_until("the timer's members are added", lambda: len(rows(page)) > 1)
        assert all(row.startswith("TankControl.refillDelay.") for row in rows(page)[1:])
        wait_for_text(page, "[data-var='TankControl.refillDelay.PT']", "T#2s")
        shoot(page, "online-test-watch-list")
        choose(page, "On this page", "TankControl.refillDelay.PT")
        page.get_by_role("button", name="Remove from list").click()
        wait_until("the row is gone", lambda: "TankControl.refillDelay.PT" not in rows(page))
        kept = rows(page)
    # the PADT kept it: another browser, another session, the same list
    with chromium() as browser:
        page = browser.new_page(viewport={"width": 1920, "height": 1080})
        open_online_test(page, plant)
        choose(page, "Watch list", "Pump")
        wait_until("the list is back", lambda: rows(page) == kept)
        shoot(page, "online-test-watch-list-1920")


def test_a_page_at_a_time(plant: Plant) -> None:
    with chromium() as browser:
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        open_online_test(page, plant)
        wait_until("all variables are listed", lambda: "TankControl.level" in rows(page))
        everything = rows(page)
        field_first = page.get_by_label("First row", exact=True)
        field_first.fill("3")
        field_first.press("Enter")
        wait_until("the page starts at row 3", lambda: rows(page) == everything[2:])
        page.get_by_role("button", name="Previous page").click()
        wait_until("back at the first row", lambda: rows(page) == everything)
        assert text_of(page, '[data-testid="olt-range"]').startswith("rows 1 to ")
