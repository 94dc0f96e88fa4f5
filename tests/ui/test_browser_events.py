"""The Events screen as a user sees it, through the demo: the event log read at once, a new
event shown live with the user who caused it, filters by kind and user, and the state of
the long-term log's hash chain."""

from __future__ import annotations

import time
from datetime import datetime, timedelta
from pathlib import Path

import pytest
from playwright.sync_api import Page

from runtime.contract.state_folder import events_path
from runtime.event_log import EventLog
from tests.support.browser import chromium
from tests.ui.browser_steps import (
    Demo,
    choose,
    confirm,
    field,
    open_demo_as_admin,
    open_tab,
    shoot,
    text_of,
    wait_until,
)

pytestmark = pytest.mark.browser


def rows(page: Page) -> list[tuple[str, str]]:
    """(kind, user) of each row shown, newest first (read at once: the table is replaced
    whenever an event comes)."""
    found = page.evaluate(
        """() => [...document.querySelectorAll('[data-testid="events"] tr[data-kind]')]
            .map(row => [row.dataset.kind, row.querySelector('[data-user]').innerText])"""
    )
    return [(kind, user) for kind, user in found]


def test_events_arrive_live_are_filtered_and_the_chain_is_verified(demo: Demo) -> None:
    with chromium() as browser:
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        open_demo_as_admin(page, demo)
        open_tab(page, "Events")
        wait_until("admin's login is listed", lambda: ("login", "admin") in rows(page))
        # the runtime's word on its native code (what runs as C; or why nothing does)
        wait_until("the native code is listed", lambda: "native" in dict(rows(page)))
        assert "stop" not in [kind for kind, _ in rows(page)]

        # an action in another tab: its event appears here without asking, with the user
        open_tab(page, "Resources")
        page.get_by_role("button", name="Stop", exact=True).click()
        confirm(page, "Tank1")
        open_tab(page, "Events")
        wait_until("the stop is listed", lambda: ("stop", "admin") in rows(page))
        assert rows(page)[0][0] in ("stop", "state")  # newest first
        shoot(page, "events-1400x900")

        choose(page, "By kind", "stop")
        wait_until("only stops", lambda: {kind for kind, _ in rows(page)} == {"stop"})
        assert text_of(page, '[data-testid="events-count"]').startswith("1 of ")
        choose(page, "By kind", "(all kinds)")
        choose(page, "By user", "(no user)")
        wait_until("admin's events hidden", lambda: "admin" not in {u for _, u in rows(page)})
        assert rows(page), "events without a user remain"
        choose(page, "By user", "admin")
        wait_until("only admin's", lambda: {u for _, u in rows(page)} == {"admin"})

        # a range in local time: from the day after tomorrow on shows nothing, yesterday to
        # today everything (a run across midnight has its events on two days, and one
        # may come after it); a typing error is said and filters nothing
        now = datetime.now()
        yesterday, today, later = (
            (now + timedelta(days=days)).strftime("%Y-%m-%d") for days in (-1, 0, 2)
        )
        field(page, "From").fill(later)
        wait_until("nothing from the day after tomorrow on", lambda: rows(page) == [])
        field(page, "From").fill(yesterday)
        field(page, "To").fill(today)
        wait_until("today's again", lambda: {u for _, u in rows(page)} == {"admin"})
        field(page, "To").fill("soon")
        wait_until(
            "the field's error is said",
            lambda: (
                "To: 'soon' is no date and time" in text_of(page, '[data-testid="range-errors"]')
            ),
        )
        assert rows(page)
        field(page, "From").fill("")
        field(page, "To").fill("")

        choose(page, "Log", "Long-term (user actions, configuration)")
        wait_until(
            "the chain is verified",
            lambda: text_of(page, '[data-testid="event-chain"]').startswith("✓ verified"),
        )
        wait_until("the stop is in the long-term log", lambda: ("stop", "admin") in rows(page))
        page.set_viewport_size({"width": 1920, "height": 1080})
        choose(page, "By user", "(all users)")
        wait_until("every user again", lambda: len({u for _, u in rows(page)}) > 1)
        shoot(page, "events-1920x1080")


@pytest.fixture
def tampered(tmp_path: Path) -> None:
    """A long-term log in the demo's state folder in which an old entry was altered."""
    path = events_path(tmp_path)
    log = EventLog(time.time_ns, long_path=path)
    for user in ("anna", "ben", "carl"):
        log.record("login", f"{user} logged in", user=user, long_term=True)
    lines = path.read_bytes().splitlines()
    lines[1] = lines[1].replace(b"ben logged in", b"bob logged in")  # still a valid entry
    path.write_bytes(b"".join(line + b"\n" for line in lines))


def test_an_altered_long_term_log_shows_where_its_chain_breaks(tampered: None, demo: Demo) -> None:
    with chromium() as browser:
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        open_demo_as_admin(page, demo)
        open_tab(page, "Events")
        choose(page, "Log", "Long-term (user actions, configuration)")
        wait_until(
            "the break is shown",
            lambda: text_of(page, '[data-testid="event-chain"]').startswith(
                "✗ broken at seq 3: prev is not the SHA-256"
            ),
        )
        marked = page.locator('tr[data-seq="3"]').get_attribute("title")
        assert marked == "the hash chain breaks here"
        shoot(page, "events-chain-broken")
