"""The Tests screen as an engineer uses it, in headless Chromium: the demo's unit tests run
from `padt demo`, all passing; then a copy of the demo with a wrong expectation: its failure
shows the assert's message, expected and actual and its place, a click on the place opens
the test file in the editor at the failing line; one test chosen from the list runs alone."""

from __future__ import annotations

import shutil
import threading
import time
from collections.abc import Iterator
from contextlib import ExitStack, contextmanager
from pathlib import Path

import pytest
from playwright.sync_api import Page

from backend.engineering.padt_accounts import PadtAccounts, write_accounts
from backend.engineering.project import demo_project_path
from backend.engineering.resource_directory import ResourceDirectory
from backend.engineering.watch_lists import WatchLists
from frontend.app import PadtUi
from frontend.screen_registry import Now
from frontend.screens.tests import Tests
from frontend.ui_context import UiContext
from runtime.contract.accounts import hash_password
from runtime.contract.artifact import UserAccount
from runtime.contract.session import open_client
from tests.conftest import free_port
from tests.support.browser import chromium
from tests.support.runtime_process import router
from tests.ui.browser_steps import (
    PASSWORD,
    START_S,
    Demo,
    log_in,
    open_tab,
    shoot_both,
    text_of,
    wait_for_text,
    wait_until,
)

pytestmark = pytest.mark.browser

TEST_FILE = "test/tank_test.st"
RUN_S = 120  # a run: a process started, the project compiled with its tests, both tiers
# the demo's low alarm test with a wrong expectation (a level of 100 l is not critical)
RIGHT = "ASSERT_FALSE(TankControl.alarmLow, '100 l is not critical');"
WRONG = "ASSERT_TRUE(TankControl.alarmLow, 'critically low at 100 l');"
STATUS = '[data-testid="tests-status"]'


def open_tests(page: Page, url: str, password: str) -> None:
    page.goto(url)
    log_in(page, "admin", password)
    page.get_by_role("tab", name="Tests").wait_for(timeout=START_S * 1000)
    open_tab(page, "Tests")


def run(page: Page, button: str, wanted: str) -> None:
    """Press a Run button once the list is there, and wait for the totals (then the time)."""
    pressed = page.get_by_role("button", name=button, exact=True)
    wait_until(f"{button} can be pressed", pressed.is_enabled, timeout_s=RUN_S)
    pressed.click()
    shown: list[str] = []  # what the status said last, for the message if it never holds

    def totals() -> bool:
        shown[:] = [text_of(page, STATUS)]
        return shown[0].startswith(wanted)

    try:
        wait_until(f"the totals say {wanted!r}", totals, timeout_s=RUN_S)
    except AssertionError as never:
        raise AssertionError(f"{never}; the status says {shown}") from None


def editor_at(page: Page) -> tuple[str, int, str]:
    """The file in front in the editor, the cursor's line and the highlighted line's text."""
    found: list[object] = page.evaluate(
        "(() => { const e = window.padtEditor; const s = e.view.state;"
        " const line = s.doc.lineAt(s.selection.main.head);"
        " const lit = e.view.dom.querySelector('.cm-activeLine');"
        " return [e.current, line.number, lit ? lit.textContent : '']; })()"
    )
    return str(found[0]), int(str(found[1])), str(found[2])


def test_the_demos_tests_all_pass_from_the_tests_screen(demo: Demo) -> None:
    with chromium() as browser:
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        open_tests(page, demo.url, demo.password)
        wait_for_text(page, STATUS, "6 tests in 1 suite: not run yet.", timeout_s=RUN_S)
        shoot_both(page, "tests-demo-listed")
        run(page, "Run all", "6 passed of 6 tests (native and python) in ")
        rows = page.locator('[data-testid="tests-results"] tr[data-test]')
        assert rows.count() == 6
        assert set(rows.evaluate_all("rs => rs.map(r => r.dataset.status)")) == {"passed"}
        assert "✓ PASS" in text_of(page, 'tr[data-test="TankTests.TestTheLowAlarm"]')
        assert "all passing" in text_of(page, 'tr[data-suite="TankTests"]')
        shoot_both(page, "tests-demo-passed")


@contextmanager
def serving(tmp_path: Path, tests: str) -> Iterator[str]:
    """The UI serving a copy of the demo project with `tests` as its test file."""
    folder = tmp_path / "copy"
    shutil.copytree(demo_project_path(), folder)
    (folder / TEST_FILE).write_text(tests, encoding="utf-8")
    accounts_file = tmp_path / "padt-accounts.json"
    admin = UserAccount("admin", "security-administrator", hash_password(PASSWORD))
    write_accounts(accounts_file, (admin,))
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    with ExitStack() as stack:
        stack.enter_context(router(endpoint))
        session = open_client(endpoint)
        stack.callback(session.close)
        directory = ResourceDirectory(session)
        accounts = PadtAccounts(accounts_file, time.monotonic_ns)
        lists = WatchLists(tmp_path / "watch-lists.json")
        projects = {"copy": folder}
        context = UiContext(directory, accounts, endpoint, lists, projects, tmp_path / "bak")
        ui = PadtUi(context, port=free_port())
        stack.callback(ui.close)
        yield ui.url


@pytest.fixture
def failing_ui(tmp_path: Path) -> Iterator[str]:
    """A copy of the demo project whose low alarm test expects wrongly."""
    text = (demo_project_path() / TEST_FILE).read_text(encoding="utf-8")
    assert RIGHT in text
    with serving(tmp_path, text.replace(RIGHT, WRONG)) as url:
        yield url


