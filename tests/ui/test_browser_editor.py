"""The code editor in the centre of the workspace as an engineer uses it, through
`padt demo` and headless Chromium: a file opened from the project tree; an error typed is
underlined and listed in the problems panel, whose row leads to it; completion offers the
variables and the members of a function block and inserts one; hover tells a variable's
declaration; F12 goes to it and Alt+Left comes back; Shift+F12 lists the references;
Ctrl+S saves the file on disk; a file changed on disk while open is offered, not
overwritten; a second browser's save of the same file is a conflict; a read-only user
opens but cannot save."""

from __future__ import annotations

from pathlib import Path

import pytest
from playwright.sync_api import Page

from frontend.editor import page_push
from tests.support.browser import chromium
from tests.ui.browser_steps import (
    PASSWORD,
    Demo,
    Plant,
    log_in,
    log_in_to_resource,
    shoot_both,
    wait_until,
)

pytestmark = pytest.mark.browser

TANK = "tank.st"


def open_in_editor(page: Page, url: str, user: str, password: str) -> None:
    """Log in and open TankControl from the project tree."""
    page.goto(url)
    page.get_by_role("button", name="Log in", exact=True).wait_for(timeout=30_000)
    log_in(page, user, password)
    entry = page.locator('[data-tree^="file:TankControl@"]').first
    entry.wait_for(timeout=30_000)
    page.locator("#padt-editor .cm-content").wait_for(timeout=30_000)
    # the workspace may have opened it at login, the cursor at its declaration already:
    # moved away first, so that only the click's own effect can bring it there (a click
    # that came later would move a cursor placed for typing)
    if "PROGRAM TankControl" in editor_text(page):
        page.evaluate(f"window.padtEditor.select({TANK!r}, 1, 1)")

    def moved() -> bool:
        # the page's report of a click can be lost in viser's sender (it keeps only the
        # newest message within 50 ms): clicked again, as a user does
        entry.click()
        page.wait_for_timeout(3_000)
        lines = editor_text(page).split("\n")
        if "PROGRAM TankControl" not in lines:
            return False
        return cursor_line(page) == lines.index("PROGRAM TankControl") + 1

    wait_until("the click moved the cursor to TankControl", moved, timeout_s=60)


def dismiss_notifications(page: Page) -> None:
    """Close viser's notifications (a note on the left may stand where a click goes)."""
    page.evaluate(
        "document.querySelectorAll('.mantine-Notification-closeButton').forEach(b => b.click())"
    )


def editor_text(page: Page) -> str:
    text: str = page.evaluate("window.padtEditor.view.state.doc.toString()")
    return text


def put_cursor(page: Page, line: int, col: int) -> None:
    """The cursor at line:col (col past the end: the line's end), as a click there does."""
    page.evaluate(f"window.padtEditor.select({TANK!r}, {line}, {col})")


def cursor_line(page: Page) -> int:
    line: int = page.evaluate(
        "(() => { const s = window.padtEditor.view.state;"
        " return s.doc.lineAt(s.selection.main.head).number; })()"
    )
    return line


def line_of(page: Page, number: int) -> str:
    line: str = page.evaluate(f"window.padtEditor.view.state.doc.line({number}).text")
    return line


def problems(page: Page) -> str:
    return page.locator('[data-testid="problems-list"]').inner_text()


def test_files_reopened_at_login_leave_the_keyboard_where_the_user_types(demo: Demo) -> None:
    """The workspace reopens the user's files after the login; typing the resource's
    password meanwhile must not land in the code."""
    with chromium() as browser:
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        page.goto(demo.url)
        log_in(page, "admin", demo.password)
        page.get_by_role("button", name="Log in to resource").wait_for(timeout=30_000)
        page.locator("#padt-editor .cm-content").wait_for(timeout=30_000)
        wait_until("the file is back", lambda: "PROGRAM TankControl" in editor_text(page))
        in_editor = "document.activeElement.closest('#padt-editor') !== null"
        assert not page.evaluate(in_editor)
        before = editor_text(page)
        page.keyboard.type("secret-typed-here")
        assert editor_text(page) == before


