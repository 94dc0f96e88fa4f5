"""What a page reports of a click is read as untrusted text."""

from __future__ import annotations

from frontend.page_clicks import MAX_NAME, Click, read, read_reports


def test_a_tab_and_a_row_are_read() -> None:
    assert read("tab|Online test|1") == Click("tab", "Online test")
    assert read("variable|TankControl.level|17") == Click("variable", "TankControl.level")
    assert read("tree|program:TankControl|2") == Click("tree", "program:TankControl")
    assert read("window|1400x900|3") == Click("window", "1400x900")


def test_anything_else_is_ignored() -> None:
    for text in (
        "",
        "tab",
        "tab|Online test",
        "button|Stop|3",
        "tab||3",
        "tab|Online test|x",
        "variable|a|b|4",
        f"variable|{'x' * (MAX_NAME + 1)}|1",
    ):
        assert read(text) is None, text


def test_reports_close_together_are_each_read_once_in_order() -> None:
    """A value holds the page's last reports: viser's callbacks, each on a thread of its
    own, read the value as it is then, so one may see two new reports and the next none."""
    assert read_reports("tab|Logic|7|tree|file:a@a.st:1|8") == [
        (7, Click("tab", "Logic")),
        (8, Click("tree", "file:a@a.st:1")),
    ]
    for text in (
        "tab|Logic|7|tree",
        "tab|Logic|²",
        "tab|Logic|" + "9" * 16,
        "|".join(["tab|a|1"] * 9),
    ):
        assert read_reports(text) is None, text
