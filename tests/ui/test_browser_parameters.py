"""The Parameters screen as a user sees it, through the demo: the parameter table with
ranges and what changes online; an online change confirmed with the old and new value and
the warning, then shown; a bad value refused at the field, with nothing sent; a parameter
not changeable online disabled with the reason."""

from __future__ import annotations

import pytest

from runtime.contract import protocol as p
from runtime.contract.refusal import Refusal
from tests.support.browser import chromium
from tests.ui.browser_steps import (
    PASSWORD,
    Demo,
    Plant,
    button_enabled,
    choose,
    confirm,
    field,
    log_in_to_resource,
    open_as,
    open_demo_as_admin,
    open_tab,
    shoot,
    text_of,
    wait_for_text,
    wait_until,
)

pytestmark = pytest.mark.browser
WATCHDOG = '[data-param="resource.watchdog_ms"]'
ERROR = '[data-testid="parameter-error"]'


def test_change_a_watchdog_online_refuse_a_bad_value_and_explain_the_disabled(
    demo: Demo,
) -> None:
    with chromium() as browser:
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        open_demo_as_admin(page, demo)
        open_tab(page, "Parameters")
        wait_for_text(page, WATCHDOG, "200 ms")
        assert text_of(page, '[data-online="resource.watchdog_ms"]') == "yes"
        assert text_of(page, '[data-online="resource.safety_time_ms"]') == "no (download)"
        assert text_of(page, '[data-param="TankControl.priority"]') == "0"
        wait_until(
            "the field shows the value", lambda: field(page, "New value").input_value() == "200 ms"
        )
        shoot(page, "parameters-1400x900")

        # out of range, and in range but more than half the safety time: refused here
        # the picker names the parameter as the docs do, with its unit and key
        assert page.get_by_label("Parameter", exact=True).first.input_value() == (
            "Watchdog Time, ms (watchdog_ms)"
        )
        # said as typed, before Set; Set sends nothing
        for bad, why in (("5", "must be from 6 to 7500"), ("400", "more than half the safety")):
            field(page, "New value").fill(bad)
            wait_until(f"the error for {bad}", lambda: why in text_of(page, ERROR))  # noqa: B023
            page.get_by_role("button", name="Set parameter").click()
            assert page.get_by_role("dialog").count() == 0
        field(page, "New value").fill("ten")
        wait_until("a type error", lambda: "whole number" in text_of(page, ERROR))
        field(page, "New value").fill("250 ms")  # corrected: the error goes as typed
        wait_until("no error", lambda: page.locator(ERROR).count() == 0)
        field(page, "New value").fill("ten")
        wait_until("a type error", lambda: "whole number" in text_of(page, ERROR))
        shoot(page, "parameters-bad-value")
        assert text_of(page, WATCHDOG) == "200 ms"

        field(page, "New value").fill("250")
        page.get_by_role("button", name="Set parameter").click()
        dialog = page.get_by_role("dialog")
        dialog.wait_for()
        text = dialog.inner_text()
        assert "Watchdog Time (watchdog_ms) of resource Tank1 (configuration " in text
        assert "from 200 ms to 250 ms, at once, while it runs" in text
        assert "cannot tell whether the new value suits the plant" in text
        shoot(page, "parameters-confirm")
        confirm(page, "250 ms")
        wait_for_text(page, WATCHDOG, "250 ms")
        assert page.locator(ERROR).count() == 0 or text_of(page, ERROR) == ""

        # a parameter that changes only with a download: disabled, and why
        choose(page, "Parameter", "Safety Time, ms (safety_time_ms)")
        wait_until("Set is disabled", lambda: not button_enabled(page, "Set parameter"))
        reason = text_of(page, '[data-testid="parameter-disabled"]')
        assert "Safety Time changes only with a download" in reason
        choose(page, "Parameter", "TankControl / Priority (priority)")
        wait_until(
            "the program parameter's reason",
            lambda: "program parameters" in text_of(page, '[data-testid="parameter-disabled"]'),
        )
        page.set_viewport_size({"width": 1920, "height": 1080})
        shoot(page, "parameters-1920x1080")


def test_a_read_user_cannot_edit_and_the_resource_refuses_the_change(plant: Plant) -> None:
    with chromium() as browser:
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        open_as(page, plant, "viewer")
        log_in_to_resource(page, "viewer", PASSWORD)
        open_tab(page, "Parameters")
        wait_for_text(page, WATCHDOG, "200 ms")
        wait_until(
            "the reason is shown",
            lambda: (
                "needs read-write at the resource; viewer is read"
                in text_of(page, '[data-testid="parameter-disabled"]')
            ),
        )
        assert not button_enabled(page, "Set parameter")
        shoot(page, "parameters-read-only")
        # what the greyed-out button would have sent, sent by hand with the same login
        plant.client.login("viewer", PASSWORD)
        with pytest.raises(Refusal) as refused:
            plant.client.ask(p.SetParameter("watchdog_ms", 250))
        assert refused.value.code == "forbidden"
        assert plant.client.ask(p.GetParameters()).resource.watchdog_ms == 200
        # a change made elsewhere (an administrator's tool) shows here too
        plant.client.login("admin", PASSWORD)
        plant.client.ask(p.SetParameter("watchdog_ms", 250))
        wait_for_text(page, WATCHDOG, "250 ms")
