"""What the editor's page script tells the server, read as hostile text: one typed
dataclass per message, each field checked, anything else refused with the reason.

The page sends every message not yet acknowledged at once, as the value of a hidden text
input, `{"s": [[seq, message], ...]}`, past viser's throttle of the panel's inputs
(frontend/page_writer.py); the server takes the messages past the last sequence number it
handled and acknowledges the newest. The page sends the queue again while it is not
acknowledged (a message sent while the websocket reconnects is lost), counting its writes
in "w" so that the same queue is a new value for the input (an input that keeps its value
sends nothing)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from runtime.contract.outside_json import JsonRefused, read_json
from runtime.contract.protocol import MAX_DEBUG_TIMEOUT_S, MIN_DEBUG_TIMEOUT_S

INPUT_LABEL = "Editor message"  # the hidden input's label; the page script finds it by it
# what one batch may carry: a whole file pasted (the services refuse a text larger than a
# file may be, 4 MiB), and the rest
MAX_TEXT = 8 << 20
MAX_BATCH_CHARS = MAX_TEXT + (1 << 20)
MAX_BATCH = 2000  # messages waiting in the page
MAX_CHANGES = 10_000  # changes in one message (a replace-all in a large file)
MAX_PATH = 512
MAX_NAME = 200
MAX_LINE = 10_000_000
BUTTONS = ("compile", "download", "online_change")
QUESTIONS = ("complete", "hover", "definition", "references")
# the Debug panel's controls: on the program in BKPT, the frame and variables it shows
DEBUG_ACTIONS = (
    "continue",
    "over",
    "into",
    "out",
    "cycle",
    "run_to",
    "frame",
    "expand",
    "collapse",
    "timeout",
)
MAX_BREAKPOINTS = 256  # in one file (as the resource takes them)
MAX_EXPRESSION = 512  # characters of a condition or a logged expression
MAX_LOGGED = 16  # expressions one logpoint records


class BadMessage(ValueError):
    """A message from the page that is not one: the reason."""


@dataclass(frozen=True)
class Open:
    file: str


@dataclass(frozen=True)
class Close:
    file: str


@dataclass(frozen=True)
class TextChange:
    """Replace from (line, column) to (line, column) of the text before the message with
    `insert`; lines 1-based, columns 0-based in UTF-16 code units (the browser's)."""

    from_line: int
    from_col: int
    to_line: int
    to_col: int
    insert: str


@dataclass(frozen=True)
class Change:
    file: str
    version: int  # the document's version after these changes
    changes: tuple[TextChange, ...]  # ascending, not overlapping, in the text before


@dataclass(frozen=True)
class Question:
    """A question about a place: complete, hover, definition, references. `col` is 1-based
    in UTF-16 code units of the line."""

    kind: str
    id: int
    file: str
    version: int
    line: int
    col: int


@dataclass(frozen=True)
class Rename:
    file: str
    version: int
    line: int
    col: int
    name: str


@dataclass(frozen=True)
class Save:
    file: str
    version: int


@dataclass(frozen=True)
class Button:
    name: str  # one of BUTTONS


@dataclass(frozen=True)
class DiskChoice:
    file: str
    keep_mine: bool  # False: reload from disk


@dataclass(frozen=True)
class View:
    file: str
    first: int  # the lines in view
    last: int


@dataclass(frozen=True)
class BreakpointItem:
    """A breakpoint as the gutter sets it: a line, and optionally a condition, a hit count
    or (a logpoint) the expressions to record."""

    line: int
    condition: str | None = None
    hit_count: int | None = None
    log: tuple[str, ...] | None = None


@dataclass(frozen=True)
class Breakpoints:
    """Every breakpoint of a file, in place of those it had."""

    file: str
    items: tuple[BreakpointItem, ...]


@dataclass(frozen=True)
class DebugAction:
    """A control of the Debug panel: a step, continue, run to `file:line`, a frame chosen
    (`frame`), a variable's members shown or hidden (`path`, relative to the frame), the
    resource's debug timeout (`seconds`)."""

    action: str  # one of DEBUG_ACTIONS
    frame: int = 0
    path: str = ""
    file: str = ""
    line: int = 0
    seconds: int = 0


Message = (
    Open
    | Close
    | Change
    | Question
    | Rename
    | Save
    | Button
    | DiskChoice
    | View
    | Breakpoints
    | DebugAction
)


@dataclass(frozen=True)
class Batch:
    messages: tuple[tuple[int, Message], ...]  # (sequence number, message), ascending
    refused: tuple[tuple[int, str], ...]  # (sequence number, reason) of what was not read


def read_batch(text: str) -> Batch:
    """The page's messages; BadMessage when the batch itself is not one."""
    try:
        data = read_json(text, "an editor message", MAX_BATCH_CHARS, max_depth=6)
    except JsonRefused as exc:
        raise BadMessage(str(exc)) from None
    if (
        not isinstance(data, dict)
        or not {"s"} <= set(data) <= {"s", "w"}
        or not isinstance(data["s"], list)
        or ("w" in data and not _is_int(data["w"], 1, 2**53))
    ):
        raise BadMessage('a batch is {"s": [[seq, message], ...], "w": writes}')
    entries = data["s"]
    if len(entries) > MAX_BATCH:
        raise BadMessage(f"more than {MAX_BATCH} messages at once")
    messages: list[tuple[int, Message]] = []
    refused: list[tuple[int, str]] = []
    last = 0
    for entry in entries:
        if not (isinstance(entry, list) and len(entry) == 2 and _is_int(entry[0], 1, 2**53)):
            raise BadMessage("an entry is [seq, message] with seq a positive integer")
        seq = entry[0]
        if seq <= last:
            raise BadMessage("sequence numbers ascend")
        last = seq
        try:
            messages.append((seq, read_message(entry[1])))
        except BadMessage as exc:
            refused.append((seq, str(exc)))
    return Batch(tuple(messages), tuple(refused))


def read_message(data: Any) -> Message:
    if not isinstance(data, dict) or not isinstance(data.get("k"), str):
        raise BadMessage('a message is an object with a kind "k"')
    kind = data["k"]
    if kind == "open":
        _keys(data, "k", "file")
        return Open(_path(data["file"]))
    if kind == "close":
        _keys(data, "k", "file")
        return Close(_path(data["file"]))
    if kind == "change":
        _keys(data, "k", "file", "version", "changes")
        changes = data["changes"]
        if not isinstance(changes, list) or len(changes) > MAX_CHANGES:
            raise BadMessage(f"changes are a list of at most {MAX_CHANGES}")
        return Change(
            _path(data["file"]),
            _int(data["version"], "version", 1, 2**53),
            tuple(_text_change(c) for c in changes),
        )
    if kind in QUESTIONS:
        _keys(data, "k", "id", "file", "version", "line", "col")
        return Question(
            kind,
            _int(data["id"], "id", 1, 2**53),
            _path(data["file"]),
            _int(data["version"], "version", 0, 2**53),
            _int(data["line"], "line", 1, MAX_LINE),
            _int(data["col"], "col", 1, MAX_LINE),
        )
    if kind == "rename":
        _keys(data, "k", "file", "version", "line", "col", "name")
        name = data["name"]
        if not isinstance(name, str) or not 0 < len(name) <= MAX_NAME:
            raise BadMessage(f"a new name has 1 to {MAX_NAME} characters")
        return Rename(
            _path(data["file"]),
            _int(data["version"], "version", 0, 2**53),
            _int(data["line"], "line", 1, MAX_LINE),
            _int(data["col"], "col", 1, MAX_LINE),
            name,
        )
    if kind == "save":
        _keys(data, "k", "file", "version")
        return Save(_path(data["file"]), _int(data["version"], "version", 0, 2**53))
    if kind == "button":
        _keys(data, "k", "name")
        if data["name"] not in BUTTONS:
            raise BadMessage(f"a button is one of {', '.join(BUTTONS)}")
        return Button(data["name"])
    if kind == "disk":
        _keys(data, "k", "file", "choice")
        if data["choice"] not in ("reload", "keep"):
            raise BadMessage("a choice is reload or keep")
        return DiskChoice(_path(data["file"]), data["choice"] == "keep")
    if kind == "view":
        _keys(data, "k", "file", "first", "last")
        first = _int(data["first"], "first", 1, MAX_LINE)
        last = _int(data["last"], "last", first, MAX_LINE)
        return View(_path(data["file"]), first, last)
    if kind == "breakpoints":
        _keys(data, "k", "file", "items")
        items = data["items"]
        if not isinstance(items, list) or len(items) > MAX_BREAKPOINTS:
            raise BadMessage(f"breakpoints are a list of at most {MAX_BREAKPOINTS}")
        return Breakpoints(_path(data["file"]), tuple(_breakpoint(i) for i in items))
    if kind == "debug":
        return _debug_action(data)
    raise BadMessage(f"no message of kind '{kind[:40]}'")


def _text_change(data: Any) -> TextChange:
    if not (isinstance(data, list) and len(data) == 5 and isinstance(data[4], str)):
        raise BadMessage("a change is [from line, from col, to line, to col, text]")
    if len(data[4]) > MAX_TEXT:
        raise BadMessage("a change inserts more text than a file may hold")
    from_line = _int(data[0], "a change's line", 1, MAX_LINE)
    to_line = _int(data[2], "a change's line", from_line, MAX_LINE)
    return TextChange(
        from_line,
        _int(data[1], "a change's column", 0, MAX_LINE),
        to_line,
        _int(data[3], "a change's column", 0, MAX_LINE),
        data[4],
    )


def _breakpoint(data: Any) -> BreakpointItem:
    if not isinstance(data, dict) or "line" not in data:
        raise BadMessage("a breakpoint is an object with a line")
    if not set(data) <= {"line", "condition", "hit_count", "log"}:
        raise BadMessage("a breakpoint has a line, a condition, a hit count and a log only")
    condition = data.get("condition")
    if condition is not None:
        condition = _expression(condition, "a condition")
    hit_count = data.get("hit_count")
    if hit_count is not None:
        hit_count = _int(hit_count, "a hit count", 1, 1_000_000_000)
    log = data.get("log")
    if log is not None:
        if not isinstance(log, list) or not 0 < len(log) <= MAX_LOGGED:
            raise BadMessage(f"a logpoint records 1 to {MAX_LOGGED} expressions")
        log = tuple(_expression(x, "a logged expression") for x in log)
    return BreakpointItem(_int(data["line"], "a line", 1, MAX_LINE), condition, hit_count, log)


def _expression(value: Any, what: str) -> str:
    if not isinstance(value, str) or not 0 < len(value.strip()) <= MAX_EXPRESSION:
        raise BadMessage(f"{what} has 1 to {MAX_EXPRESSION} characters")
    return value.strip()


def _debug_action(data: dict[str, Any]) -> DebugAction:
    action = data.get("action")
    if action not in DEBUG_ACTIONS:
        raise BadMessage(f"a debug action is one of {', '.join(DEBUG_ACTIONS)}")
    if action == "run_to":
        _keys(data, "k", "action", "file", "line")
        return DebugAction(
            action, file=_path(data["file"]), line=_int(data["line"], "line", 1, MAX_LINE)
        )
    if action == "frame":
        _keys(data, "k", "action", "frame")
        return DebugAction(action, frame=_int(data["frame"], "a frame", 0, 10_000))
    if action in ("expand", "collapse"):
        _keys(data, "k", "action", "path")
        path = data["path"]
        if not isinstance(path, str) or not 0 < len(path) <= MAX_PATH:
            raise BadMessage(f"a variable's path has 1 to {MAX_PATH} characters")
        return DebugAction(action, path=path)
    if action == "timeout":
        _keys(data, "k", "action", "seconds")
        low, high = MIN_DEBUG_TIMEOUT_S, MAX_DEBUG_TIMEOUT_S
        return DebugAction(action, seconds=_int(data["seconds"], "a timeout in seconds", low, high))
    _keys(data, "k", "action")
    return DebugAction(action)


def _keys(data: dict[str, Any], *keys: str) -> None:
    if set(data) != set(keys):
        raise BadMessage(f"a {data['k']} message has exactly {', '.join(keys)}")


def _is_int(value: Any, low: int, high: int) -> bool:
    return type(value) is int and low <= value <= high


def _int(value: Any, what: str, low: int, high: int) -> int:
    if not _is_int(value, low, high):
        raise BadMessage(f"{what} is an integer from {low} to {high}")
    assert isinstance(value, int)
    return value


def _path(value: Any) -> str:
    """A file's name as the page has it; what it names is checked by the project's files
    service when it is read or saved."""
    if not isinstance(value, str) or not 0 < len(value) <= MAX_PATH:
        raise BadMessage(f"a file's name has 1 to {MAX_PATH} characters")
    return value
