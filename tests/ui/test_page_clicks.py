"""What a page reports of its clicks is read as untrusted text; each click is handled once,
in order, and acknowledged."""

from __future__ import annotations

import json
from typing import Any

import pytest

from frontend import page_clicks
from frontend.page_clicks import (
    MAX_BATCH_CHARS,
    MAX_NAME,
    MAX_QUEUE,
    Batch,
    Click,
    Handled,
    read_batch,
    read_click,
)


def _queue(*entries: Any, page: str = "k3x9", writes: int = 1) -> str:
    return json.dumps({"p": page, "s": list(entries), "w": writes})


def test_a_tab_and_a_row_are_read() -> None:
    assert read_click("tab|Online test") == Click("tab", "Online test")
    assert read_click("variable|TankControl.level") == Click("variable", "TankControl.level")
    assert read_click("tree|program:TankControl") == Click("tree", "program:TankControl")
    assert read_click("window|1400x900") == Click("window", "1400x900")


def test_anything_else_is_not_a_click() -> None:
    for text in (
        "",
        "tab",
        "tab|",
        "button|Stop",
        "|Online test",
        "variable|a|b",
        f"variable|{'x' * (MAX_NAME + 1)}",
    ):
        assert read_click(text) is None, text


def test_a_queue_is_read_in_order() -> None:
    batch = read_batch(_queue([3, "tab|Online test"], [4, "tree|file:TankControl@x.st:1"]))
    assert batch == Batch(
        "k3x9",
        ((3, Click("tab", "Online test")), (4, Click("tree", "file:TankControl@x.st:1"))),
    )


def test_an_unreadable_click_keeps_its_place() -> None:
    batch = read_batch(_queue([1, "button|Stop"], [2, "tab|Trends"]))
    assert batch == Batch("k3x9", ((1, None), (2, Click("tab", "Trends"))))


@pytest.mark.parametrize(
    "text",
    [
        "",
        "tab|Online test|1",  # the old form
        "{",
        "[]",
        "null",
        '{"p": "a", "s": []}',  # no write count
        '{"p": "a", "s": [], "w": 1, "x": 0}',
        '{"p": "", "s": [], "w": 1}',
        '{"p": "a-b", "s": [], "w": 1}',
        '{"p": 7, "s": [], "w": 1}',
        '{"p": "' + "a" * 33 + '", "s": [], "w": 1}',
        '{"p": "a", "s": [], "w": 0}',
        '{"p": "a", "s": [], "w": true}',
        '{"p": "a", "s": {}, "w": 1}',
        '{"p": "a", "s": [[1]], "w": 1}',
        '{"p": "a", "s": [[1, "tab|A", 2]], "w": 1}',
        '{"p": "a", "s": [["1", "tab|A"]], "w": 1}',
        '{"p": "a", "s": [[0, "tab|A"]], "w": 1}',
        '{"p": "a", "s": [[1.0, "tab|A"]], "w": 1}',
        '{"p": "a", "s": [[9007199254740993, "tab|A"]], "w": 1}',
        '{"p": "a", "s": [[1, ["tab", "A"]]], "w": 1}',
        '{"p": "a", "s": [[2, "tab|A"], [2, "tab|B"]], "w": 1}',  # n ascends
        '{"p": "a", "s": [[3, "tab|A"], [2, "tab|B"]], "w": 1}',
        '{"p": "a", "s": [[[[1]]]], "w": 1}',  # nested too deep
    ],
)
def test_anything_but_a_queue_is_refused(text: str) -> None:
    assert read_batch(text) is None


def test_a_queue_too_long_or_too_large_is_refused() -> None:
    entries = [[n, "tab|Trends"] for n in range(1, MAX_QUEUE + 2)]
    assert read_batch(_queue(*entries[:MAX_QUEUE])) is not None
    assert read_batch(_queue(*entries)) is None
    assert read_batch(_queue([1, "tab|" + "x" * MAX_BATCH_CHARS])) is None


def test_a_click_is_taken_once() -> None:
    handled = Handled()
    first = read_batch(_queue([1, "tab|Trends"]))
    again = read_batch(_queue([1, "tab|Trends"], [2, "tab|Events"], writes=2))
    assert first is not None and again is not None
    assert handled.take(first) == [Click("tab", "Trends")]
    assert handled.take(first) == []  # written again before the acknowledgement came
    assert handled.take(again) == [Click("tab", "Events")]
    assert (handled.page, handled.last) == ("k3x9", 2)


def test_an_unreadable_click_is_passed_over_and_counted() -> None:
    handled = Handled()
    batch = read_batch(_queue([1, "button|Stop"], [2, "tab|Trends"]))
    assert batch is not None
    assert handled.take(batch) == [Click("tab", "Trends")]
    assert handled.last == 2


def test_a_page_loaded_anew_counts_from_one() -> None:
    handled = Handled()
    before = read_batch(_queue([5, "tab|Trends"], page="old"))
    after = read_batch(_queue([1, "tab|Events"], page="new"))
    assert before is not None and after is not None
    assert handled.take(before) == [Click("tab", "Trends")]
    assert handled.take(after) == [Click("tab", "Events")]
    assert (handled.page, handled.last) == ("new", 1)


class _Handle:
    def __init__(self) -> None:
        self.value = ""
        self.updated: list[Any] = []

    def on_update(self, callback: Any) -> None:
        self.updated.append(callback)


class _Gui:
    def add_text(self, label: str, value: str) -> _Handle:
        return _Handle()

    def add_html(self, content: str) -> _Handle:
        return _Handle()


class _Client:
    gui = _Gui()


def test_the_newest_click_is_acknowledged_to_the_page(monkeypatch: pytest.MonkeyPatch) -> None:
    pushed: list[tuple[str, str]] = []
    monkeypatch.setattr(
        page_clicks, "run", lambda _, channel, source: pushed.append((channel, source))
    )
    heard: list[Click] = []

    def clicked(click: Click) -> None:
        heard.append(click)
        if click.name == "Boom":
            raise RuntimeError("a screen failed")

    clicks = page_clicks.build(_Client(), clicked)  # type: ignore[arg-type]
    clicks.heard(_queue([1, "tab|Boom"], [2, "tab|Trends"]))
    clicks.heard(_queue([1, "tab|Boom"], [2, "tab|Trends"], writes=2))
    clicks.heard("not a queue")
    assert heard == [Click("tab", "Boom"), Click("tab", "Trends")]
    ack = 'window.__padtClickAck&&window.__padtClickAck("k3x9",2)'
    assert pushed == [(page_clicks.ACK_CHANNEL, ack)] * 2