def test_an_error_typed_is_underlined_listed_and_found_again(demo: Demo) -> None:
    with chromium() as browser:
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        open_in_editor(page, demo.url, "admin", demo.password)
        assert "No problems." in problems(page)
        assert line_of(page, 20).strip() == "level := tankLevel;"
        put_cursor(page, 20, 100)
        page.keyboard.press("Backspace")  # the `;`
        page.keyboard.type(" + lvl;")  # a name nothing declares
        page.locator("#padt-editor .cm-lintRange-error").first.wait_for(timeout=10_000)
        wait_until("the problem is listed", lambda: "tank.st:20:" in problems(page))
        row = page.locator('[data-testid="problems-list"] tr', has_text="tank.st:20:")
        assert "lvl" in row.inner_text()
        dismiss_notifications(page)
        shoot_both(page, "editor-diagnostics")
        put_cursor(page, 1, 1)
        row.click()
        wait_until("the cursor is at the problem", lambda: cursor_line(page) == 20)
        # fixed with completion: the variable offered, chosen with Enter
        page.keyboard.press("End")
        for _ in range(4):
            page.keyboard.press("Backspace")  # `lvl;`
        page.keyboard.type("tankLe")
        menu = page.locator(".cm-tooltip-autocomplete")
        menu.wait_for(timeout=10_000)
        chosen = menu.locator("li[aria-selected=true]")
        first = "tankLevel"
        wait_until("tankLevel is offered first", lambda: chosen.inner_text().startswith(first))
        chosen.click()
        wait_until("inserted", lambda: line_of(page, 20).strip().endswith("tankLevel"))
        page.keyboard.type(";")
        assert line_of(page, 20).strip() == "level := tankLevel + tankLevel;"
        wait_until("no problem any more", lambda: "No problems." in problems(page))
        assert page.locator("#padt-editor .cm-lintRange-error").count() == 0


def test_completion_offers_the_members_of_a_function_block(demo: Demo) -> None:
    with chromium() as browser:
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        open_in_editor(page, demo.url, "admin", demo.password)
        put_cursor(page, 20, 100)
        page.keyboard.press("Enter")
        page.keyboard.type("  pumpStarts := refillDelay.")
        wait_until("typed", lambda: line_of(page, 21).strip() == "pumpStarts := refillDelay.")
        menu = page.locator(".cm-tooltip-autocomplete")
        menu.wait_for(timeout=30_000)  # the language service answers off the page's thread
        wait_until("TON's members are offered", lambda: "ET" in menu.inner_text())
        offered = menu.inner_text()
        for member in ("IN", "PT", "Q", "ET"):
            assert member in offered
        dismiss_notifications(page)
        shoot_both(page, "editor-completion")
        page.keyboard.type("E")
        chosen = menu.locator("li[aria-selected=true]")
        wait_until("ET is offered first", lambda: chosen.inner_text().startswith("ET"))
        chosen.click()
        wait_until("inserted", lambda: line_of(page, 21).strip() == "pumpStarts := refillDelay.ET")


def test_hover_definition_back_and_references(demo: Demo) -> None:
    with chromium() as browser:
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        open_in_editor(page, demo.url, "admin", demo.password)
        assert line_of(page, 22).startswith("IF level >= highLevel")
        place = page.evaluate(
            "(() => { const v = window.padtEditor.view;"
            " return v.coordsAtPos(v.state.doc.line(22).from + 5); })()"
        )
        page.mouse.move(place["left"] + 2, place["top"] + 4)
        hover = page.locator('[data-testid="editor-hover"]')
        hover.wait_for(timeout=10_000)
        said = hover.inner_text()
        assert "level : INT := 500" in said
        assert "the tank level" in said  # the declaration's comment
        put_cursor(page, 22, 6)
        page.keyboard.press("F12")
        wait_until("at the declaration", lambda: cursor_line(page) == 8)
        page.keyboard.press("Alt+ArrowLeft")
        wait_until("back where it was", lambda: cursor_line(page) == 22)
        page.keyboard.press("Shift+F12")
        listed = page.locator('[data-testid="references-list"]')
        listed.wait_for(timeout=10_000)
        wait_until("the references are listed", lambda: "tank.st:8:" in listed.inner_text())
        rows = listed.inner_text()
        for line in (8, 20, 22, 25, 30):
            assert f"tank.st:{line}:" in rows


