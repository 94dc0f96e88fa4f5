"""Asking before a command that changes a running controller, and telling how it went."""

from __future__ import annotations

import html
from collections.abc import Callable

import viser

from backend.engineering.resource_client import ResourceUnreachable
from runtime.contract.refusal import Refusal


def confirm(client: viser.ClientHandle, title: str, text: str, yes: Callable[[], object]) -> None:
    """A modal that names what will happen; the command runs only on its OK."""
    with client.gui.add_modal(title) as modal:
        client.gui.add_html(f'<div data-testid="confirm-text">{html.escape(text)}</div>')
        ok = client.gui.add_button("OK", color="blue")
        cancel = client.gui.add_button("Cancel")

    def accepted(_: viser.GuiEvent[viser.GuiButtonHandle]) -> None:
        modal.close()
        yes()

    ok.on_click(accepted)
    cancel.on_click(lambda _: modal.close())


def attempt(client: viser.ClientHandle, what: str, action: Callable[[], object]) -> bool:
    """Run an action; a refusal or no answer is shown to the user, never raised."""
    try:
        action()
    except Refusal as refused:
        client.add_notification(
            f"{what} refused", f"{refused.code}: {refused.message}", color="red",
            auto_close_seconds=8,
        )  # fmt: skip
        return False
    except ResourceUnreachable as exc:
        client.add_notification("No answer", str(exc), color="red", auto_close_seconds=8)
        return False
    client.add_notification(what, "done", color="green", auto_close_seconds=3)
    return True
