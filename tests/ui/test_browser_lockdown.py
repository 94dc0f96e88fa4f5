"""What of viser the PADT's page does without (issue 30, item 15): no client opens a public
share tunnel, whatever it sends over the websocket; the page shows neither Share nor
viser's settings (Dev Settings, scene tree, Save Canvas); a password field is a real
password input, not a text input masked by a Chromium-only CSS property."""

from __future__ import annotations

import asyncio
import logging

import msgspec
import pytest
import viser
import websockets
from playwright.sync_api import Page
from websockets.typing import Subprotocol

from tests.support.browser import chromium
from tests.ui.browser_steps import (
    PASSWORD,
    Plant,
    field,
    log_in_to_resource,
    open_as,
    shoot,
    wait_until,
)

pytestmark = pytest.mark.browser
SHARED_BROWSER = False  # asyncio.run cannot run while a Playwright lives (tests/ui/conftest.py)


async def _send_raw(url: str, message: dict[str, object]) -> None:
    """One message over a websocket of our own, encoded as viser's client encodes it."""
    address = url.replace("http://", "ws://")
    protocol = Subprotocol(f"viser-v{viser.__version__}")  # as viser's client says it
    async with websockets.connect(address, subprotocols=[protocol]) as ws:
        await ws.send(msgspec.msgpack.encode(message))
        await asyncio.sleep(0.5)  # stay connected while the server reads it


def test_a_crafted_share_url_request_opens_no_tunnel(
    plant: Plant, caplog: pytest.LogCaptureFixture
) -> None:
    caplog.set_level(logging.WARNING, logger="padt.ui")
    asyncio.run(_send_raw(plant.url, {"type": "ShareUrlRequest"}))
    wait_until(
        "the UI refused the share URL request",
        lambda: any("refused a share URL request" in r.getMessage() for r in caplog.records),
    )
    assert plant.ui.server._share_tunnel is None  # no tunnel, not even one being connected
    # a second one, after the first was handled, is refused all the same
    asyncio.run(_send_raw(plant.url, {"type": "ShareUrlRequest"}))
    wait_until(
        "the second request is refused too",
        lambda: sum("refused a share URL" in r.getMessage() for r in caplog.records) == 2,
    )
    assert plant.ui.server._share_tunnel is None


def _visible(page: Page, selector: str) -> int:
    return page.locator(f"{selector} >> visible=true").count()


def _no_viser_controls(page: Page) -> None:
    for icon in ("share", "adjustments"):  # Share and the button unfolding the settings
        assert _visible(page, f"button:has(svg.tabler-icon-{icon})") == 0, icon
    # the settings are folded away, and hidden for good (a fold opens when the panel moves)
    wait_until(
        "viser's settings are hidden",
        lambda: (
            page.locator("text=Save Canvas").first.evaluate(
                "b => getComputedStyle(b.closest('.mantine-Stack-root')).display"
            )
            == "none"
        ),
    )
    for words in ("Save Canvas", "Dev Settings", "Scene tree", "Share"):
        assert _visible(page, f"text={words}") == 0, words


def test_no_share_or_settings_in_the_page_and_passwords_are_password_inputs(
    plant: Plant,
) -> None:
    with chromium() as browser:
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        page.goto(plant.url)
        page.get_by_role("button", name="Log in", exact=True).wait_for(timeout=30_000)
        wait_until("the login's password is a password input",
                   lambda: field(page, "Password").get_attribute("type") == "password")  # fmt: skip
        _no_viser_controls(page)
        shoot(page, "login")
        # typing works as in any field, and logs in
        open_as(page, plant, "admin")
        _no_viser_controls(page)
        wait_until("the resource login's password is a password input",
                   lambda: field(page, "Password").get_attribute("type") == "password")  # fmt: skip
        log_in_to_resource(page, "admin", PASSWORD)
        assert field(page, "Password").get_attribute("type") == "password"
        assert field(page, "Password").input_value() == ""  # not kept in the page
        # logged out, the login card's password is a password input again
        page.get_by_role("button", name="Log out").click()
        page.get_by_role("button", name="Log in", exact=True).wait_for(timeout=30_000)
        wait_until("the password is a password input after logging out",
                   lambda: field(page, "Password").get_attribute("type") == "password")  # fmt: skip
        _no_viser_controls(page)
