"""The login: all an anonymous browser sees. Its password field is a password input
(`frontend/viser_lockdown.py` makes every field labelled Password one)."""

from __future__ import annotations

import html
from collections.abc import Callable
from dataclasses import dataclass

import viser

from frontend.viser_lockdown import PASSWORD_LABEL

LEFT_PX, TOP_PX, WIDTH_PX = 360, 120, 400


@dataclass
class LoginForm:
    user: viser.GuiTextHandle
    password: viser.GuiTextHandle
    message: viser.GuiHtmlHandle
    handles: tuple[viser.GuiInputHandle[str] | viser.GuiHtmlHandle | viser.GuiButtonHandle, ...]

    def remove(self) -> None:
        for handle in self.handles:
            handle.remove()


def build(gui: viser.GuiApi, message: str, submit: Callable[[str, str], None]) -> LoginForm:
    gui.main_panel.float(x=LEFT_PX, y=TOP_PX, width=WIDTH_PX)  # a login card, not a sidebar
    title = gui.add_html(
        '<div style="padding:8px 0"><b style="font-size:1.2em">PADT</b><br>'
        "Log in with your PADT account.</div>"
    )
    user = gui.add_text("User", "")
    password = gui.add_text(PASSWORD_LABEL, "")
    button = gui.add_button("Log in", color="blue")
    shown = gui.add_html(note(message))

    def clicked(_: viser.GuiEvent[viser.GuiButtonHandle]) -> None:
        submit(user.value.strip(), password.value)

    button.on_click(clicked)
    return LoginForm(user, password, shown, (title, user, password, button, shown))


def note(message: str, error: bool = False) -> str:
    """A refused login in red; "Logged out." and the like in grey."""
    if not message:
        return ""
    color = "#c92a2a" if error else "#868e96"
    return f'<div data-testid="login-message" style="color:{color}">{html.escape(message)}</div>'
