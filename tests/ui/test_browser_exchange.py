"""The exchange between resources on the I/O screen (docs/exchange.md): the resource's
publication with its messages counted, a subscription to a publisher that is not there
(lost, its global at its safe value, marked bad, the reason shown), then the publisher's
messages arriving (connected, the value good)."""

from __future__ import annotations

import contextlib
import itertools
import re
import threading
from collections.abc import Iterator

import pytest
from playwright.sync_api import Page

from runtime.contract.keyspace import exchange_key
from runtime.contract.signatures import stamp_bytes, stamped
from runtime.field_io.peer_exchange.message import encode
from runtime.identity import Identity
from tests.support.browser import chromium
from tests.ui.browser_steps import (
    PASSWORD,
    Plant,
    log_in_to_resource,
    open_as,
    open_tab,
    shoot_both,
    text_of,
    wait_until,
)

pytestmark = pytest.mark.browser


def messages(page: Page) -> int:
    line = text_of(page, '[data-testid="io-server"][data-protocol="zenoh"]')
    found = re.search(r"(\d+) messages? put", line)
    return int(found.group(1)) if found else -1


def point(page: Page, variable: str) -> tuple[str, str]:
    cell = page.locator(f'[data-point="{variable}"]').first
    return cell.inner_text(), cell.get_attribute("data-quality") or ""


@pytest.mark.parametrize("plant", ["exchange"], indirect=True)
def test_a_publication_and_a_subscription_on_the_io_screen(plant: Plant) -> None:
    with chromium() as browser:
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        open_as(page, plant, "admin")
        log_in_to_resource(page, "admin", PASSWORD)
        open_tab(page, "I/O")
        wait_until("the publication is put", lambda: messages(page) > 0)
        assert "padt/v2/res/Tank1/exchange/tank" in text_of(
            page, '[data-testid="io-server"][data-protocol="zenoh"]'
        )
        before = messages(page)
        wait_until("its messages are counted", lambda: messages(page) > before)

        # nobody publishes Filler/levels: lost after its timeout, the safe value marked bad
        wait_until(
            "the subscription is lost",
            lambda: text_of(page, '[data-device="Filler/levels"] [data-state]') == "lost",
        )
        row = text_of(page, '[data-device="Filler/levels"]')
        assert "padt/v2/res/Filler/exchange/levels" in row
        assert "no message for 300 ms" in row
        assert point(page, "fillerLevel") == ("-1", "bad")  # a REAL shown as the Online test does
        shoot_both(page, "io-exchange-lost")

        # the publisher's messages arrive (signed with its own key, pinned at the first)
        with _publishing(plant, 12.5):
            wait_until("the value is good", lambda: point(page, "fillerLevel") == ("12.5", "good"))
            wait_until(
                "the subscription is connected",
                lambda: text_of(page, '[data-device="Filler/levels"] [data-state]') == "connected",
            )
            shoot_both(page, "io-exchange-connected")


@contextlib.contextmanager
def _publishing(plant: Plant, level: float) -> Iterator[None]:
    """A publisher of Filler/levels in the test's process: every 50 ms, as a runtime would."""
    identity, stop = Identity.fresh(), threading.Event()

    def publish() -> None:
        for number in itertools.count(1):
            entries = [("level", "REAL", level)]
            payload = encode("Filler", "levels", True, identity.public_key, entries)
            stamp = stamp_bytes(identity.boot, number)
            attachment = stamp + identity.sign(stamped(stamp, payload))
            plant.client.session.put(
                exchange_key("Filler", "levels"), payload, attachment=attachment
            )
            if stop.wait(0.05):
                return

    thread = threading.Thread(target=publish, daemon=True)
    thread.start()
    try:
        yield
    finally:
        stop.set()
        thread.join()
