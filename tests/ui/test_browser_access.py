"""Levels in the browser: a user whose levels do not allow a command sees it greyed out
with the reason, and the resource itself refuses the same command sent by hand."""

from __future__ import annotations

import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest
from playwright.sync_api import Page

from backend.engineering.padt_accounts import PadtAccounts, write_accounts
from backend.engineering.project import compile_project, load_project
from backend.engineering.resource_client import ResourceClient
from backend.engineering.resource_directory import ResourceDirectory
from frontend.app import PadtUi
from frontend.ui_context import UiContext
from padt.demo import demo_project_with_accounts
from runtime.contract import protocol as p
from runtime.contract.accounts import hash_password
from runtime.contract.artifact import UserAccount
from runtime.contract.refusal import Refusal
from tests.conftest import free_port
from tests.support.browser import chromium
from tests.support.runtime_process import running_resource, store_artifact
from tests.ui.browser_steps import (
    button_enabled,
    log_in,
    log_in_to_resource,
    text_of,
    wait_for_text,
)

pytestmark = pytest.mark.browser
PASSWORD = "correct-horse-7"


@dataclass(frozen=True)
class Plant:
    url: str
    client: ResourceClient


@pytest.fixture
def plant(tmp_path: Path, zenoh_endpoint: str) -> Iterator[Plant]:
    """The demo resource with a read-only user `viewer`, and the UI with three PADT
    accounts: `admin` (security administrator), `viewer` (read-write), `guest` (read-only)."""
    verifier = hash_password(PASSWORD)
    resource_users = [
        UserAccount("admin", "administrator", verifier),
        UserAccount("viewer", "read", verifier),
    ]
    result = compile_project(load_project([demo_project_with_accounts(tmp_path, resource_users)]))
    assert result.artifact is not None
    store_artifact(tmp_path, result.artifact)
    accounts_file = tmp_path / "padt-accounts.json"
    write_accounts(
        accounts_file,
        (
            UserAccount("admin", "security-administrator", verifier),
            UserAccount("viewer", "read-write", verifier),
            UserAccount("guest", "read-only", verifier),
        ),
    )
    with running_resource("Tank1", tmp_path, zenoh_endpoint) as (_, client):
        session = client.session
        accounts = PadtAccounts(accounts_file, time.monotonic_ns)
        context = UiContext(ResourceDirectory(session), accounts, zenoh_endpoint)
        ui = PadtUi(context, port=free_port())
        try:
            yield Plant(ui.url, client)
        finally:
            ui.close()


def open_as(page: Page, plant: Plant, user: str) -> None:
    page.goto(plant.url)
    page.get_by_role("button", name="Log in", exact=True).wait_for(timeout=30_000)
    log_in(page, user, PASSWORD)
    wait_for_text(page, '[data-testid="user"]', user)


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
