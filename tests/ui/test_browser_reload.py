"""Reload (online change) in the browser, as an engineer does it: edit the demo's project in
its folder, preview the reload, confirm the risks, reload, and see the values carried over
in the running resource; a compile error, a rename, a resource that changed since the
preview, and a user whose level does not allow it."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from playwright.sync_api import Page

from tests.support.browser import chromium
from tests.ui.browser_steps import (
    PASSWORD,
    Demo,
    Plant,
    button_enabled,
    choose,
    confirm,
    field,
    log_in_to_resource,
    open_as,
    open_demo_as_admin,
    shoot,
    text_area,
    text_of,
    value,
    wait_for_text,
    wait_until,
)

pytestmark = pytest.mark.browser
WAIT_MS = 30_000


def tank_source(tmp_path: Path) -> Path:
    """The demo's project as `padt demo` copied it into its state folder (= tmp_path)."""
    return tmp_path / "project" / "tank.st"


def edit(path: Path, old: str, new: str) -> None:
    """What the engineer does in an editor."""
    text = path.read_text(encoding="utf-8")
    assert old in text, old
    path.write_text(text.replace(old, new), encoding="utf-8")


PREVIEW_S = 60  # two compiles in two processes, on a machine that may be busy


def preview(page: Page) -> None:
    page.get_by_role("button", name="Preview", exact=True).click()
    wait_until(
        "the preview is done",
        lambda: page.locator('[data-testid="preview-progress"]').count() == 0,
        timeout_s=PREVIEW_S,
    )


def wait_for_shown(page: Page, selector: str, wanted: str) -> None:
    """Like wait_for_text, for what only a preview brings: absent until then."""
    shown = page.locator(selector)
    wait_until(
        f"{selector} shows {wanted!r}",
        lambda: shown.count() > 0 and shown.first.inner_text() == wanted,
        timeout_s=PREVIEW_S,
    )


def wait_for_fate(page: Page, path: str, wanted: str) -> None:
    wait_for_shown(page, f'[data-fate="{path}"]', wanted)


def fate(page: Page, path: str) -> str:
    return text_of(page, f'[data-fate="{path}"]')


def count(page: Page, fate_name: str) -> str:
    return text_of(page, f'[data-count="{fate_name}"]')


def falling_level(page: Page, variable: str) -> int:
    """Wait until the pump rests and the level falls, well between the high and the low
    level, and return it. In that phase the pump's state carried over and one started
    afresh (the pump on) cannot be mistaken for each other; and the plant drains the tank
    for some 10 s more (3 l per 100 ms) before the pump may restart."""
    page.get_by_role("tab", name="Online test").click()
    wait_until(
        "the pump is off and the level between 780 and 550",
        lambda: (
            value(page, "TankControl.pump") == "FALSE" and 550 < int(value(page, variable)) < 780
        ),
        timeout_s=60,
    )
    return int(value(page, variable))


def assert_carried_over(page: Page, variable: str, before: int) -> None:
    """The program's state went on from where it was: the pump still resting, the level
    (the plant's) below what it was before the reload (a fresh start would turn the pump
    on, and the tank would fill)."""
    page.get_by_role("tab", name="Online test").click()
    wait_until(f"{variable} is shown", lambda: page.locator(f'[data-var="{variable}"]').count() > 0)
    assert value(page, "TankControl.pump") == "FALSE"
    after = int(value(page, variable))
    assert after < before, (before, after)


