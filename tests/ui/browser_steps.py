"""What a user does in the PADT's browser UI, as Playwright steps: fill a field, log in,
pick a tab, confirm a modal, read what a screen shows;
keep a screenshot for a person to look at (`PADT_SHOTS=folder`)."""

from __future__ import annotations

import os
import subprocess
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from playwright.sync_api import Error as PlaywrightError
from playwright.sync_api import Locator, Page

from backend.engineering.resource_client import ResourceClient
from frontend.app import PadtUi

WAIT_S = 20
# a page coming up, or the workspace after a login: on a loaded machine (two cores shared
# with the resource and the UI, WebGL in software) the browser may be busy for long
START_S = 60
PASSWORD = "correct-horse-7"  # of every account of the `plant` fixture


@dataclass(frozen=True)
class Demo:
    url: str
    password: str
    modbus_port: int = 0  # where the resource serves its image over Modbus TCP
    opcua_port: int = 0  # where its OPC UA server listens (0: it has none)
    zenoh: str = ""  # its Zenoh router's endpoint


@dataclass(frozen=True)
class Plant:
    url: str
    client: ResourceClient
    ui: PadtUi  # the UI server, in the test's process
    runtime: subprocess.Popen[bytes] | None = None  # the resource's runtime process
    state: Path | None = None  # its state folder
    zenoh: str = ""  # the router's endpoint


def shoot(page: Page, name: str) -> None:
    if "PADT_SHOTS" in os.environ:  # for a person to look at
        page.screenshot(path=str(Path(os.environ["PADT_SHOTS"]) / f"{name}.png"))


WAITING = "…"  # a cell whose first value has not come yet


def field(page: Page, label: str) -> Locator:
    """A viser text input by its label (viser does not link the two for the browser)."""
    return page.locator(f"div:has(> div > p > label:text-is('{label}')) input").first


def text_of(page: Page, selector: str) -> str:
    return page.locator(selector).first.inner_text(timeout=WAIT_S * 1000)


def wait_until(what: str, check: Callable[[], bool], timeout_s: float = WAIT_S) -> None:
    """Until `check()` holds; an element not there yet (Playwright's timeout inside the
    check) is "not yet" too, until the deadline."""
    deadline = time.monotonic() + timeout_s
    while True:
        try:
            if check():
                return
            last = ""
        except PlaywrightError as error:
            last = f" ({error.message.splitlines()[0]})"
        assert time.monotonic() < deadline, f"never: {what}{last}"
        time.sleep(0.1)


def wait_for_text(page: Page, selector: str, wanted: str, timeout_s: float = WAIT_S) -> None:
    wait_until(f"{selector} shows {wanted!r}", lambda: text_of(page, selector) == wanted, timeout_s)


def log_in(page: Page, user: str, password: str) -> None:
    button = page.get_by_role("button", name="Log in", exact=True)
    button.wait_for(timeout=START_S * 1000)
    field(page, "User").fill(user, timeout=START_S * 1000)
    field(page, "Password").fill(password, timeout=START_S * 1000)
    button.click(timeout=START_S * 1000)


def log_in_to_resource(page: Page, user: str, password: str) -> None:
    try:
        page.get_by_role("button", name="Log in to resource").wait_for(timeout=START_S * 1000)
    except PlaywrightError:  # seen rarely under load: say what the page showed instead
        raise AssertionError(f"no workspace; the page shows: {page.inner_text('body')}") from None
    # as a user does: the resource listed (chosen) before the login to it is tried
    wait_until("a resource is chosen", lambda: bool(_login_note(page)), timeout_s=START_S)
    # viser sends a field's value at most every 50 ms: a click right after typing may reach
    # the server before the password does (then refused, the field emptied): typed again
    deadline = time.monotonic() + START_S
    answers: list[str] = []  # the toasts of the attempts, for the message if none holds
    while True:
        field(page, "User").fill(user, timeout=START_S * 1000)
        field(page, "Password").fill(password, timeout=START_S * 1000)
        page.get_by_role("button", name="Log in to resource").click(timeout=START_S * 1000)
        answer = _login_answer(page)
        if answer == "logged in":
            return
        answers.append(answer)
        if time.monotonic() > deadline:  # say what the page showed instead
            try:
                shown = text_of(page, '[data-testid="resource-login"]')
            except PlaywrightError:
                shown = "(no resource login on the page)"
            raise AssertionError(
                f"never logged in to the resource; the attempts' answers: {answers}; its "
                f"login note: {shown!r}; the page: {page.inner_text('body')[:2000]!r}"
            )


