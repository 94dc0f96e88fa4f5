"""Writing and forcing in the browser, as a commissioning engineer does it on the demo:
write a value once from the Online test, have a bad literal refused at the field, force the
pump off, start local forcing with a time limit, see the banner and the forced value, clear
all. And a read-only user who sees Write and Force greyed out, and the resource refusing
the same commands sent by hand."""

from __future__ import annotations

import re
import time

import pytest
from playwright.sync_api import Page

from runtime.contract import protocol as p
from runtime.contract.refusal import Refusal
from tests.support.browser import chromium
from tests.ui.browser_steps import (
    PASSWORD,
    Demo,
    Plant,
    banner,
    button_enabled,
    choose,
    confirm,
    edit_value,
    field,
    open_demo_as_admin,
    open_online_test,
    shoot_both,
    text_of,
    value,
    wait_for_text,
    wait_until,
)

pytestmark = pytest.mark.browser


def quality(page: Page, variable: str) -> str:
    return page.locator(f'[data-var="{variable}"]').first.get_attribute("data-quality") or ""


def test_write_a_value_and_a_bad_literal_is_refused_at_the_field(demo: Demo) -> None:
    with chromium() as browser:
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        open_demo_as_admin(page, demo)
        page.get_by_role("tab", name="Online test").click()
        assert value(page, "TankControl.lowLevel") == "300"

        edit_value(page, "tankcontrol.lowlevel", "three")  # names are case-insensitive
        wait_until(
            "the type and value are shown",
            lambda: (
                "TankControl.lowLevel INT · now 300" in text_of(page, '[data-testid="edit-info"]')
            ),
        )
        wait_for_text(page, '[data-testid="value-error"]', "three is not an ST literal of type INT")
        assert not button_enabled(page, "Write")
        assert not button_enabled(page, "Force")
        shoot_both(page, "value-error")
        time.sleep(0.5)
        assert page.get_by_role("dialog").count() == 0
        assert value(page, "TankControl.lowLevel") == "300"  # nothing was sent

        field(page, "New value").fill("350")
        wait_until(
            "the error goes", lambda: page.locator('[data-testid="value-error"]').count() == 0
        )
        wait_until("Write is enabled", lambda: button_enabled(page, "Write"))
        page.get_by_role("button", name="Write", exact=True).click()
        page.get_by_role("dialog").wait_for()
        shoot_both(page, "write-dialog")
        confirm(page, "Write TankControl.lowLevel (INT) once: 300 → 350")
        wait_until(
            "the Online test shows 350", lambda: value(page, "TankControl.lowLevel") == "350"
        )

        # a click on a row of the table chooses its variable, a second click again
        page.locator('tr:has(td[data-var="TankControl.pump"])').click()
        wait_until(
            "the pump is chosen",
            lambda: field(page, "Variable").input_value() == "TankControl.pump",
        )
        field(page, "Variable").fill("")
        # the server has the empty field first: a click before it would be undone by it
        wait_until("the field is empty", lambda: page.get_by_text("Type a variable").count() > 0)
        page.locator('tr:has(td[data-var="TankControl.pump"]) td.p').click()
        wait_until(
            "chosen again", lambda: field(page, "Variable").input_value() == "TankControl.pump"
        )
        wait_until(
            "its type and value are shown",
            lambda: "TankControl.pump BOOL" in text_of(page, '[data-testid="edit-info"]'),
        )