def test_preview_and_reload_a_new_variable_keeps_the_running_values(
    demo: Demo, tmp_path: Path
) -> None:
    source = tank_source(tmp_path)
    with chromium() as browser:
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        open_demo_as_admin(page, demo)
        old_crc = text_of(page, '[data-testid="resource-crc"]')
        page.get_by_role("tab", name="Reload").click()

        # a typing error: the preview shows where, with the compiler's code
        edit(source, "level := tankLevel;", "level := tankLvel;")
        preview(page)
        assert "No preview (compile)" in text_of(page, '[data-testid="preview-error"]')
        diagnostic = text_of(page, '[data-testid="diagnostic"]')
        assert "tank.st:20:12" in diagnostic and "E0201" in diagnostic, diagnostic
        assert "'tankLvel' is not declared" in diagnostic
        assert not button_enabled(page, "Reload")
        shoot(page, "reload-compile-error-1400")

        # corrected, and a new variable: the low alarm's limit becomes a setting
        edit(source, "level := tankLvel;", "level := tankLevel;")
        edit(
            source,
            "  alarmLow : BOOL;",
            "  alarmLevel : INT := 100;     (* alarmLow below this *)\n  alarmLow : BOOL;",
        )
        edit(source, "alarmLow := level < 100;", "alarmLow := level < alarmLevel;")
        preview(page)
        wait_for_fate(page, "TankControl.alarmLevel", "new")
        assert count(page, "new") == "1 new"
        assert count(page, "deleted") == "0 deleted"
        assert count(page, "initialised") == "0 initialised"
        kept = int(count(page, "kept").split()[0])
        assert kept > 5
        assert fate(page, "TankControl.level") == "kept"
        assert text_of(page, '[data-testid="crc-running"]') == old_crc
        new_crc = text_of(page, '[data-testid="crc-new"]')
        assert re.fullmatch(r"[0-9A-F]{8}", new_crc) and new_crc != old_crc
        assert text_of(page, '[data-testid="reload-programs"]') == "changed TankControl"
        assert "Nothing to confirm" in text_of(page, '[data-testid="risks"]')
        # the filter: only the new variable
        choose(page, "Show", "new")
        wait_until(
            "only new variables are listed",
            lambda: page.locator("[data-fate]").count() == 1,
        )
        choose(page, "Show", "all")
        wait_until("every variable is listed", lambda: page.locator("[data-fate]").count() > 5)
        shoot(page, "reload-preview-1400")

        # the budget of the switch-over: a field that is no number disables Reload; a
        # watchdog below the configured one is refused by the resource, a higher one taken
        page.get_by_text("Budget of the switch-over").click()
        field(page, "Watchdog for the reload (ms)").fill("lots")
        wait_until(
            "the field's error is said",
            lambda: "'lots' is no number" in text_of(page, '[data-testid="budget-errors"]'),
        )
        shoot(page, "reload-budget-error-1400")
        wait_until("Reload is disabled", lambda: not button_enabled(page, "Reload"))
        assert "budget of the switch-over" in text_of(page, '[data-testid="reload-disabled"]')
        field(page, "Watchdog for the reload (ms)").fill("1")
        wait_until("Reload is enabled", lambda: button_enabled(page, "Reload"))
        page.get_by_role("button", name="Reload", exact=True).click()
        confirm(page, "For the cycle of the switch-over: watchdog 1 ms")
        wait_until(
            "the resource refuses a lower watchdog",
            lambda: page.get_by_text("may only raise it").count() > 0,
            timeout_s=30,
        )
        assert text_of(page, '[data-testid="resource-crc"]') == old_crc
        field(page, "Watchdog for the reload (ms)").fill("5000")

        before = falling_level(page, "TankControl.level")
        page.get_by_role("tab", name="Reload").click()
        wait_until("Reload is enabled", lambda: button_enabled(page, "Reload"))
        page.get_by_role("button", name="Reload", exact=True).click()
        dialog = page.get_by_role("dialog")
        dialog.wait_for(timeout=WAIT_MS)
        for named in ("Tank1", old_crc, new_crc, "watchdog 5000 ms"):
            assert named in dialog.inner_text()
        confirm(page, "Tank1")
        shoot(page, "reload-running-1400")  # most often still compiling or switching over
        wait_for_text(page, '[data-testid="reload-new-crc"]', new_crc, timeout_s=30)
        assert re.fullmatch(r"\d+\.\d{3} ms", text_of(page, '[data-testid="reload-pause"]'))
        backup = text_of(page, '[data-testid="reload-backup"]')
        assert Path(backup).is_file() and backup.startswith(str(tmp_path / "backups"))
        wait_for_text(page, '[data-testid="resource-crc"]', new_crc)
        assert "preview again" in text_of(page, '[data-testid="reload-disabled"]')
        shoot(page, "reload-done-1400")

        # the new variable with its initial value; the level carried over
        assert_carried_over(page, "TankControl.level", before)
        wait_for_text(page, '[data-var="TankControl.alarmLevel"]', "100")


