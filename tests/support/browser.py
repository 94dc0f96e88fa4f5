"""Headless Debian Chromium driven by Playwright (never a downloaded browser).

Within `one_browser_for_the_tests_within()` (each module of tests/ui: its conftest) the
Chromium process is started once and `chromium()` gives each test that browser; what the
test opens in it (its pages, each in a context of its own: cookies, storage, cache) is
closed when its `with chromium()` ends, so no test sees another's session. Elsewhere each
`chromium()` starts a browser of its own."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

from playwright.sync_api import Browser, Playwright, sync_playwright

CHROMIUM = "/usr/bin/chromium"
# Without the background-networking flags Chromium keeps calling out to a closed network.
CHROMIUM_ARGS = [
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--use-angle=swiftshader",
    "--enable-unsafe-swiftshader",
]


class _Shared:
    """One Playwright and one Chromium, started when a test first asks for a browser."""

    def __init__(self) -> None:
        self.playwright: Playwright | None = None
        self.browser: Browser | None = None

    def get(self) -> Browser:
        if self.browser is not None and not self.browser.is_connected():  # it crashed
            self.browser = None
        if self.playwright is None:
            self.playwright = sync_playwright().start()
        if self.browser is None:
            self.browser = self.playwright.chromium.launch(
                executable_path=CHROMIUM, args=CHROMIUM_ARGS
            )
        return self.browser

    def close(self) -> None:
        try:
            if self.browser is not None and self.browser.is_connected():
                self.browser.close()
        finally:
            if self.playwright is not None:
                self.playwright.stop()


_shared: _Shared | None = None


@contextmanager
def one_browser_for_the_tests_within() -> Iterator[None]:
    """`chromium()` within gives one Chromium process, each time with nothing left open.
    While it lives, Playwright's event loop is this thread's running loop: code that runs
    a loop of its own (`asyncio.run`) in this thread cannot run within."""
    global _shared
    shared = _shared = _Shared()
    try:
        yield
    finally:
        _shared = None
        shared.close()


@contextmanager
def chromium() -> Iterator[Browser]:
    if _shared is None:
        with sync_playwright() as playwright:
            browser = playwright.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
            try:
                yield browser
            finally:
                browser.close()
        return
    browser = _shared.get()
    before = set(browser.contexts)
    try:
        yield browser
    finally:
        for context in browser.contexts:
            if context not in before:
                context.close()
