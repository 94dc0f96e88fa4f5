"""Download and online change in the browser, as an engineer does them through `padt
demo`: a download refused while the resource runs, then, in STOP, confirmed naming the
resource and both CRCs, and started from the same dialog; a target cycle time changed
online; the code changed; the online change dialog shows the source diff, every value's
fate and the online parameter value the change resets; confirmed, the values are kept;
a typing error, and a user whose level does not allow it."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from playwright.sync_api import Locator, Page

from tests.support.browser import chromium
from tests.ui.browser_steps import (
    Demo,
    Plant,
    button_enabled,
    choose,
    confirm,
    edit_value,
    field,
    log_in,
    open_as,
    open_tab,
    shoot_both,
    state,
    text_of,
    value,
    wait_for_text,
    wait_until,
)

pytestmark = pytest.mark.browser
DIALOG_S = 90  # two compiles in two processes and a transfer, on a machine that may be busy
TAB = "Online change"


def open_demo(page: Page, demo: Demo) -> None:
    """`open_demo_as_admin` with the patience of a machine shared by several test runs:
    the first refreshes of a new workspace (its project tree, the editor) may take a while."""
    page.goto(demo.url)
    page.get_by_role("button", name="Log in", exact=True).wait_for(timeout=60_000)
    log_in(page, "admin", demo.password)
    login = page.get_by_role("button", name="Log in to resource")
    login.wait_for(timeout=60_000)
    wait_until(
        "Tank1 is selected and its status shown",
        lambda: page.locator('[data-testid="resource-crc"]').count() > 0,
        timeout_s=60,
    )
    field(page, "User").fill("admin")
    field(page, "Password").fill(demo.password)
    login.click()
    wait_until(
        "the resource login is shown",
        lambda: text_of(page, '[data-testid="resource-login"]').startswith("logged in"),
        timeout_s=60,
    )
    wait_until("Tank1 runs", lambda: state(page) == "RUN", timeout_s=60)


def edit(path: Path, old: str, new: str) -> None:
    """What the engineer does in an editor."""
    text = path.read_text(encoding="utf-8")
    assert old in text, old
    path.write_text(text.replace(old, new), encoding="utf-8")


def dialog_showing(page: Page, selector: str) -> Locator:
    """The open dialog, once `selector` is in it (it fills when the compile is done)."""
    dialog = page.get_by_role("dialog")
    wait_until(
        f"the dialog shows {selector}",
        lambda: dialog.locator(selector).count() > 0,
        timeout_s=DIALOG_S,
    )
    return dialog


def screen_button(page: Page, name: str) -> Locator:
    """A button of the work area's screens (the editor's toolbar has its own)."""
    return page.locator("#root").get_by_role("button", name=name, exact=True).first


def scroll_dialog(page: Page, to: str) -> None:
    """Scroll what scrolls inside the open dialog (its plan, the diff, the table) to its
    "top" or "bottom", for a screenshot of that part."""
    page.evaluate(
        """to => {
          for (const e of document.querySelector('[role=dialog]').querySelectorAll('*'))
            if (e.scrollHeight > e.clientHeight) e.scrollTop = to === 'top' ? 0 : e.scrollHeight;
        }""",
        to,
    )


def fits_the_window(page: Page, dialog: Locator, buttons: tuple[str, ...]) -> None:
    """The dialog within the window, not scrolled as a whole, and each of `buttons` in
    view and on top where it is drawn: the user reaches it without scrolling anything."""
    whole = page.evaluate(
        """() => {
          const c = document.querySelector('.mantine-Modal-content');
          const r = c.getBoundingClientRect();
          return [r.top, r.bottom, c.scrollHeight - c.clientHeight, window.innerHeight];
        }"""
    )
    top, bottom, overflow, height = whole
    assert top >= 0 and bottom <= height and overflow <= 1, whole
    for name in buttons:
        button = dialog.get_by_role("button", name=name, exact=True)
        box = button.bounding_box()
        assert box is not None and box["y"] >= 0, (name, box)
        assert box["y"] + box["height"] <= height, (name, box)
        assert button.evaluate(
            """b => { const r = b.getBoundingClientRect();
              const x = r.x + r.width / 2, y = r.y + r.height / 2;
              return b.contains(document.elementFromPoint(x, y)) }"""
        ), name


def close(dialog: Locator) -> None:
    dialog.get_by_role("button", name="Close", exact=True).click()
    dialog.wait_for(state="detached")


def write(page: Page, variable: str, literal: str, said: str) -> None:
    """Write a value once from the Online test, confirmed."""
    open_tab(page, "Online test")
    edit_value(page, variable, literal)
    wait_until("Write is enabled", lambda: button_enabled(page, "Write"))
    page.get_by_role("button", name="Write", exact=True).click()
    confirm(page, said)
    wait_until(f"{variable} is {literal}", lambda: value(page, variable) == literal)


def test_download_in_stop_start_then_an_online_change_keeps_the_values(
    demo: Demo, tmp_path: Path
) -> None:
    source = tmp_path / "project" / "tank.st"  # the demo's project in its state folder
    with chromium() as browser:
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        open_demo(page, demo)
        running_crc = text_of(page, '[data-testid="resource-crc"]')
        # a new setting in the code
        edit(
            source,
            "  alarmLow : BOOL;",
            "  alarmLevel : INT := 100;     (* alarmLow below this *)\n  alarmLow : BOOL;",
        )
        edit(source, "alarmLow := level < 100;", "alarmLow := level < alarmLevel;")
        open_tab(page, TAB)

        # what changed since the configuration the demo loaded at its start (its backup)
        screen_button(page, TAB).click()
        dialog = dialog_showing(page, '[data-testid="source-diff"]')
        assert running_crc in text_of(page, '[data-testid="source-origin"]')
        diff = dialog.locator('[data-testid="source-diff"]').inner_text()
        assert "+  alarmLevel : INT := 100;     (* alarmLow below this *)" in diff
        assert text_of(page, '[data-fate="TankControl.alarmLevel"]') == "new"
        dialog.get_by_role("button", name="Cancel", exact=True).click()
        dialog.wait_for(state="detached")

        # while the resource runs, a download is refused, and the dialog says why
        screen_button(page, "Download").click()
        dialog = dialog_showing(page, '[data-testid="download-refused"]')
        assert "the resource is in RUN" in dialog.inner_text()
        assert "needs it in STOP" in dialog.inner_text()
        assert dialog.get_by_role("button", name="Download", exact=True).count() == 0
        close(dialog)

        # STOP, and a download instead
        open_tab(page, "Resources")
        page.get_by_role("button", name="Stop", exact=True).click()
        confirm(page, "Tank1")
        wait_until("Tank1 is in STOP", lambda: state(page) == "STOP/VALID CONFIGURATION")
        open_tab(page, TAB)
        screen_button(page, "Download").click()
        dialog = dialog_showing(page, '[data-testid="download-effects"]')
        assert text_of(page, '[data-testid="download-resource"]') == "Tank1"
        assert text_of(page, '[data-testid="download-project"]') == "demo"  # as in the tree
        assert text_of(page, '[data-testid="download-running-crc"]') == running_crc
        new_crc = text_of(page, '[data-testid="download-new-crc"]')
        assert re.fullmatch(r"[0-9A-F]{8}", new_crc) and new_crc != running_crc
        assert f"{new_crc} and {new_crc}, in two processes" in dialog.inner_text()
        assert "every variable starts from its initial value" in dialog.inner_text()
        fits_the_window(page, dialog, ("Download", "Cancel"))
        shoot_both(page, "download-dialog")
        dialog.get_by_role("button", name="Download", exact=True).click()
        wait_for_text(page, '[data-testid="download-crc"]', new_crc, timeout_s=DIALOG_S)
        assert text_of(page, '[data-testid="download-state"]') == "STOP/VALID CONFIGURATION"
        backup = text_of(page, '[data-testid="download-backup"]')
        assert Path(backup).is_file() and new_crc in backup
        shoot_both(page, "download-done")
        dialog.get_by_role("button", name="Start Tank1", exact=True).click()
        dialog.wait_for(state="detached")
        wait_until("Tank1 runs", lambda: state(page) == "RUN", timeout_s=30)
        assert text_of(page, '[data-testid="resource-crc"]') == new_crc

        # the engineer speeds the cycle up online
        open_tab(page, "Parameters")
        choose(page, "Parameter", "Target Cycle Time, ms (target_cycle_ms)")
        # the field offers the current value once the server has the choice; typed before
        # that, "50" was overwritten by "100 ms" (as a user sees and types again)
        new_value = field(page, "New value")
        wait_until("the current value is offered", lambda: new_value.input_value() == "100 ms")
        new_value.fill("50")
        # viser sends a field's value at most every 50 ms: a click that reaches the server
        # before the value asks nothing, so Set is pressed again until its dialog comes
        set_button = page.get_by_role("button", name="Set parameter")

        def asked() -> bool:
            if page.get_by_role("dialog").count():
                return True
            if new_value.input_value() != "50":
                new_value.fill("50")
            if button_enabled(page, "Set parameter"):
                set_button.click()
            page.wait_for_timeout(1_000)
            return page.get_by_role("dialog").count() > 0

        wait_until("the parameter's confirmation", asked, timeout_s=60)
        confirm(page, "50 ms")
        wait_for_text(page, '[data-param="resource.target_cycle_ms"]', "50 ms")

        # a typing error: the dialog says where, with the compiler's code
        edit(source, "level := tankLevel;", "level := tankLvel;")
        open_tab(page, TAB)
        screen_button(page, TAB).click()
        dialog = dialog_showing(page, '[data-testid="dialog-refused"]')
        assert "Online change refused (compile)" in dialog.inner_text()
        diagnostic = dialog.locator('[data-testid="diagnostic"]').first.inner_text()
        assert "tank.st:21:12" in diagnostic and "E0201" in diagnostic, diagnostic
        close(dialog)

        # corrected, and changed: a narrower counter, another limit
        edit(source, "level := tankLvel;", "level := tankLevel;")
        edit(source, "pumpStarts : DINT;", "pumpStarts : INT;")
        edit(source, "alarmLevel : INT := 100;", "alarmLevel : INT := 120;")
        # a value the running program holds that a fresh start would put back to 300
        write(page, "TankControl.lowLevel", "350", "TankControl.lowLevel (INT) once: 300 → 350")
        open_tab(page, TAB)
        screen_button(page, TAB).click()
        dialog = dialog_showing(page, '[data-fate="TankControl.level"]')
        assert text_of(page, '[data-testid="crc-running"]') == new_crc
        diff = dialog.locator('[data-testid="source-diff"]').inner_text()
        assert "tank.st (changed)" in diff
        assert "-  pumpStarts : DINT;" in diff and "+  pumpStarts : INT;" in diff
        assert "+  alarmLevel : INT := 120;" in diff
        assert "against backup " in text_of(page, '[data-testid="source-origin"]')
        fates = {
            path: text_of(page, f'[data-fate="{path}"]')
            for path in ("TankControl.level", "TankControl.pumpStarts", "TankControl.alarmLevel")
        }
        assert fates == {
            "TankControl.level": "kept",
            "TankControl.pumpStarts": "initialised",
            "TankControl.alarmLevel": "kept",
        }
        reset = text_of(page, '[data-testid="parameter-reset"]')
        assert reset == ("target_cycle_ms: 50 online, 100 in the project; the reload sets 100"), (
            reset
        )
        change = dialog.get_by_role("button", name=TAB, exact=True)
        assert not change.is_enabled()
        assert "1 of 1 not ticked" in text_of(page, '[data-testid="online-change-disabled"]')
        keep = text_of(page, '[data-testid="keep"]')
        assert keep == "Keep target_cycle_ms at its online value 50 after the switch-over", keep
        for label in ("Keep", "Accept"):  # one line each, not squeezed into a narrow column
            box = dialog.locator(f"label:text-is('{label}')").first.bounding_box()
            assert box is not None and box["height"] < 26, (label, box)
        dialog.get_by_label("Keep", exact=True).check()
        dialog.get_by_label("Accept", exact=True).check()
        wait_until("Online change is enabled", change.is_enabled)
        fits_the_window(page, dialog, (TAB, "Cancel"))
        for long_part in ('[data-testid="source-diff"]', '[data-testid="reload-plan"]'):
            assert dialog.locator(long_part).is_visible(), long_part
        scroll_dialog(page, "top")
        shoot_both(page, "online-change-dialog")
        scroll_dialog(page, "bottom")
        shoot_both(page, "online-change-confirm")
        change.click()
        wait_until(
            "the online change is done",
            lambda: page.locator('[data-testid="reload-result"]').count() > 0,
            timeout_s=DIALOG_S,
        )
        outcome = text_of(page, '[data-testid="reload-result"]')
        assert "Kept online" in outcome and "target_cycle_ms 50" in outcome, outcome
        changed_crc = text_of(page, '[data-testid="reload-new-crc"]')
        shoot_both(page, "online-change-done")
        close(dialog)
        wait_for_text(page, '[data-testid="resource-crc"]', changed_crc)

        # the values went on from where they were
        open_tab(page, "Online test")
        assert value(page, "TankControl.lowLevel") == "350"
        assert value(page, "TankControl.alarmLevel") == "100"  # kept: not the new initial
        open_tab(page, "Parameters")
        wait_for_text(page, '[data-param="resource.target_cycle_ms"]', "50 ms")


def test_a_read_only_user_sees_download_and_online_change_disabled_with_the_reason(
    plant: Plant,
) -> None:
    with chromium() as browser:
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        open_as(page, plant, "guest")  # a Read-only PADT account: it may look, not act
        wait_for_text(page, '[data-testid="resource-state"]', "RUN", timeout_s=30)
        open_tab(page, TAB)
        reason = "your PADT account is read-only: it may only look"
        wait_until(
            "the screen says why",
            lambda: reason in text_of(page, '[data-testid="deploy-disabled"]'),
        )
        said = text_of(page, '[data-testid="deploy-disabled"]')
        assert f"Download: {reason}" in said and f"Online change: {reason}" in said
        assert screen_button(page, "Compile").is_enabled()  # compiling changes nothing
        assert not screen_button(page, "Download").is_enabled()
        assert not screen_button(page, TAB).is_enabled()


def test_the_editor_toolbar_opens_the_same_dialogs(demo: Demo) -> None:
    with chromium() as browser:
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        open_demo(page, demo)
        page.locator('[data-tree^="file:TankControl@"]').first.click(timeout=30_000)
        page.locator("#padt-editor .cm-content").wait_for(timeout=30_000)
        page.evaluate(
            "document.querySelectorAll('.mantine-Notification-closeButton').forEach(b => b.click())"
        )

        # Download while Tank1 runs: the dialog says why not
        page.locator('#padt-editor [data-action="download"]').click()
        dialog = dialog_showing(page, '[data-testid="download-refused"]')
        assert "needs it in STOP" in dialog.inner_text()
        close(dialog)

        # Online change of the project as it is: nothing differs from what was loaded
        page.locator('#padt-editor [data-action="online_change"]').click()
        dialog = dialog_showing(page, '[data-testid="source-diff-none"]')
        assert text_of(page, '[data-testid="change-resource"]') == "Tank1"
        assert text_of(page, '[data-testid="crc-running"]') == text_of(
            page, '[data-testid="crc-new"]'
        )
        dialog.get_by_role("button", name="Cancel", exact=True).click()
        dialog.wait_for(state="detached")