def test_a_rename_keeps_its_value_a_deletion_is_confirmed_and_a_stale_preview_is_refused(
    demo: Demo, tmp_path: Path
) -> None:
    source = tank_source(tmp_path)
    text = source.read_text(encoding="utf-8")
    # the engineer renames the level, drops the low alarm and narrows the pump start counter
    text = text.replace("  alarmLow : BOOL;             (* level critically low *)\n", "")
    text = text.replace("alarmLow := level < 100;\n", "")
    text = re.sub(r"\blevel\b", "measuredLevel", text)
    text = text.replace("pumpStarts : DINT;", "pumpStarts : INT;")
    source.write_text(text, encoding="utf-8")
    with chromium() as browser:
        page = browser.new_page(viewport={"width": 1920, "height": 1080})
        other = browser.new_page(viewport={"width": 1400, "height": 900})
        for each in (page, other):
            open_demo_as_admin(each, demo)
            each.get_by_role("tab", name="Reload").click()
        old_crc = text_of(page, '[data-testid="resource-crc"]')

        # without a rename map the level is lost and a new one starts at 500
        preview(page)
        wait_for_fate(page, "TankControl.measuredLevel", "new")
        assert fate(page, "TankControl.level") == "deleted"
        assert fate(page, "TankControl.alarmLow") == "deleted"
        assert count(page, "deleted") == "2 deleted"
        assert "2 values deleted" in page.locator('[data-testid="risk"]').all_inner_texts()[1]
        # DINT to INT does not convert every value: the initial value is taken
        assert fate(page, "TankControl.pumpStarts") == "initialised"
        starts = page.locator('tr:has([data-fate="TankControl.pumpStarts"])').inner_text()
        assert "DINT → INT" in starts

        # an invalid line is shown at the field and holds the preview back
        text_area(page, "Renames").fill("TankControl.level => measuredLevel")
        wait_for_text(
            page,
            '[data-testid="rename-errors"]',
            "line 1: 'TankControl.level => measuredLevel' is not old -> new",
        )
        assert not button_enabled(page, "Preview")
        assert not button_enabled(page, "Reload")
        # the map corrected: the preview comes again by itself
        for each in (page, other):
            text_area(each, "Renames").fill("TankControl.level -> TankControl.measuredLevel")
        preview(other)
        for each in (page, other):
            wait_for_fate(each, "TankControl.measuredLevel", "kept")
            wait_for_shown(each, '[data-count="deleted"]', "1 deleted")
        row = page.locator('tr:has([data-fate="TankControl.measuredLevel"])').inner_text()
        assert "the value of TankControl.level" in row
        risks = page.locator('[data-testid="risk"]').all_inner_texts()
        assert "1 value initialised" in risks[0] and "TankControl.pumpStarts" in risks[0]
        assert "1 value deleted" in risks[1] and "TankControl.alarmLow" in risks[1]
        reason = text_of(page, '[data-testid="reload-disabled"]')
        assert "tick each risk above (2 of 2 not ticked)" in reason
        page.get_by_label("Accept: 1 value deleted", exact=True).check()
        wait_for_text(
            page,
            '[data-testid="reload-disabled"]',
            "Disabled: tick each risk above (1 of 2 not ticked)",
        )
        assert not button_enabled(page, "Reload")
        page.get_by_label("Accept: 1 value initialised", exact=True).check()
        other.get_by_label("Accept: 1 value deleted", exact=True).check()
        other.get_by_label("Accept: 1 value initialised", exact=True).check()
        wait_until("Reload is enabled", lambda: button_enabled(page, "Reload"))
        wait_until("Reload is enabled there too", lambda: button_enabled(other, "Reload"))
        shoot(page, "reload-preview-1920")

        before = falling_level(page, "TankControl.level")
        page.get_by_role("tab", name="Reload").click()
        page.get_by_role("button", name="Reload", exact=True).click()
        confirm(page, old_crc)
        new_crc = text_of(page, '[data-testid="crc-new"]')
        wait_for_text(page, '[data-testid="reload-new-crc"]', new_crc, timeout_s=30)
        wait_for_text(page, '[data-testid="resource-crc"]', new_crc)
        shoot(page, "reload-done-1920")
        assert_carried_over(page, "TankControl.measuredLevel", before)
        assert page.locator('[data-var="TankControl.level"]').count() == 0
        assert page.locator('[data-var="TankControl.alarmLow"]').count() == 0
        assert value(page, "TankControl.pumpStarts") == "0"  # its initial value

        # the other browser's preview was made against the configuration before: its
        # reload is refused by the resource, which runs another one by now
        wait_until(
            "the other browser sees the resource moved on",
            lambda: other.locator('[data-testid="crc-moved"]').count() > 0,
        )
        other.get_by_role("button", name="Reload", exact=True).click()
        confirm(other, old_crc)
        refused = other.locator('[data-testid="reload-refused"]')
        refused.wait_for(timeout=WAIT_MS)
        assert "changed" in refused.inner_text(), refused.inner_text()
        # also in one line under the button, where the user is
        assert "Reload refused: changed" in text_of(other, '[data-testid="reload-outcome"]')
        shoot(other, "reload-refused-1400")
        assert text_of(other, '[data-testid="resource-crc"]') == new_crc


def test_a_read_user_sees_reload_disabled_with_the_reason(plant: Plant) -> None:
    with chromium() as browser:
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        open_as(page, plant, "viewer")
        log_in_to_resource(page, "viewer", PASSWORD)
        wait_for_text(page, '[data-testid="resource-state"]', "RUN", timeout_s=30)
        page.get_by_role("tab", name="Reload").click()
        reason = "needs read-write at the resource; viewer is read"
        wait_until(
            "Reload says why it is disabled",
            lambda: reason in text_of(page, '[data-testid="reload-disabled"]'),
        )
        assert reason in text_of(page, '[data-testid="preview-disabled"]')
        assert not button_enabled(page, "Preview")
        assert not button_enabled(page, "Reload")
        shoot(page, "reload-read-user-1400")