def test_save_then_a_change_on_disk_is_offered_and_a_second_browser_conflicts(
    demo: Demo, tmp_path: Path
) -> None:
    on_disk = tmp_path / "project" / TANK
    with chromium() as browser:
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        open_in_editor(page, demo.url, "admin", demo.password)
        other = browser.new_page(viewport={"width": 1400, "height": 900})
        open_in_editor(other, demo.url, "admin", demo.password)
        # the first browser saves: the file on disk changes
        put_cursor(page, 16, 100)
        page.keyboard.type("  (* saved from the browser *)")
        page.keyboard.press("Control+s")
        wait_until("the file is saved", lambda: "saved from the browser" in on_disk.read_text())
        # the second browser had the old text: its save is refused, and offered
        put_cursor(other, 16, 100)
        other.keyboard.type("  (* the second browser *)")
        other.keyboard.press("Control+s")
        note = other.locator('[data-testid="editor-note"]')
        wait_until("the conflict is offered", lambda: "changed on disk" in note.inner_text())
        assert "second browser" not in on_disk.read_text()
        # another tool writes the file: the first browser is told, its text kept
        on_disk.write_text(on_disk.read_text().replace("saved from the browser", "by vim"))
        mine = page.locator('[data-testid="editor-note"]')
        wait_until("the change on disk is offered", lambda: "changed on disk" in mine.inner_text())
        assert "saved from the browser" in editor_text(page)
        dismiss_notifications(page)
        page.locator('#padt-editor [data-action="reload"]').click()
        wait_until("the disk's text is loaded", lambda: "by vim" in editor_text(page))
        # the second browser keeps its own and saves knowingly
        dismiss_notifications(other)
        other.locator('#padt-editor [data-action="keep"]').click()
        wait_until(
            "the offer is gone",
            lambda: not other.locator('[data-testid="editor-note"]').is_visible(),
        )
        other.keyboard.press("Control+s")
        wait_until("the second save is done", lambda: "second browser" in on_disk.read_text())


def test_a_read_only_user_opens_but_cannot_save(plant: Plant) -> None:
    with chromium() as browser:
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        open_in_editor(page, plant.url, "guest", PASSWORD)
        note = page.locator('[data-testid="editor-note"]')
        wait_until("the reason is shown", lambda: "read-only" in note.inner_text())
        assert page.locator('#padt-editor [data-action="save"]').is_disabled()
        before = editor_text(page)
        put_cursor(page, 20, 100)
        page.keyboard.type("xyz")
        assert editor_text(page) == before  # nothing typed goes in


HELPER = """FUNCTION_BLOCK Counter
VAR_INPUT
  step : DINT;
END_VAR
VAR_OUTPUT
  total : DINT;
END_VAR
total := total + step;
END_FUNCTION_BLOCK
"""


def test_rename_across_the_open_file_and_a_file_on_disk(demo: Demo, tmp_path: Path) -> None:
    helper = tmp_path / "project" / "helper.st"
    helper.write_text(HELPER)
    with chromium() as browser:
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        open_in_editor(page, demo.url, "admin", demo.password)
        # the declaration put in as an edit at the end of line 16, not typed: a reveal of
        # TankControl still on its way from the login may move the cursor (the rename
        # below places the cursor again on each try)
        page.evaluate(
            "(() => { const v = window.padtEditor.view; const end = v.state.doc.line(16).to;"
            " v.dispatch({changes: {from: end, insert: '\\n  starts : Counter;'}}); })()"
        )
        assert line_of(page, 17).strip() == "starts : Counter;"
        box = page.locator('[data-testid="rename-input"]')

        def rename_offered() -> bool:
            """F2 asks the server what stands there; while the typed line has not reached
            the analysis yet it answers "nothing to rename": then F2 again, as a user would."""
            put_cursor(page, 17, 14)
            page.keyboard.press("F2")
            box.wait_for(timeout=3_000)  # a timeout here is "not yet" to wait_until
            return True

        wait_until("F2 offers the rename", rename_offered, 60)
        assert box.input_value() == "Counter"
        box.fill("PumpCounter")
        box.press("Enter")
        status = page.locator('[data-testid="editor-status"]')
        wait_until("the rename is reported", lambda: "Renamed Counter" in status.inner_text())
        assert "2 edits in 2 files" in status.inner_text()
        assert line_of(page, 17).strip() == "starts : PumpCounter;"
        assert helper.read_text().startswith("FUNCTION_BLOCK PumpCounter\n")
        # the open file's edit is the user's, to save or undo
        page.keyboard.press("Control+z")
        wait_until("undone", lambda: line_of(page, 17).strip() == "starts : Counter;")


