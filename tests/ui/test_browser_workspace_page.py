"""The programming workspace as a user first meets it, through the UI and headless Chromium
(whose WebGL renders in software, as in a VM without a GPU): the project's first PROGRAM is
open in the centre without a click; no note of viser's about software WebGL covers the
editor's toolbar; the inputs through which the page talks to the server are never seen;
a confirmation and a dropdown's list opened while a file is open are above the editor and
answer a click where they are drawn; the stop confirmed is the newest event below the
editor; the plant drawing and the editor take turns."""

from __future__ import annotations

import io

import pytest
from PIL import Image
from playwright.sync_api import Locator, Page

from tests.support.browser import chromium
from tests.ui.browser_steps import (
    Plant,
    confirm,
    log_in_to_resource,
    open_as,
    open_tab,
    state,
    wait_until,
)

pytestmark = pytest.mark.browser

WEBGL_NOTE = "Software WebGL rendering detected"
RENDERER = """() => {
    const gl = document.createElement('canvas').getContext('webgl');
    const info = gl && gl.getExtension('WEBGL_debug_renderer_info');
    return info ? String(gl.getParameter(info.UNMASKED_RENDERER_WEBGL)) : '';
}"""
# what a click at the middle of the element would hit: the element itself, or else the id
# of what covers it (through the editor's shadow root)
ON_TOP = """(e) => {
    const r = e.getBoundingClientRect();
    const x = r.left + r.width / 2, y = r.top + r.height / 2;
    let hit = document.elementFromPoint(x, y);
    while (hit && hit.shadowRoot) {
        const inner = hit.shadowRoot.elementFromPoint(x, y);
        if (!inner || inner === hit) break;
        hit = inner;
    }
    if (hit === e || e.contains(hit) || (hit && hit.contains(e))) return 'it';
    return (hit && hit.id) || String(hit && hit.tagName);
}"""


def editor_text(page: Page) -> str:
    text: str = page.evaluate(
        "window.padtEditor ? window.padtEditor.view.state.doc.toString() : ''"
    )
    return text


def on_top(locator: Locator) -> str:
    said: str = locator.evaluate(ON_TOP)
    return said


@pytest.mark.parametrize("size", [(1400, 900), (1920, 1080)])
def test_the_first_program_is_open_and_nothing_covers_it(
    plant: Plant, size: tuple[int, int]
) -> None:
    width, height = size
    with chromium() as browser:
        page = browser.new_page(viewport={"width": width, "height": height})
        open_as(page, plant, "admin")
        # the first PROGRAM, opened without a click on the tree
        page.locator("#padt-editor .cm-content").wait_for(timeout=30_000)
        wait_until("TankControl is open", lambda: "PROGRAM TankControl" in editor_text(page))
        toolbar = page.locator('#padt-editor [data-action="download"]')
        assert on_top(toolbar) == "it"
        software = page.evaluate(RENDERER).lower()
        if any(word in software for word in ("swiftshader", "llvmpipe", "software")):
            page.wait_for_timeout(1500)  # viser's check runs as its page starts: long done
            note = page.get_by_text(WEBGL_NOTE, exact=True)
            assert note.locator("visible=true").count() == 0
        for label in ("Editor message", "Page click"):
            row = page.locator(f"label:text-is('{label}')")
            assert row.count() == 1 and not row.is_visible(), label

        # a confirmation opened while the file is open answers a click on its OK
        log_in_to_resource(page, "admin", "correct-horse-7")
        wait_until("Tank1 runs", lambda: state(page) == "RUN", timeout_s=30)
        open_tab(page, "Resources")
        page.get_by_role("button", name="Stop", exact=True).click()
        dialog = page.get_by_role("dialog")
        dialog.wait_for(timeout=20_000)
        assert on_top(dialog.get_by_role("button", name="OK")) == "it"
        confirm(page, "Tank1")
        wait_until("Tank1 is in STOP", lambda: state(page).startswith("STOP"), timeout_s=30)
        # below the editor, the resource's newest events: the stop among them, by admin
        page.locator('#padt-editor [data-bottom="events"]').click()
        stop = page.locator('#padt-editor [data-testid="events-list"] tr[data-kind="stop"]')
        wait_until("the stop is listed", lambda: stop.count() == 1)
        assert "admin" in stop.inner_text()

        # a dropdown's list (drawn in a layer of its own) above the editor
        page.get_by_label("Resource", exact=True).first.click()
        option = page.get_by_role("option", name="Tank1", exact=True).first
        option.wait_for(timeout=20_000)
        assert on_top(option) == "it"
        page.keyboard.press("Escape")


CANVAS_WIDTH = "() => document.querySelector('canvas[data-engine]').getBoundingClientRect().width"
RUN_GREEN = (47, 158, 68)  # frontend/plant_view.py: a block in RUN


def _near(colour: tuple[int, int, int], wanted: tuple[int, int, int]) -> bool:
    return all(abs(a - b) <= 12 for a, b in zip(colour, wanted, strict=True))


def green_share(page: Page) -> float:
    """The share of the canvas' pixels in the green of RUN, as the user sees them."""
    box = page.locator("canvas[data-engine]").bounding_box()
    assert box is not None
    shot = Image.open(io.BytesIO(page.screenshot(clip=box))).convert("RGB")
    colours: list[tuple[int, tuple[int, int, int]]] = shot.getcolors(shot.width * shot.height) or []  # type: ignore[assignment]
    near = sum(count for count, colour in colours if _near(colour, RUN_GREEN))
    return near / (shot.width * shot.height)


def test_the_plant_drawing_and_the_editor_take_turns(plant: Plant) -> None:
    """The editor's "Plant drawing" shows the resource and its programs in the colours of
    their states in the editor's place; "Editor" brings the editor back. While the editor
    shows, the canvas under it is out of the page, so that viser does not draw it: it drew
    its scene anew after each of the editor's live values, which cost a browser that draws
    without a GPU more than a core."""
    with chromium() as browser:
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        open_as(page, plant, "admin")
        page.locator("#padt-editor .cm-content").wait_for(timeout=30_000)
        log_in_to_resource(page, "admin", "correct-horse-7")
        wait_until("Tank1 runs", lambda: state(page) == "RUN", timeout_s=30)
        wait_until("no canvas under the editor", lambda: page.evaluate(CANVAS_WIDTH) == 0)

        page.locator('#padt-editor [data-action="drawing"]').click()
        wait_until("the canvas fills the editor's place", lambda: page.evaluate(CANVAS_WIDTH) > 300)
        wait_until("the resource and its program drawn in RUN", lambda: green_share(page) > 0.1)
        assert not page.locator("#padt-editor .cm-content").is_visible()

        page.get_by_role("button", name="Editor", exact=True).click()
        page.locator("#padt-editor .cm-content").wait_for(timeout=20_000)
        wait_until("no canvas under the editor again", lambda: page.evaluate(CANVAS_WIDTH) == 0)