def _login_answer(page: Page) -> str:
    """ "logged in", else the refusal the attempt was answered with (a red toast), else
    "no answer in 15 s"."""
    refusals = page.locator(".mantine-Notification-root", has_text="refused")
    unanswered = page.locator(".mantine-Notification-root", has_text="No answer")
    done = page.locator(".mantine-Notification-root", has_text="done")
    deadline = time.monotonic() + 15
    answered = False  # the green toast: it closes after 3 s
    while time.monotonic() < deadline:
        try:
            if _login_note(page).startswith("logged in"):
                return "logged in"
            answered = answered or done.count() > 0
            for toasts in (refusals, unanswered):
                if toasts.count():
                    text = " ".join(toasts.all_inner_texts())
                    page.evaluate(  # closed: the next attempt's answer is told apart
                        "document.querySelectorAll('.mantine-Notification-closeButton')"
                        ".forEach(b => b.click())"
                    )
                    page.wait_for_timeout(300)  # their fade
                    return text
        except PlaywrightError:
            pass
        time.sleep(0.1)
    if answered:  # the server answered, but the page did not follow
        return f"done, yet the login note says {_login_note(page)!r} after 15 s"
    return "no answer in 15 s"


def _login_note(page: Page) -> str:
    """What the workspace says of the login to the chosen resource ("" with none chosen)."""
    note = page.locator('[data-testid="resource-login"]')
    return note.first.inner_text(timeout=1000) if note.count() else ""


def open_demo_as_admin(page: Page, demo: Demo) -> None:
    """Open the demo, log in to the PADT and to its resource Tank1 as its administrator."""
    page.goto(demo.url)
    log_in(page, "admin", demo.password)
    log_in_to_resource(page, "admin", demo.password)
    wait_until("Tank1 runs", lambda: state(page) == "RUN", timeout_s=START_S)


def confirm(page: Page, names: str) -> None:
    """Check the confirmation says what it is about, then press its OK."""
    dialog = page.get_by_role("dialog")
    dialog.wait_for(timeout=WAIT_S * 1000)
    assert names in dialog.inner_text(), dialog.inner_text()
    dialog.get_by_role("button", name="OK").click()
    dialog.wait_for(state="detached", timeout=WAIT_S * 1000)


def state(page: Page) -> str:
    return text_of(page, '[data-testid="resource-state"]')


def cycle(page: Page) -> int:
    return int(text_of(page, '[data-testid="resource-cycle"]'))


def value(page: Page, variable: str) -> str:
    """The value shown for a variable, once it came (a tab just opened may show its rows
    a moment before their first values)."""
    cell = f'[data-var="{variable}"]'
    wait_until(f"a value of {variable}", lambda: text_of(page, cell) != WAITING)
    return text_of(page, cell)


def button_enabled(page: Page, name: str) -> bool:
    return page.get_by_role("button", name=name, exact=True).first.is_enabled()


def open_as(page: Page, plant: Plant, user: str) -> None:
    page.goto(plant.url)
    log_in(page, user, PASSWORD)
    wait_for_text(page, '[data-testid="user"]', user, timeout_s=START_S)


def open_online_test(page: Page, plant: Plant) -> None:
    """The plant's UI as `viewer`, logged in to the resource, the Online test in front."""
    open_as(page, plant, "viewer")
    log_in_to_resource(page, "viewer", PASSWORD)
    wait_for_text(page, '[data-testid="resource-state"]', "RUN")
    page.get_by_role("tab", name="Online test").click()


def choose(page: Page, label: str, option: str) -> None:
    """Pick `option` in the viser dropdown (a Mantine select) labelled `label`. A list
    opened before the screen offered the option (the Code screen's instances come once
    the project is compiled) does not take it in: it is closed and opened again."""
    deadline = time.monotonic() + WAIT_S
    wanted = page.get_by_role("option", name=option, exact=True).first
    while True:
        page.get_by_label(label, exact=True).first.click()
        try:
            wanted.wait_for(timeout=2_000)
            break
        except PlaywrightError:
            if time.monotonic() > deadline:
                raise
            page.keyboard.press("Escape")
    wanted.click()
    wait_until(
        f"{label} shows {option}",
        lambda: page.get_by_label(label, exact=True).first.input_value() == option,
    )


# ---- writing and forcing (tests/ui/test_browser_forcing.py)


def shoot_both(page: Page, name: str) -> None:
    """A screenshot at 1400x900 and one at 1920x1080; the page is left at 1400x900."""
    if "PADT_SHOTS" not in os.environ:
        return
    for width, height in ((1920, 1080), (1400, 900)):
        page.set_viewport_size({"width": width, "height": height})
        time.sleep(0.5)  # let the panels settle
        shoot(page, f"{name}-{width}x{height}")


def edit_value(page: Page, variable: str, literal: str) -> None:
    """Fill the Online test's write/force fields."""
    field(page, "Variable").fill(variable)
    field(page, "New value").fill(literal)


def banner(page: Page) -> str:
    """The forcing banner's text, "" while it is not shown."""
    # no waiting: the strip comes and goes with the refresher
    shown = page.locator('[data-testid="forcing-banner"]:visible').all_inner_texts()
    return shown[0] if shown else ""


def open_tab(page: Page, name: str) -> None:
    page.get_by_role("tab", name=name).click()


def text_area(page: Page, label: str) -> Locator:
    """A viser multiline text input by its label."""
    return page.locator(f"div:has(> div > p > label:text-is('{label}')) textarea").first


def set_number(page: Page, label: str, number: int) -> None:
    """Type a number into the viser number input labelled `label`."""
    box = page.get_by_label(label, exact=True)
    box.fill(str(number))
    box.press("Enter")
