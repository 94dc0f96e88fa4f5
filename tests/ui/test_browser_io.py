"""The I/O screen as a user sees it, through the demo: the served image listening with its
request count going up as a Modbus client reads it, the plant polled as a remote device,
and every mapped point with its value; in STOP the served pump command is its safe value."""

from __future__ import annotations

import re

import pytest
from playwright.sync_api import Page

from tests.runtime.test_modbus_server import wait_for
from tests.support.browser import chromium
from tests.support.modbus_device import modbus_client, reachable
from tests.ui.browser_steps import (
    Demo,
    choose,
    confirm,
    open_demo_as_admin,
    open_tab,
    shoot_both,
    text_of,
    wait_until,
)

pytestmark = pytest.mark.browser


def requests(page: Page) -> int:
    server = text_of(page, '[data-testid="io-server"]')
    found = re.search(r"(\d+) requests? ·", server)
    assert found is not None, server
    return int(found.group(1))


def point(page: Page, variable: str) -> tuple[str, str]:
    cell = page.locator(f'[data-point="{variable}"]').first
    return cell.inner_text(), cell.get_attribute("data-quality") or ""


def served(page: Page) -> list[list[str]]:
    """[value, quality] of each point of the served image."""
    found: list[list[str]] = page.evaluate(
        """() => [...document.querySelectorAll('[data-testid="io-points"] tr')]
            .filter(row => row.firstChild.innerText === 'server')
            .map(row => row.querySelector('[data-point]'))
            .map(cell => [cell.innerText, cell.dataset.quality])"""
    )
    return found


@pytest.mark.parametrize("demo", ["opcua"], indirect=True)
def test_the_served_image_the_plant_and_the_points_with_their_values(demo: Demo) -> None:
    wait_for(lambda: reachable(demo.modbus_port), 30)
    with chromium() as browser:
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        open_demo_as_admin(page, demo)
        open_tab(page, "I/O")
        wait_until(
            "the server listens",
            lambda: f"127.0.0.1:{demo.modbus_port}" in text_of(page, '[data-testid="io-server"]'),
        )
        wait_until(
            "the OPC UA server listens",
            lambda: (
                f"opc.tcp://127.0.0.1:{demo.opcua_port}"
                in text_of(page, '[data-testid="io-server"][data-protocol="opcua"]')
            ),
        )
        wait_until(
            "the plant is connected",
            lambda: text_of(page, '[data-device="plant"] [data-state]') == "connected",
        )

        # a Modbus client's reads are counted
        before = requests(page)
        with modbus_client(demo.modbus_port) as modbus:
            for _ in range(5):
                modbus.read_input_registers(0, count=1)
        wait_until("the reads are counted", lambda: requests(page) >= before + 5)

        # the level as delivered by the plant moves
        wait_until("the level is shown", lambda: point(page, "tankLevel")[1] == "good")
        first = point(page, "tankLevel")[0]
        wait_until("the level moves", lambda: point(page, "tankLevel")[0] != first)
        shoot_both(page, "io")

        choose(page, "Points of", "plant")
        wait_until(
            "only the plant's points",
            lambda: page.locator('[data-testid="io-points"] tr').count() == 1 + 3,
        )
        choose(page, "Points of", "(all)")

        # in STOP the served outputs are their safe values
        open_tab(page, "Resources")
        page.get_by_role("button", name="Stop", exact=True).click()
        confirm(page, "Tank1")
        open_tab(page, "I/O")
        wait_until(
            "the served pump command is its safe value",
            lambda: ["FALSE", "safe"] in served(page),
        )
        shoot_both(page, "io-stop")
