"""Debugging in the browser's editor as an engineer does it through `padt demo`: a click in
the gutter beside a statement of TankControl arms a breakpoint there; when the program
stops at it, the line is lit with an arrow, the Debug panel says which program is in BKPT
and where, its call stack and its variables with their values (`level`); Step over (the
button, then F10) moves the lit line to the next statement; Run to cursor, Step into a
block's call (the caller's frame chosen: its line and variables), Step out; with the
breakpoint removed,
Continue runs on: the lit line goes and the program is back in RUN. A user who may only
read at the resource sees the breakpoints another engineer set, sets none and finds the
steps disabled, with the reason."""

from __future__ import annotations

import re

import pytest
from playwright.sync_api import Page

from runtime.contract import protocol as p
from tests.support.browser import chromium
from tests.ui.browser_steps import (
    PASSWORD,
    START_S,
    Demo,
    Plant,
    log_in_to_resource,
    open_as,
    open_demo_as_admin,
    shoot_both,
    text_of,
    wait_until,
)
from tests.ui.test_browser_editor import dismiss_notifications

pytestmark = pytest.mark.browser

LINE = 18  # alarmPlant := tankLevel < 0;  (the first statement of TankControl's cycle)
STOP_S = 30  # from the click to the stop: the set goes to the resource, the stop comes back


def debug_state(page: Page, key: str) -> object:
    return page.evaluate(f"(window.padtEditor.debug.state || {{}})[{key!r}]")


def paused_line(page: Page) -> int:
    line: int = page.evaluate(
        "(() => { const p = window.padtEditor.debug.state.paused; return p ? p.line : 0; })()"
    )
    return line


def lit_text(page: Page, kind: str = "paused") -> str:
    """The text of the line lit as the one the program stands at (`frame`: the chosen
    frame's), without the live values at its end; "" when none is. Read at once: the line
    may be drawn anew at any moment."""
    text: str = page.evaluate(
        """kind => {
          const root = document.querySelector('#padt-editor').shadowRoot;
          const line = root.querySelector(`.cm-line[data-lit="${kind}"]`);
          if (!line) return "";
          return Array.from(line.childNodes).filter(n => !n.classList ||
            !n.classList.contains('padt-live')).map(n => n.textContent).join('');
        }""",
        kind,
    )
    return text


def line_text(page: Page, number: int) -> str:
    text: str = page.evaluate(f"window.padtEditor.view.state.doc.line({number}).text")
    return text


def click_gutter(page: Page, line: int, button: str = "left") -> None:
    """A click in the debug gutter, level with the line's number."""
    number = page.locator(f"#padt-editor .cm-lineNumbers .cm-gutterElement:text-is('{line}')")
    number.first.scroll_into_view_if_needed()
    row = number.first.bounding_box()
    gutter = page.locator("#padt-editor .padt-debug-gutter").first.bounding_box()
    assert row is not None and gutter is not None
    x, y = gutter["x"] + gutter["width"] / 2, row["y"] + row["height"] / 2
    page.mouse.click(x, y, button="right" if button == "right" else "left")


def told(page: Page) -> str:
    """The debug state the page was sent last and what the editor said last."""
    text: str = page.evaluate(
        "JSON.stringify([window.padtEditor.debug.state, window.padtEditor.status.textContent])"
    )
    return text


def program_state(page: Page) -> str:
    return text_of(page, '[data-program="TankControl"]')


def editor_ready(page: Page, allowed: bool) -> None:
    """tank.st in the editor, which knows that the resource runs it."""
    wait_until(
        "TankControl is in the editor",
        lambda: "alarmPlant := tankLevel < 0;" in line_text(page, LINE),
        timeout_s=START_S,
    )
    wait_until(
        "the editor knows Tank1 runs this project",
        lambda: debug_state(page, "on") is True and debug_state(page, "allowed") is allowed,
        timeout_s=START_S,  # the project is compiled to find the running one
    )


