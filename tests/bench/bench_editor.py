"""The browser's code editor while one types: a minute of typing at about 8 characters a
second in the middle of a 2,000-line file, in headless Chromium against the UI in this
process. Prints the browser's CPU (Chrome's TaskDuration over the minute, from the
DevTools protocol's Performance.getMetrics), the UI server's CPU (this process), and how
long a diagnostic takes to appear after the keystroke that causes it (p50 / p95)."""

from __future__ import annotations

import statistics
import tempfile
import time
from pathlib import Path

from playwright.sync_api import CDPSession, Page

from backend.engineering.padt_accounts import PadtAccounts, write_accounts
from backend.engineering.resource_directory import ResourceDirectory
from backend.engineering.watch_lists import WatchLists
from frontend.app import PadtUi
from frontend.ui_context import UiContext
from runtime.contract.accounts import hash_password
from runtime.contract.artifact import UserAccount
from tests.conftest import free_port
from tests.support.browser import chromium
from tests.support.runtime_process import client_session, router
from tests.ui.browser_steps import log_in, wait_until

LINES = 2000
TYPING_S = 60.0
IDLE_S = 20.0
CHARS_PER_S = 8
ERRORS = 20  # diagnostics timed: an undeclared name typed, then taken back
PASSWORD = "bench-Password-1"
TEXT = "counter := counter + 1; "  # what is typed, over and over


def big_program() -> str:
    """A PROGRAM of LINES lines: declarations, then statements."""
    names = [f"v{n}" for n in range(200)]
    head = ["PROGRAM Big", "VAR", "  counter : DINT;"]
    head += [f"  {name} : INT;" for name in names]
    head.append("END_VAR")
    body = [
        f"{names[n % 200]} := {names[(n + 1) % 200]} + {n % 7};"
        for n in range(LINES - len(head) - 1)
    ]
    return "\n".join([*head, *body, "END_PROGRAM"]) + "\n"


def main() -> None:
    with tempfile.TemporaryDirectory() as temporary:
        folder = Path(temporary) / "bench"
        folder.mkdir()
        (folder / "big.st").write_text(big_program())
        accounts_file = Path(temporary) / "accounts.json"
        account = UserAccount("engineer", "read-write", hash_password(PASSWORD))
        write_accounts(accounts_file, (account,))
        endpoint = f"tcp/127.0.0.1:{free_port()}"
        with router(endpoint), client_session(endpoint) as session:
            context = UiContext(
                ResourceDirectory(session),
                PadtAccounts(accounts_file, time.monotonic_ns),
                endpoint,
                WatchLists(Path(temporary) / "watch-lists.json"),
                {"bench": folder},
            )
            ui = PadtUi(context, port=free_port())
            try:
                _measure(ui.url)
            finally:
                ui.close()


def _measure(url: str) -> None:
    with chromium() as browser:
        page = browser.new_page(viewport={"width": 1920, "height": 1080})
        page.goto(url)
        page.get_by_role("button", name="Log in", exact=True).wait_for(timeout=30_000)
        log_in(page, "engineer", PASSWORD)
        page.locator('[data-tree^="file:Big@"]').first.click(timeout=30_000)
        page.locator("#padt-editor .cm-content").wait_for(timeout=30_000)
        wait_until("the file is open", lambda: _lines(page) == LINES + 1, timeout_s=60)
        middle = LINES // 2
        page.evaluate(f"window.padtEditor.select('big.st', {middle}, 1000)")
        page.keyboard.press("Enter")
        cdp = page.context.new_cdp_session(page)
        cdp.send("Performance.enable")
        before = _task_s(cdp)
        time.sleep(IDLE_S)  # the page alone (viser's canvas draws behind the editor)
        idle_s = _task_s(cdp) - before
        before = _task_s(cdp)
        cpu_before, started = time.process_time(), time.monotonic()
        typed = 0
        while time.monotonic() - started < TYPING_S:
            page.keyboard.type(TEXT[typed % len(TEXT)])
            typed += 1
            time.sleep(max(0.0, started + typed / CHARS_PER_S - time.monotonic()))
        wall = time.monotonic() - started
        browser_s = _task_s(cdp) - before
        server_s = time.process_time() - cpu_before
        page.keyboard.press("Home")  # the typed line cleared: no error left
        page.keyboard.press("Shift+End")
        page.keyboard.press("Delete")
        errors = page.locator("#padt-editor .cm-lintRange-error")
        wait_until("no underline", lambda: errors.count() == 0, timeout_s=60)
        delays = [_diagnostic_delay(page) for _ in range(ERRORS)]
    print(f"editor: typing {typed} characters in {wall:.0f} s into a {LINES:,}-line file")
    print(
        f"  browser CPU (Chrome TaskDuration): {100 * browser_s / wall:.1f} % of one core "
        f"typing, {100 * idle_s / IDLE_S:.1f} % with the page idle"
    )
    print(f"  UI server CPU (this process):      {100 * server_s / wall:.1f} % of one core")
    p95 = statistics.quantiles(delays, n=20)[-1]
    print(
        f"  keystroke to underline in the browser: p50 {1000 * statistics.median(delays):.0f} "
        f"ms, p95 {1000 * p95:.0f} ms ({ERRORS} errors typed; the page waits 150 ms "
        "before it sends)"
    )


def _lines(page: Page) -> int:
    count: int = page.evaluate("window.padtEditor.view.state.doc.lines")
    return count


def _task_s(cdp: CDPSession) -> float:
    metrics = cdp.send("Performance.getMetrics")["metrics"]
    return float(next(m["value"] for m in metrics if m["name"] == "TaskDuration"))


def _diagnostic_delay(page: Page) -> float:
    """Seconds from typing a statement with an undeclared name to its underline, then the
    statement taken back (and its underline gone)."""
    errors = page.locator("#padt-editor .cm-lintRange-error")
    wrong = "counter := zz;"
    started = time.monotonic()
    page.keyboard.type(wrong)
    wait_until("an underline", lambda: errors.count() > 0)
    delay = time.monotonic() - started
    for _ in wrong:
        page.keyboard.press("Backspace")
    wait_until("no underline", lambda: errors.count() == 0)
    return delay


if __name__ == "__main__":
    main()
