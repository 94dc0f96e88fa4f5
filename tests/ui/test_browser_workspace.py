"""The workspace as an IDE (issue 31, item 3): a screen listed in one place appears as a
tab and is drawn; the project tree shows the project's POUs, resource, program instances,
Modbus devices and accounts; at 1400x900 nothing of the navigation or the work panel is
cut off by the window, and no browser, logged in or not, sees viser's Share or settings."""

from __future__ import annotations

import os
from pathlib import Path

import pytest
import viser
from playwright.sync_api import Page

from frontend import screens
from frontend.screen_registry import Now, Screen, Work
from tests.support.browser import chromium
from tests.ui.browser_steps import Plant, open_as, text_of, wait_for_text, wait_until

pytestmark = pytest.mark.browser

SHOTS = Path(os.environ.get("PADT_WORKSPACE_SHOTS", "/work/notes/31/shots"))


class Cycles(Screen):
    """A screen of the test's own: the selected resource's cycle count."""

    name = "Cycles"
    icon = viser.Icon.CLOCK

    def __init__(self, work: Work) -> None:
        super().__init__(work)
        self.shown = work.gui.add_html("")

    def refresh(self, now: Now) -> None:
        count = now.status.cycle if now.status is not None else -1
        self.shown.content = f'<div data-testid="cycles">{now.resource} {count}</div>'


def test_a_screen_listed_in_one_place_is_a_tab_and_is_drawn(
    plant: Plant, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(screens, "SCREENS", (*screens.SCREENS, Cycles))
    with chromium() as browser:
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        open_as(page, plant, "admin")
        page.get_by_role("tab", name="Cycles").click()

        def counted() -> int:
            words = text_of(page, '[data-testid="cycles"]').split()
            return int(words[1]) if len(words) == 2 and words[0] == "Tank1" else -1

        wait_until("the new screen shows Tank1's cycles", lambda: counted() > 0)
        first = counted()
        wait_until("and is drawn again as they go on", lambda: counted() > first)


def _tree(page: Page) -> str:
    return text_of(page, '[data-testid="project-tree"]')


def test_the_tree_shows_the_project(plant: Plant) -> None:
    with chromium() as browser:
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        open_as(page, plant, "admin")
        wait_until("the tree is read", lambda: "POUs" in _tree(page))
        tree = _tree(page)
        for seen in (
            "Programs",
            "TankControl",  # the PROGRAM, and its instance on the resource
            "Resource Tank1",
            "TankControl : TankControl (priority 0)",
            "Modbus devices",
            "plant at 127.0.0.1:",
            "admin (administrator)",
            "viewer (read)",
        ):
            assert seen in tree, (seen, tree)
        # an entry clicked is the tree's selection
        page.locator('[data-tree^="program:TankControl"]').click()
        wait_until(
            "the program instance is selected",
            lambda: (
                page.locator('[data-tree^="program:TankControl"]').evaluate(
                    "e => getComputedStyle(e).backgroundColor"
                )
                == "rgb(208, 235, 255)"
            ),
        )


def _cut_off(page: Page) -> list[str]:
    """Every control or text the user should see that the window cuts off: its box across
    the window's sides or above its top, where no scroll bar of its own brings it into view
    (a wide table scrolling sideways in its screen can be read whole; a panel that clips
    it, or the window's edge, cannot)."""
    return list(
        page.evaluate(
            """() => {
            const w = window.innerWidth, cut = [];
            const seen = 'button, input, label, [role=tab], [data-testid], summary';
            const scroller = e => {
                for (let a = e.parentElement; a; a = a.parentElement) {
                    const x = getComputedStyle(a).overflowX;
                    if ((x === 'auto' || x === 'scroll') && a.scrollWidth > a.clientWidth)
                        return a;
                }
                return null;
            };
            for (const e of document.querySelectorAll(seen)) {
                let r = e.getBoundingClientRect();
                if (r.width === 0 || r.height === 0) continue;  // not shown
                if (getComputedStyle(e).visibility === 'hidden') continue;
                const name = (e.dataset.testid || e.textContent || e.tagName).slice(0, 40);
                const box = scroller(e);
                if (box) r = box.getBoundingClientRect();
                if (r.left < -1 || r.right > w + 1 || r.top < -1)
                    cut.push(`${name} ${Math.round(r.left)}..${Math.round(r.right)}`);
            }
            return cut;
        }"""
        )
    )


@pytest.mark.parametrize("size", [(1400, 900), (1920, 1080)])
def test_nothing_is_cut_off_and_no_viser_controls(plant: Plant, size: tuple[int, int]) -> None:
    width, height = size
    with chromium() as browser:
        page = browser.new_page(viewport={"width": width, "height": height})
        page.goto(plant.url)
        page.get_by_role("button", name="Log in", exact=True).wait_for(timeout=30_000)
        _no_viser_controls(page)  # anonymous
        open_as(page, plant, "admin")
        wait_until("the tree is read", lambda: "POUs" in _tree(page))
        wait_for_text(page, '[data-testid="resource-state"]', "RUN", timeout_s=30)
        _no_viser_controls(page)
        for tab in ("Resources", "Online test", "Reload", "Trends"):
            page.get_by_role("tab", name=tab).click()
            page.wait_for_timeout(600)  # the panel's width follows the tab
            if tab in ("Resources", "Trends"):
                SHOTS.mkdir(parents=True, exist_ok=True)
                shot = SHOTS / f"workspace-{tab.lower()}-{width}x{height}.png"
                page.screenshot(path=str(shot))
            assert _cut_off(page) == [], (tab, _cut_off(page))


def _no_viser_controls(page: Page) -> None:
    for icon in ("share", "adjustments"):
        assert page.locator(f"button:has(svg.tabler-icon-{icon}) >> visible=true").count() == 0
    for words in ("Save Canvas", "Dev Settings", "Scene tree", "Share"):
        assert page.locator(f"text={words} >> visible=true").count() == 0, words
    # viser's logo (its header's image) is not drawn either
    assert page.locator("img[src*='viser'] >> visible=true").count() == 0
