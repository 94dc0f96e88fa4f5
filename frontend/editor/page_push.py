"""What the server tells the editor in one browser: the CodeMirror bundle once, then
messages for `window.padtEditor.receive`, each a script viser runs in the page
(`RunJavascriptMessage`).

viser keeps every RunJavascriptMessage in the client's buffer for as long as the page
lives (it never culls them); pushed at each keystroke they would grow without end. Each
push here has a channel instead, and a newer push on the channel replaces the older one in
the buffer: a channel is chosen so that only its newest message matters (the diagnostics,
the acknowledgement, the live values of a file, the answer to a question)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import viser
from viser import _messages

BUNDLE = Path(__file__).resolve().parents[2] / ".tools" / "codemirror" / "editor.bundle.js"
INSTALL = "scripts/install-codemirror.sh"


class _ChannelScript(_messages.RunJavascriptMessage):
    """A RunJavascriptMessage that a newer one of its channel replaces. The leading
    underscore keeps it out of viser's table of message types; it goes on the wire as a
    RunJavascriptMessage."""

    channel = ""

    def redundancy_key(self) -> str:
        return f"padt-editor:{self.channel}"

    def as_serializable_dict(self, binary_buffers: Any = None) -> dict[str, Any]:
        out = super().as_serializable_dict(binary_buffers)
        out["type"] = "RunJavascriptMessage"
        return out


def run(client: viser.ClientHandle, channel: str, source: str) -> None:
    connection = client._websock_connection  # viser is pinned below 1.2
    if connection.get_message_buffer().done:
        return  # the page is gone (a worker's answer may come after it)
    message = _ChannelScript(source=source)
    message.channel = channel
    connection.queue_message(message)


def script_json(data: Any) -> str:
    """`data` as a JavaScript expression: JSON, with the two line separators JavaScript
    once did not allow in strings and `</` (a script's end) escaped."""
    text = json.dumps(data, ensure_ascii=False, separators=(",", ":"))
    return text.replace("\u2028", "\\u2028").replace("\u2029", "\\u2029").replace("</", "<\\/")


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
