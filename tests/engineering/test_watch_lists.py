"""The users' watch lists: kept by the PADT across restarts, per user, owner-only, within
limits; a file that is not a watch list file is refused, not overwritten."""

from __future__ import annotations

import stat
from pathlib import Path

import pytest

from backend.engineering.watch_lists import (
    MAX_LISTS,
    MAX_VARIABLES,
    WatchList,
    WatchListError,
    WatchLists,
    list_name,
    with_variables,
    without_variable,
)


def test_lists_are_kept_per_user_across_a_restart(tmp_path: Path) -> None:
    path = tmp_path / "lists.json"
    lists = WatchLists(path)
    lists.put("anna", "Pump", ("TankControl.pump", "TankControl.level"))
    lists.put("anna", "Alarms", ("TankControl.alarmLow",))
    lists.put("ben", "Pump", ())
    again = WatchLists(path)
    assert again.of("anna") == (
        WatchList("Alarms", ("TankControl.alarmLow",)),
        WatchList("Pump", ("TankControl.pump", "TankControl.level")),
    )
    assert again.of("ben") == (WatchList("Pump", ()),)
    assert again.of("carl") == ()
    assert stat.S_IMODE(path.stat().st_mode) == 0o600
    again.delete("anna", "Pump")
    assert [x.name for x in WatchLists(path).of("anna")] == ["Alarms"]


def test_adding_keeps_the_order_and_each_variable_once() -> None:
    assert with_variables(("a", "b"), ["c", "a", "c", "d"]) == ("a", "b", "c", "d")
    assert without_variable(("a", "b", "c"), "b") == ("a", "c")


def test_limits_are_refused_with_the_reason(tmp_path: Path) -> None:
    lists = WatchLists(tmp_path / "lists.json")
    with pytest.raises(WatchListError, match="at most 20,000"):
        with_variables((), [f"v{i}" for i in range(MAX_VARIABLES + 1)])
    for number in range(MAX_LISTS):
        lists.put("anna", f"list {number}", ())
    with pytest.raises(WatchListError, match=f"at most {MAX_LISTS} watch lists"):
        lists.put("anna", "one more", ())
    with pytest.raises(WatchListError, match="give the list a name"):
        list_name("   ")
    assert list_name("  my   list ") == "my list"


def test_a_file_that_is_not_a_watch_list_file_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "lists.json"
    path.write_text("[1, 2, 3]")
    with pytest.raises(WatchListError, match="is not a watch list file"):
        WatchLists(path)
    assert path.read_text() == "[1, 2, 3]"
