"""A tree entry the page reports is read as untrusted text: a place in a file or a part of
the settings, or nothing."""

from __future__ import annotations

from frontend.project_tree_view import Entry, entry_of


def test_entries_are_read() -> None:
    assert entry_of("file:TankControl@tank.st:6") == Entry("file", "TankControl", "tank.st", 6)
    assert entry_of("file:tank@lib/tank.st:38") == Entry("file", "tank", "lib/tank.st", 38)
    assert entry_of("program:TankControl") == Entry("program", "TankControl")
    assert entry_of("account:admin") == Entry("account", "admin")


def test_anything_else_is_nothing() -> None:
    for text in (
        "",
        "file:",
        "file:A@tank.st",
        "file:A@tank.st:x",
        "file:@tank.st:3",
        "file:A@:3",
        "program:",
        "pou:A",
        "resource",
    ):
        assert entry_of(text) is None, text
