"""What the server tells the editor in one browser: the CodeMirror bundle once, then
messages for `window.padtEditor.receive`, each a script run in the page on a channel of
its own (frontend/page_push.py: a channel keeps only its newest message in viser's
buffer)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import viser

from frontend.page_push import run, script_json

BUNDLE = Path(__file__).resolve().parents[2] / ".tools" / "codemirror" / "editor.bundle.js"
INSTALL = "scripts/install-codemirror.sh"


def send(client: viser.ClientHandle, channel: str, message: dict[str, Any]) -> None:
    """`message` for the page's editor; dropped by a page that has no editor (its bundle
    is missing)."""
    run(client, channel, f"window.padtEditor&&window.padtEditor.receive({script_json(message)})")


def install(client: viser.ClientHandle) -> str | None:
    """Send the editor's code to the browser (it keeps it for the page's life); the
    reason when there is none to send."""
    try:
        source = BUNDLE.read_text(encoding="utf-8")
    except OSError:
        return (
            f"The code editor is not installed: run `bash {INSTALL}` (make demo and make "
            "test do) and reload the page."
        )
    run(client, "bundle", source)
    return None