def test_the_run_buttons_wait_until_the_tests_are_read(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Every screen is made at the login and drawn once its tab is open. Under load that
    drawing comes late: a Run button pressable before it took a press that ran nothing (seen
    in CI as a run that never began). Here the screen's first drawing is held back."""
    drawn = threading.Event()
    draw = Tests.refresh

    def late(screen: Tests, now: Now) -> None:
        drawn.wait(RUN_S)
        draw(screen, now)

    monkeypatch.setattr(Tests, "refresh", late)
    tests = (demo_project_path() / TEST_FILE).read_text(encoding="utf-8")
    with serving(tmp_path, tests) as url, chromium() as browser:
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        page.goto(url)
        log_in(page, "admin", PASSWORD)
        page.get_by_role("tab", name="Tests").wait_for(timeout=START_S * 1000)
        open_tab(page, "Tests")
        for name in ("Run all", "Run suite", "Run test", "Run with coverage"):
            button = page.get_by_role("button", name=name, exact=True)
            assert button.is_disabled(), f"{name} can be pressed before the tests are read"
        drawn.set()
        wait_for_text(page, STATUS, "6 tests in 1 suite: not run yet.", timeout_s=RUN_S)
        run(page, "Run all", "6 passed of 6 tests (native and python) in ")


def test_a_failure_shows_expected_and_actual_and_opens_at_its_line(failing_ui: str) -> None:
    wrong_line = 1 + (demo_project_path() / TEST_FILE).read_text().split("\n").index(RIGHT)
    place = f"{TEST_FILE}:{wrong_line}:1"
    with chromium() as browser:
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        open_tests(page, failing_ui, PASSWORD)
        run(page, "Run all", "5 passed, 1 failed of 6 tests (native and python) in ")
        failed = 'tr[data-test="TankTests.TestTheLowAlarm"]'
        assert page.locator(failed).get_attribute("data-status") == "failed"
        assert "✗ FAIL" in text_of(page, failed)
        failure = text_of(page, '[data-failure="TankTests.TestTheLowAlarm"]')
        assert "ASSERT_TRUE failed: critically low at 100 l" in failure, failure
        assert "expected TRUE, actual FALSE" in failure and place in failure, failure
        assert "1 failing" in text_of(page, 'tr[data-suite="TankTests"]')
        shoot_both(page, "tests-failure")

        # the place opens the test file in the editor, the cursor on the failing assert
        page.locator(f'[data-place="{place}"]').click()
        wait_until(
            "the editor shows the failing line",
            lambda: (
                editor_at(page)[:2]
                == (
                    TEST_FILE,
                    wrong_line,
                )
            ),
        )
        assert editor_at(page)[2].strip() == WRONG
        tab = page.locator(f'#padt-editor [data-file="{TEST_FILE}"]')
        assert tab.inner_text().startswith("tank_test.st")
        shoot_both(page, "tests-failure-in-editor")

        # one test chosen in the list runs alone; the others keep their results
        page.locator('tr[data-test="TankTests.TestTheLevelFollowsThePlant"] td').nth(1).click()
        wait_until(
            "the test is chosen",
            lambda: (
                page.get_by_label("Test", exact=True).first.input_value()
                == "TestTheLevelFollowsThePlant"
            ),
        )
        run(page, "Run test", "1 passed of 1 test (native and python) in ")
        assert page.locator(failed).get_attribute("data-status") == "failed"


# one test of the demo's: the level is read, the pump never stops nor restarts
ONE_TEST = """FUNCTION_BLOCK TankTests
METHOD TestTheLevelFollowsThePlant
tankLevel := 500;
RUN_CYCLES(1);
ASSERT_EQUAL(500, TankControl.level, 'the level is the plant$'s measurement');
END_METHOD
END_FUNCTION_BLOCK
"""


def shades(page: Page) -> dict[int, tuple[str, str]]:
    """The shaded lines of the file in front: line -> (how, title)."""
    found: list[list[object]] = page.evaluate(
        "(() => { const v = window.padtEditor.view;"
        " return [...v.dom.querySelectorAll('.cm-line[data-coverage]')].map(e =>"
        " [v.state.doc.lineAt(v.posAtDOM(e)).number, e.dataset.coverage, e.title]); })()"
    )
    return {int(str(line)): (str(how), str(title)) for line, how, title in found}


def test_run_with_coverage_shades_the_lines_in_the_editor(tmp_path: Path) -> None:
    tank = (demo_project_path() / "tank.st").read_text(encoding="utf-8").split("\n")
    stop = 1 + tank.index("  pump := FALSE;")  # the high level is never reached
    decided = stop - 1  # IF level >= highLevel THEN: its THEN never taken
    read = 1 + tank.index("  level := tankLevel;")
    with serving(tmp_path, ONE_TEST) as url, chromium() as browser:
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        open_tests(page, url, PASSWORD)
        run(page, "Run with coverage", "1 passed of 1 test (native and python) in ")
        row = text_of(page, '[data-coverage-file="tank.st"]')
        assert "%" in row and "100 %" not in row, row
        page.locator('[data-coverage-file="tank.st"] [data-test-click]').click()
        # tank.st comes to the front at its first line never run
        wait_until(f"tank.st is at line {stop}", lambda: editor_at(page)[:2] == ("tank.st", stop))
        lines = shades(page)
        assert lines[stop] == ("uncovered", "never ran in the tests")
        assert lines[decided][0] == "partial" and "not taken: THEN" in lines[decided][1]
        assert lines[read] == ("covered", "ran 1 time in the tests")
        shoot_both(page, "tests-coverage")
        # a run without coverage takes the shading away
        run(page, "Run all", "1 passed of 1 test (native and python) in ")
        wait_until("no line is shaded", lambda: shades(page) == {})