def test_a_gutter_breakpoint_stops_the_program_and_the_panel_steps_it(demo: Demo) -> None:
    with chromium() as browser:
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        open_demo_as_admin(page, demo)
        editor_ready(page, allowed=True)

        click_gutter(page, LINE)
        dot = page.locator(f'#padt-editor [data-bp-line="{LINE}"][data-bp="verified"]')
        wait_until("the breakpoint is armed", lambda: dot.count() == 1, timeout_s=STOP_S)
        try:
            wait_until("TankControl stops", lambda: paused_line(page) == LINE, timeout_s=STOP_S)
        except AssertionError as never:  # what the page knew, for whoever reads the failure
            raise AssertionError(f"{never}; the page: {told(page)}") from None
        wait_until(
            "its line is lit", lambda: lit_text(page) == line_text(page, LINE), timeout_s=STOP_S
        )
        assert page.locator('#padt-editor [data-arrow="top"]').count() == 1
        where = '[data-testid="debug-where"]'
        wait_until(
            "the panel says where",
            lambda: "TankControl in BKPT at tank.st:18" in text_of(page, where),
        )
        wait_until("the status says BKPT", lambda: "BKPT" in program_state(page))
        frame = '[data-testid="debug-stack"] [data-frame="0"]'
        wait_until("the stack shows the program", lambda: "tank.st:18" in text_of(page, frame))
        assert "TankControl" in text_of(page, frame)
        level = '[data-testid="debug-variables"] [data-value="level"]'
        wait_until(
            "level has a value", lambda: re.fullmatch(r"-?\d+", text_of(page, level)) is not None
        )
        row = page.locator('[data-testid="debug-variables"] [data-var-path="level"]')
        assert "TankControl.level" in (row.get_attribute("title") or ""), "where to write it"
        dismiss_notifications(page)
        shoot_both(page, "debugging-bkpt")

        page.locator('[data-testid="debug-variables"] [data-var-path="refillDelay"]').click()
        member = '[data-testid="debug-variables"] [data-value="refillDelay.Q"]'
        wait_until("the TON's members show", lambda: text_of(page, member) in ("TRUE", "FALSE"))

        page.locator('#padt-editor [data-debug="over"]').click()
        wait_until("Step over goes to the next statement", lambda: paused_line(page) == LINE + 1)
        wait_until("the lit line follows", lambda: lit_text(page) == line_text(page, LINE + 1))
        page.keyboard.press("F10")  # IF NOT alarmPlant THEN: into its branch, or past it
        wait_until("F10 steps over too", lambda: paused_line(page) in (LINE + 2, LINE + 4))

        page.evaluate("window.padtEditor.select('tank.st', 25, 3)")
        page.locator('#padt-editor [data-debug="run_to"]').click()
        wait_until("Run to cursor", lambda: paused_line(page) == 25)
        # into the TON's body (the standard library's ST), then the caller's frame chosen
        page.locator('#padt-editor [data-debug="into"]').click()
        stack = '[data-testid="debug-stack"]'
        wait_until(
            "a frame of the TON on top", lambda: "TON" in text_of(page, f'{stack} [data-frame="0"]')
        )
        wait_until(
            "TankControl below", lambda: "tank.st:25" in text_of(page, f'{stack} [data-frame="1"]')
        )
        page.locator(f'{stack} [data-frame="1"]').click()
        wait_until("its line is lit", lambda: lit_text(page, "frame") == line_text(page, 25))
        wait_until("its variables listed", lambda: page.locator(level).count() == 1)
        page.locator('#padt-editor [data-debug="out"]').click()
        wait_until("Step out: back in TankControl", lambda: paused_line(page) == 26)
        wait_until(
            "one frame again", lambda: page.locator(f'{stack} [data-frame="1"]').count() == 0
        )

        click_gutter(page, LINE)  # the breakpoint off: Continue would stop there again
        wait_until(
            "the breakpoint is gone",
            lambda: page.locator(f'#padt-editor [data-bp-line="{LINE}"]').count() == 0,
        )
        wait_until("the resource has no breakpoint", lambda: debug_state(page, "breakpoints") == [])
        page.locator('#padt-editor [data-debug="continue"]').click()
        wait_until("no line is lit", lambda: lit_text(page) == "" and paused_line(page) == 0)
        wait_until("TankControl runs again", lambda: program_state(page) == "TankControl: RUN")
        assert page.locator('#padt-editor [data-debug="over"]').is_disabled()
        assert "No program is in BKPT" in text_of(page, '[data-testid="debug-reason"]')
        dismiss_notifications(page)
        shoot_both(page, "debugging-run")

        timeout = page.locator('[data-testid="debug-timeout"]')
        timeout.fill("300")
        timeout.press("Enter")
        wait_until("the debug timeout is set", lambda: debug_state(page, "timeout_s") == 300)

        # a condition that does not parse: the breakpoint is not armed, and says why
        click_gutter(page, 22, button="right")
        form = page.locator('[data-testid="breakpoint-form"]')
        form.locator('[data-bp-field="condition"]').fill("level >")
        shoot_both(page, "debugging-form")
        form.locator('[data-bp-field="condition"]').press("Enter")
        hollow = page.locator('#padt-editor [data-bp-line="22"][data-bp="unverified"]')
        wait_until("an unverified breakpoint", lambda: hollow.count() == 1, timeout_s=STOP_S)
        assert hollow.get_attribute("title"), "its tooltip says why"
        hollow.hover()
        shoot_both(page, "debugging-unverified")
        assert "TankControl: RUN" in program_state(page)
        click_gutter(page, 22, button="right")
        page.locator('[data-testid="breakpoint-form"] [data-bp-action="remove"]').click()
        wait_until("no breakpoint left", lambda: debug_state(page, "breakpoints") == [])


def test_a_user_who_may_only_read_sets_no_breakpoint(plant: Plant) -> None:
    plant.client.login("admin", PASSWORD)  # another engineer's breakpoint, never hit
    spec = p.BreakpointSpec(22, condition="level > 30000")
    plant.client.ask(p.DebugSet("tank.st", [spec]))
    with chromium() as browser:
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        open_as(page, plant, "viewer")  # read-write on the PADT, read at the resource
        log_in_to_resource(page, "viewer", PASSWORD)
        editor_ready(page, allowed=False)
        page.locator('#padt-editor [data-bottom="debug"]').click()
        reason = "needs read-write at the resource; viewer is read"
        wait_until(
            "the panel says why", lambda: reason in text_of(page, '[data-testid="debug-reason"]')
        )
        theirs = page.locator('#padt-editor [data-bp-line="22"][data-bp="verified"]')
        wait_until("the other engineer's breakpoint shows", lambda: theirs.count() == 1)
        for action in ("continue", "over", "into", "out", "cycle", "run_to"):
            button = page.locator(f'#padt-editor [data-debug="{action}"]')
            assert button.is_disabled() and reason in (button.get_attribute("title") or "")
        click_gutter(page, LINE)
        status = '[data-testid="editor-status"]'
        wait_until("the click is answered with the reason", lambda: reason in text_of(page, status))
        assert page.locator(f'#padt-editor [data-bp-line="{LINE}"]').count() == 0
        armed = plant.client.ask(p.DebugGet()).debug.breakpoints
        assert [(b.file, b.line) for b in armed] == [("tank.st", 22)]  # none came from the page