def test_force_the_pump_off_with_a_time_limit_and_clear_all(demo: Demo) -> None:
    with chromium() as browser:
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        open_demo_as_admin(page, demo)
        assert banner(page) == ""

        # prepare the force value: local forcing of TankControl is not started yet
        page.get_by_role("tab", name="Online test").click()
        edit_value(page, "TankControl.pump", "FALSE")
        wait_until("Force is enabled", lambda: button_enabled(page, "Force"))
        page.get_by_role("button", name="Force", exact=True).click()
        confirm(page, "Local forcing of TankControl is not started")
        wait_until(
            "the user is told to start forcing",
            lambda: page.get_by_text("Start it on the Forcing tab").count() > 0,
        )

        page.get_by_role("tab", name="Forcing").click()
        wait_for_text(page, '[data-force-state="TankControl.pump"]', "waiting for start")
        assert text_of(page, '[data-force-value="TankControl.pump"]') == "FALSE"
        assert banner(page) == ""

        choose(page, "Forcing level", "TankControl (local)")
        field(page, "Time limit").fill("T#5m")
        wait_until("Start forcing is enabled", lambda: button_enabled(page, "Start forcing"))
        page.get_by_role("button", name="Start forcing", exact=True).click()
        confirm(page, "Start local forcing of TankControl for 5 min 0 s")

        wait_until("the banner shows", lambda: "local TankControl" in banner(page))
        shown = banner(page)
        assert shown.startswith("FORCING ACTIVE — 1 value forced"), shown
        assert re.search(r"local TankControl, (5 min 0|4 min \d+) s left", shown), shown
        wait_for_text(page, '[data-force-state="TankControl.pump"]', "in force")
        left = text_of(page, '[data-remaining="TankControl"]')
        assert re.fullmatch(r"(5 min 0|4 min \d+) s left", left), left
        wait_until(  # it counts down
            "the remaining time falls",
            lambda: text_of(page, '[data-remaining="TankControl"]') not in (left, "5 min 0 s left"),
        )
        shoot_both(page, "forcing")

        # the Online test shows the value as forced; the banner is seen from every tab
        page.get_by_role("tab", name="Online test").click()
        wait_until("pump is forced", lambda: quality(page, "TankControl.pump") == "forced")
        assert value(page, "TankControl.pump") == "FALSE"
        assert "FORCING ACTIVE" in banner(page)
        # the plant's pump stops (its feedback over Modbus) and the tank drains
        wait_until("the plant's pump stops", lambda: value(page, "pumpRunning") == "FALSE")
        # 30 litres a second: on a loaded machine the tank may be empty by now
        level = int(value(page, "TankControl.level"))
        wait_until(
            "the tank drains",
            lambda: int(value(page, "TankControl.level")) in range(max(level - 6, 1)),
        )

        page.get_by_role("tab", name="Forcing").click()
        page.get_by_role("button", name="Clear all", exact=True).click()
        confirm(page, "Remove the force value of TankControl.pump and stop local forcing")
        wait_until("the banner goes", lambda: banner(page) == "")
        wait_for_text(
            page,
            '[data-testid="no-force-values"]',
            "No force value is prepared. Force a value from the Online test tab.",
        )
        assert text_of(page, '[data-testid="forcing-TankControl"]') == "stopped"
        page.get_by_role("tab", name="Online test").click()
        wait_until("pump is live", lambda: quality(page, "TankControl.pump") == "live")


def test_a_read_user_sees_write_and_force_disabled_and_the_resource_refuses_them(
    plant: Plant,
) -> None:
    with chromium() as browser:
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        open_online_test(page, plant)
        edit_value(page, "TankControl.pump", "FALSE")
        wait_until(
            "the reason is shown",
            lambda: page.locator('[data-testid="edit-disabled"]').count() > 0,
        )
        reason = text_of(page, '[data-testid="edit-disabled"]')
        assert "needs read-write at the resource; viewer is read" in reason, reason
        assert "needs operator at the resource; viewer is read" in reason, reason
        assert not button_enabled(page, "Write")
        assert not button_enabled(page, "Force")
        page.get_by_role("tab", name="Forcing").click()
        assert not button_enabled(page, "Start forcing")
        shoot_both(page, "forcing-read-user")
        forcing_reason = text_of(page, '[data-testid="forcing-disabled"]')
        assert "needs operator at the resource; viewer is read" in forcing_reason
    # what the greyed-out buttons would have sent, sent by hand with the same login
    plant.client.login("viewer", PASSWORD)
    for command in (
        p.Write("TankControl.pump", False),
        p.Force("TankControl.pump", False),
        p.StartForcing("TankControl", 60_000),
    ):
        with pytest.raises(Refusal) as refused:
            plant.client.ask(command)
        assert refused.value.code == "forbidden", command
    assert plant.client.ask(p.GetForcing()).forcing.entries == []