def live_values(page: Page) -> dict[int, str]:
    """The values beside each line in view: line number -> what is shown."""
    shown: dict[str, str] = page.evaluate(
        "(() => { const v = window.padtEditor.view; const out = {};"
        " window.padtEditor.shadow.querySelectorAll('.padt-live').forEach(e => {"
        " out[v.state.doc.lineAt(v.posAtDOM(e)).number] = e.textContent; }); return out; })()"
    )
    return {int(line): text for line, text in shown.items()}


def hover_over(page: Page, line: int, col: int) -> str:
    place = page.evaluate(
        "(() => { const v = window.padtEditor.view;"
        f" return v.coordsAtPos(v.state.doc.line({line}).from + {col - 1}); }})()"
    )
    for step in range(2):  # as a hand moves: more than one event
        page.mouse.move(place["left"] + 2 + step, place["top"] + 4)
    hover = page.locator('[data-testid="editor-hover"]')
    hover.wait_for(timeout=10_000)
    return hover.inner_text()


def test_live_values_beside_the_lines_of_the_running_source(demo: Demo) -> None:
    with chromium() as browser:
        page = browser.new_page(viewport={"width": 1920, "height": 1080})
        page.goto(demo.url)
        page.get_by_role("button", name="Log in", exact=True).wait_for(timeout=30_000)
        log_in(page, "admin", demo.password)
        log_in_to_resource(page, "admin", demo.password)
        page.locator('[data-tree^="file:TankControl@"]').first.click(timeout=30_000)
        page.locator("#padt-editor .cm-content").wait_for(timeout=30_000)
        wait_until(
            "values beside the lines",
            lambda: live_values(page).get(13) == "restartDelay = T#2s",  # "..." until it comes
        )
        shown = live_values(page)
        assert shown[20].startswith("level = ") and "tankLevel = " in shown[20]
        assert shown[13] == "restartDelay = T#2s"
        assert "refillDelay.IN = " in shown[25] and "restartDelay = T#2s" in shown[25]
        assert 2 not in shown and 33 not in shown  # a comment, after END_PROGRAM: nothing
        # the bottom panel lists them too, one row a variable
        page.locator('#padt-editor [data-bottom="live"]').click()
        row = page.locator('#padt-editor [data-live="restartDelay"]')
        wait_until("restartDelay is listed", lambda: row.inner_text() == "restartDelay\tT#2s")
        level = page.locator('#padt-editor [data-live="tankLevel"]')
        wait_until("tankLevel is listed", lambda: level.inner_text().startswith("tankLevel\t"))
        dismiss_notifications(page)
        shoot_both(page, "editor-live-values")
        # hover tells the value now as well
        said = hover_over(page, 22, 5)
        assert "level : INT := 500" in said and "value now: " in said
        # the level moves with the plant: the values beside the lines follow it
        first = live_values(page)[20]
        wait_until(
            "the level moves", lambda: live_values(page).get(20, first) != first, timeout_s=60
        )
        # an edit that moves the lines: they are no longer the running source, no values
        put_cursor(page, 18, 1)
        page.keyboard.press("Enter")
        wait_until("no values for an edited POU", lambda: not live_values(page))
        page.keyboard.press("Control+z")
        wait_until("values again once undone", lambda: 20 in live_values(page))


def test_without_the_editors_code_the_centre_says_how_to_get_it(
    plant: Plant, monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    monkeypatch.setattr(page_push, "BUNDLE", tmp_path / "missing.js")
    with chromium() as browser:
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        page.goto(plant.url)
        page.get_by_role("button", name="Log in", exact=True).wait_for(timeout=30_000)
        log_in(page, "viewer", PASSWORD)
        said = page.locator("#padt-editor-missing")
        said.wait_for(timeout=30_000)
        assert "scripts/install-codemirror.sh" in said.inner_text()
