"""Levels in the browser: a user whose levels do not allow a command sees it greyed out
with the reason, and the resource itself refuses the same command sent by hand."""

from __future__ import annotations

import pytest

from runtime.contract import protocol as p
from runtime.contract.refusal import Refusal
from tests.support.browser import chromium
from tests.ui.browser_steps import (
    PASSWORD,
    Plant,
    button_enabled,
    log_in_to_resource,
    open_as,
    text_of,
    wait_for_text,
)

pytestmark = pytest.mark.browser


def test_a_read_user_sees_controls_disabled_and_the_resource_refuses_them(plant: Plant) -> None:
    with chromium() as browser:
        page = browser.new_page()
        open_as(page, plant, "viewer")
        log_in_to_resource(page, "viewer", PASSWORD)
        wait_for_text(page, '[data-testid="resource-state"]', "RUN")
        for control in ("Start", "Stop", "Cold start"):
            assert not button_enabled(page, control), control
        reason = text_of(page, '[data-testid="commands-disabled"]')
        assert "needs operator at the resource; viewer is read" in reason
    # what the greyed-out button would have sent, sent by hand with the same login
    plant.client.login("viewer", PASSWORD)
    with pytest.raises(Refusal) as refused:
        plant.client.ask(p.Stop())
    assert refused.value.code == "forbidden"
    assert plant.client.ask(p.GetStatus()).status.state == "RUN"


def test_a_read_only_padt_account_may_only_look(plant: Plant) -> None:
    with chromium() as browser:
        page = browser.new_page()
        open_as(page, plant, "guest")
        log_in_to_resource(page, "admin", PASSWORD)  # even with an administrator's login
        wait_for_text(page, '[data-testid="resource-state"]', "RUN")
        assert not button_enabled(page, "Stop")
        reason = text_of(page, '[data-testid="commands-disabled"]')
        assert "your PADT account is read-only: it may only look" in reason
