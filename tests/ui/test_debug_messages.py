"""What the editor's gutter and Debug panel may tell the server: a file's breakpoints and
each control read into their types; a bad breakpoint or action refused with the reason,
never sent on."""

from __future__ import annotations

import pytest

from frontend.editor.messages import (
    BadMessage,
    BreakpointItem,
    Breakpoints,
    DebugAction,
    read_message,
)


def test_breakpoints_and_controls_are_read_into_their_types() -> None:
    items = [
        {"line": 18},
        {"line": 22, "condition": " level > 700 ", "hit_count": 3},
        {"line": 30, "log": ["level", "LIMIT(0, level, 10)"]},
    ]
    assert read_message({"k": "breakpoints", "file": "tank.st", "items": items}) == Breakpoints(
        "tank.st",
        (
            BreakpointItem(18),
            BreakpointItem(22, "level > 700", 3),
            BreakpointItem(30, log=("level", "LIMIT(0, level, 10)")),
        ),
    )
    assert read_message({"k": "debug", "action": "over"}) == DebugAction("over")
    run_to = {"k": "debug", "action": "run_to", "file": "tank.st", "line": 30}
    assert read_message(run_to) == DebugAction("run_to", file="tank.st", line=30)
    assert read_message({"k": "debug", "action": "frame", "frame": 1}) == DebugAction(
        "frame", frame=1
    )
    expand = {"k": "debug", "action": "expand", "path": "refillDelay"}
    assert read_message(expand) == DebugAction("expand", path="refillDelay")
    timeout = {"k": "debug", "action": "timeout", "seconds": 300}
    assert read_message(timeout) == DebugAction("timeout", seconds=300)


@pytest.mark.parametrize(
    ("message", "reason"),
    [
        ({"k": "breakpoints", "file": "tank.st", "items": [{"line": 0}]}, "a line is"),
        ({"k": "breakpoints", "file": "tank.st", "items": [{"line": "18"}]}, "a line is"),
        ({"k": "breakpoints", "file": "tank.st", "items": [{"line": 1, "x": 1}]}, "only"),
        ({"k": "breakpoints", "file": "tank.st", "items": [{"line": 1, "hit_count": 0}]}, "hit"),
        ({"k": "breakpoints", "file": "tank.st", "items": [{"line": 1, "condition": ""}]}, "1 to"),
        (
            {"k": "breakpoints", "file": "t.st", "items": [{"line": 1, "condition": "x" * 513}]},
            "1 to 512",
        ),
        ({"k": "breakpoints", "file": "t.st", "items": [{"line": 1, "log": []}]}, "1 to 16"),
        ({"k": "breakpoints", "file": "t.st", "items": [{"line": 1, "log": [3]}]}, "logged"),
        ({"k": "breakpoints", "file": "t.st", "items": [{"line": 1}] * 257}, "at most 256"),
        ({"k": "debug", "action": "reload"}, "a debug action is one of"),
        ({"k": "debug", "action": "over", "program": "Other"}, "exactly"),
        ({"k": "debug", "action": "frame", "frame": -1}, "a frame"),
        ({"k": "debug", "action": "expand", "path": ""}, "a variable's path"),
        ({"k": "debug", "action": "run_to", "file": "tank.st", "line": True}, "line"),
        ({"k": "debug", "action": "timeout", "seconds": 4}, "5 to 3600"),
    ],
)
def test_a_bad_breakpoint_or_control_is_refused_with_the_reason(
    message: dict[str, object], reason: str
) -> None:
    with pytest.raises(BadMessage, match=reason):
        read_message(message)
