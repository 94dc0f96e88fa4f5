"""The Debug Adapter Protocol's messages on a byte stream: `Content-Length: N`, an empty
line, then N bytes of JSON (https://microsoft.github.io/debug-adapter-protocol/overview).

What comes in is hostile: a header or a body that is not the protocol's becomes a
`Malformed` the server answers with an error response, and reading goes on at the next
header; nothing a client sends makes the adapter crash or read without bound."""

from __future__ import annotations

import json
import threading
from dataclasses import dataclass
from typing import Any, BinaryIO

MAX_HEADER_LINE = 1024  # bytes of one header line
MAX_HEADER_LINES = 16
MAX_BODY = 4 * 1024 * 1024  # bytes of one message: a setBreakpoints of a large file fits


@dataclass(frozen=True)
class Malformed:
    """A message that is not the protocol's; `seq` and `command` when they could be read,
    so that the error response names the request it answers."""

    reason: str
    seq: int = 0
    command: str = ""


def read_message(stream: BinaryIO) -> dict[str, Any] | Malformed | None:
    """The next message (a JSON object with its `seq` and `type`), a `Malformed`, or None
    at the end of the stream."""
    length: int | None = None
    problem: str | None = None
    seen = False  # a header line: an empty line before any is a stray one between messages
    for count in range(MAX_HEADER_LINES + 1):
        line = stream.readline(MAX_HEADER_LINE + 1)
        if not line:
            return None
        if count == MAX_HEADER_LINES:
            return Malformed(f"more than {MAX_HEADER_LINES} header lines")
        if len(line) > MAX_HEADER_LINE and not line.endswith(b"\n"):
            seen = True
            _skip_line(stream)
            problem = f"a header line longer than {MAX_HEADER_LINE} bytes"
            continue
        text = line.strip()
        if not text:
            if not seen:
                continue
            break
        seen = True
        name, colon, value = text.partition(b":")
        if not colon:
            problem = f"'{_shown(text)}' is no header 'Name: value'"
        elif name.strip().lower() == b"content-length":
            try:
                length = int(value.strip())
            except ValueError:
                problem = f"Content-Length '{_shown(value.strip())}' is no number"
    if problem is not None:
        return Malformed(problem)
    if length is None:
        return Malformed("no Content-Length header")
    if not 0 <= length <= MAX_BODY:
        return Malformed(f"Content-Length {length} is not between 0 and {MAX_BODY}")
    body = _read_exactly(stream, length)
    if body is None:
        return None
    return _decoded(body)


def _decoded(body: bytes) -> dict[str, Any] | Malformed:
    try:
        message = json.loads(body)
    except (UnicodeDecodeError, ValueError) as exc:
        return Malformed(f"the body is no JSON: {exc}")
    if not isinstance(message, dict):
        return Malformed("the body is no JSON object")
    seq = message.get("seq")
    seq = seq if isinstance(seq, int) and not isinstance(seq, bool) else 0
    command = message.get("command")
    command = command if isinstance(command, str) else ""
    if message.get("type") != "request":
        return Malformed("only requests are taken (`type` 'request')", seq, command[:80])
    if not command:
        return Malformed("a request without its `command`", seq)
    arguments = message.get("arguments", {})
    if arguments is None:
        message["arguments"] = {}
    elif not isinstance(arguments, dict):
        return Malformed("`arguments` is no JSON object", seq, command[:80])
    message["seq"] = seq
    return message


def _read_exactly(stream: BinaryIO, length: int) -> bytes | None:
    chunks, left = [], length
    while left > 0:
        chunk = stream.read(left)
        if not chunk:
            return None
        chunks.append(chunk)
        left -= len(chunk)
    return b"".join(chunks)


def _skip_line(stream: BinaryIO) -> None:
    while True:
        chunk = stream.readline(MAX_HEADER_LINE)
        if not chunk or chunk.endswith(b"\n"):
            return


def _shown(text: bytes) -> str:
    return text[:80].decode("utf-8", "replace")


class MessageWriter:
    """Writes messages with their header and numbers them (`seq`); thread-safe, since
    events come from the threads that follow the resource."""

    def __init__(self, stream: BinaryIO) -> None:
        self._stream = stream
        self._lock = threading.Lock()
        self._seq = 0
        self.closed = False

    def send(self, message: dict[str, Any]) -> None:
        with self._lock:
            if self.closed:
                return
            self._seq += 1
            body = json.dumps({"seq": self._seq, **message}, separators=(",", ":")).encode()
            try:
                self._stream.write(b"Content-Length: %d\r\n\r\n" % len(body) + body)
                self._stream.flush()
            except (OSError, ValueError):  # the client went away: nothing more to tell it
                self.closed = True

    def respond(self, request: dict[str, Any], body: dict[str, Any] | None = None) -> None:
        self.send(
            {
                "type": "response",
                "request_seq": request["seq"],
                "success": True,
                "command": request["command"],
                "body": body or {},
            }
        )

    def refuse(self, seq: int, command: str, message: str, show: bool = True) -> None:
        """An error response: VS Code shows `message` (and the error's `format`) unless not
        `show`."""
        self.send(
            {
                "type": "response",
                "request_seq": seq,
                "success": False,
                "command": command,
                "message": message,
                "body": {"error": {"id": 1, "format": message, "showUser": show}},
            }
        )

    def event(self, name: str, body: dict[str, Any] | None = None) -> None:
        message: dict[str, Any] = {"type": "event", "event": name}
        if body is not None:
            message["body"] = body
        self.send(message)

    def close(self) -> None:
        with self._lock:
            self.closed = True
