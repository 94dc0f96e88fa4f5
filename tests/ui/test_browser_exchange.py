"""A plant of several resources as the PADT shows it: the exchange between resources on
the I/O screen (docs/exchange.md): the resource's publication with its messages counted, a
subscription to a publisher that is not there (lost, its global at its safe value, marked
bad, the reason shown), then the publisher's messages arriving (connected, the value
good); and a resource out of the PADT's reach and back, in the status bar."""

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
from tests.support.runtime_process import runtime_process
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


def test_a_resource_out_of_reach_and_back_in_the_status_bar(plant: Plant) -> None:
    """Its runtime process gone (killed: a host cut off looks the same to the PADT), the
    status bar says since when and that the values shown are the last it sent; back, it
    says for how long it was away and where the gap is."""
    assert plant.runtime is not None and plant.state is not None
    with chromium() as browser:
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        open_as(page, plant, "admin")
        log_in_to_resource(page, "admin", PASSWORD)
        wait_until("RUN", lambda: text_of(page, '[data-testid="resource-state"]') == "RUN")
        plant.runtime.kill()
        plant.runtime.wait()
        wait_until(
            "out of reach",
            lambda: "out of reach since" in text_of(page, '[data-testid="resource-reach"]'),
        )
        assert "what is shown is what it last sent" in text_of(page, '[data-testid="statusbar"]')
        banner = text_of(page, '[data-testid="reach-banner"]')
        assert re.fullmatch(
            r"Tank1 OUT OF REACH since \d\d:\d\d:\d\d: the values shown are the last it sent",
            banner.strip(),
        ), banner
        # the Resources screen lists it no more, and no command is offered for it
        wait_until(
            "no Tank1 row",
            lambda: "Tank1" not in text_of(page, '[data-testid="resources"]'),
        )
        assert not page.get_by_role("button", name="Stop", exact=True).first.is_enabled()
        assert "Tank1 is out of reach" in text_of(page, '[data-testid="commands-disabled"]')
        shoot_both(page, "status-out-of-reach")
        with runtime_process("Tank1", plant.state, plant.zenoh, "--modbus-port", "0"):
            wait_until(
                "back",
                lambda: (
                    re.search(
                        r"out of reach \d\d:\d\d:\d\d to \d\d:\d\d:\d\d \(\d+\.\d s\)",
                        text_of(page, '[data-testid="resource-reach"]'),
                    )
                    is not None
                ),
            )
            assert "values and trends have a gap there" in text_of(
                page, '[data-testid="statusbar"]'
            )
            assert not page.locator('[data-testid="reach-banner"]').is_visible()
            shoot_both(page, "status-back-in-reach")
