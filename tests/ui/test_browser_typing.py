"""What the page's scripts tell the server and what the user does, at the same moment, all
reach it (frontend/page_writer.py): viser's panel sends inputs and presses through one
sender that keeps only the newest message within 50 ms, which the page's scripts do not
use."""

from __future__ import annotations

from collections.abc import Callable

import pytest
from playwright.sync_api import Page

from tests.support.browser import chromium
from tests.ui.browser_steps import (
    Plant,
    field,
    open_online_test,
    wait_until,
)

pytestmark = pytest.mark.browser

NAMES = tuple(f"Line {n}" for n in range(1, 5))
# tree entries and the file each opens
FILES = (
    ("file:TankTests@test/tank_test.st:4", "test/tank_test.st"),
    ("file:tank@tank.st:38", "tank.st"),
)

# In one task of the page, as a browser catching up after a stall handles them: the editor
# tells the server which lines are in view, a file is opened from the project tree (the
# page script's report), the editor tells its lines again; then a name is typed and Create
# list pressed (the field found by its label, as a user finds it).
AT_ONCE = """([name, entry]) => {
  const lines = () => window.padtEditor.send({k: 'view', file: 'tank.st', first: 1, last: 9});
  lines();
  document.querySelector(`[data-tree="${entry}"]`).click();
  lines();
  const label = [...document.querySelectorAll('label')].find(l => l.textContent === 'New list');
  const input = label.closest('.mantine-Flex-root').querySelector('input');
  const set = Object.getOwnPropertyDescriptor(HTMLInputElement.prototype, 'value').set;
  set.call(input, name);
  input.dispatchEvent(new Event('input', {bubbles: true}));
  const buttons = [...document.querySelectorAll('button')];
  buttons.find(b => b.textContent.trim() === 'Create list').click();
}"""


def lists_of(plant: Plant, user: str) -> list[str]:
    """The watch lists `user` has, as the next login offers them."""
    return sorted(found.name for found in plant.ui.context.watch_lists.of(user))


def editor_file(page: Page) -> str:
    found: str = page.evaluate("window.padtEditor ? window.padtEditor.current : ''")
    return found


def file_open(page: Page, file: str) -> Callable[[], bool]:
    return lambda: editor_file(page) == file


def lists_counted(plant: Plant, count: int) -> Callable[[], bool]:
    return lambda: len(lists_of(plant, "viewer")) == count


def test_a_file_opened_while_the_editor_reports_opens_and_a_list_is_created(
    plant: Plant,
) -> None:
    with chromium() as browser:
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        open_online_test(page, plant)
        page.get_by_text("Compose watch lists", exact=True).click()
        name = field(page, "New list")
        name.wait_for()
        wait_until("the editor shows tank.st", lambda: editor_file(page) == "tank.st")
        for number, list_name in enumerate(NAMES, 1):
            entry, file = FILES[(number - 1) % 2]
            page.wait_for_timeout(300)  # the page idle: no message of the user's under way
            page.evaluate(AT_ONCE, [list_name, entry])
            wait_until(f"{file} is open", file_open(page, file))
            wait_until(f"{list_name} is created", lists_counted(plant, number))
            wait_until("the field is empty again", lambda: name.input_value() == "")
        assert lists_of(plant, "viewer") == list(NAMES)
