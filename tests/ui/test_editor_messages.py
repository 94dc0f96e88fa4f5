"""What the editor's page script may tell the server, and what it may not: each message
read into its dataclass, anything else refused with a reason (never an exception of
another kind), and the server's copy of a document following the browser's changes."""

from __future__ import annotations

import json

import pytest

from frontend.editor.document import BadChange, Document
from frontend.editor.messages import (
    BadMessage,
    Change,
    Question,
    Save,
    TextChange,
    read_batch,
)


def batch(*messages: object) -> str:
    return json.dumps({"s": [[n, m] for n, m in enumerate(messages, 1)]})


def test_messages_are_read_into_their_types() -> None:
    read = read_batch(
        batch(
            {"k": "change", "file": "tank.st", "version": 1, "changes": [[2, 0, 2, 3, "x"]]},
            {"k": "complete", "id": 4, "file": "tank.st", "version": 1, "line": 2, "col": 2},
            {"k": "save", "file": "tank.st", "version": 1},
        )
    )
    assert read.refused == ()
    assert [m for _, m in read.messages] == [
        Change("tank.st", 1, (TextChange(2, 0, 2, 3, "x"),)),
        Question("complete", 4, "tank.st", 1, 2, 2),
        Save("tank.st", 1),
    ]


def test_the_same_queue_written_again_is_read_once_more_by_its_write_count() -> None:
    # the page writes its unacknowledged queue again, counting the writes, so that viser
    # sends it even where an earlier write of the same queue was dropped
    message = {"k": "save", "file": "tank.st", "version": 1}
    first = read_batch(json.dumps({"s": [[1, message]], "w": 1}))
    again = read_batch(json.dumps({"s": [[1, message]], "w": 2}))
    assert first.messages == again.messages == ((1, Save("tank.st", 1)),)


@pytest.mark.parametrize(
    "message",
    [
        {"k": "format-disk"},
        {"k": "save", "file": "tank.st"},
        {"k": "save", "file": "tank.st", "version": -1},
        {"k": "save", "file": "tank.st", "version": True},
        {"k": "save", "file": "", "version": 1},
        {"k": "save", "file": "x" * 600, "version": 1},
        {"k": "change", "file": "a.st", "version": 1, "changes": [[3, 0, 2, 0, ""]]},
        {"k": "change", "file": "a.st", "version": 1, "changes": [[1, 0, 1, 0]]},
        {"k": "button", "name": "erase"},
        {"k": "rename", "file": "a.st", "version": 1, "line": 1, "col": 1, "name": ""},
        [1, 2],
        "save",
    ],
)
def test_a_message_that_is_not_one_is_refused_with_a_reason(message: object) -> None:
    read = read_batch(batch(message))
    assert read.messages == ()
    assert len(read.refused) == 1 and read.refused[0][1]


@pytest.mark.parametrize(
    "text",
    [
        "",
        "{",
        "[]",
        '{"s": 1}',
        '{"s": [[0, {}]]}',
        '{"s": [[2, {}], [1, {}]]}',
        "[" * 100_000,
        '{"s": [], "w": 0}',
        '{"s": [], "w": "1"}',
        '{"s": [], "w": 1, "x": 1}',
    ],
)
def test_a_batch_that_is_not_one_is_refused(text: str) -> None:
    with pytest.raises(BadMessage):
        read_batch(text)


def test_the_document_follows_the_browsers_changes() -> None:
    document = Document.of("demo", "a.st", "IF a THEN\n  b := 1;\nEND_IF;", "hash")
    # two changes of one message, positions in the text before both
    document.apply(1, (TextChange(1, 3, 1, 4, "ready"), TextChange(2, 7, 2, 8, "2;\n  c := 3")))
    assert document.text() == "IF ready THEN\n  b := 2;\n  c := 3;\nEND_IF;"
    # columns count UTF-16 units, as the browser does: an emoji is two
    document.apply(2, (TextChange(1, 0, 1, 0, "(* 🙂 *) "),))
    document.apply(3, (TextChange(1, 9, 1, 11, "IF"),))
    assert document.lines[0] == "(* 🙂 *) IF ready THEN"
    with pytest.raises(BadChange):
        document.apply(3, ())  # a version again
    with pytest.raises(BadChange):
        document.apply(4, (TextChange(9, 0, 9, 0, "x"),))  # past the end
    with pytest.raises(BadChange):
        document.apply(4, (TextChange(1, 4, 1, 4, "x"),))  # inside the emoji
