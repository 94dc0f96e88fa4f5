"""VAR_ACCESS names in the online test: a watch set, a write and forcing take an access path
where they take a variable's path, and answer with that path; a READ_ONLY one is read only
(docs/language.md, "VAR_ACCESS")."""

from __future__ import annotations

from pathlib import Path

from runtime.contract.recording import read_recording
from runtime.recorder import Recordings
from tests.compiler.test_var_config import DOORS
from tests.support.resource_harness import harness

PLANT = DOORS.replace("Cpu", "R")  # the harness's resource is R


def test_a_watch_set_takes_access_paths_and_answers_with_the_variables_paths() -> None:
    h = harness(PLANT)
    reply = h.ok("watch", id="w", variables=["FrontOpen", "speed", "Main.shown"])
    assert reply["variables"] == ["Main.front.open", "Main.speed", "Main.shown"]
    h.ok("write", variable="Speed", value=7)  # READ_WRITE
    h.cycle()
    assert h.value("Main.shown") == 7
    watch_set = h.resource.online.watches.get("w")
    assert watch_set is not None
    snapshot = h.resource.online.snapshot(watch_set, 1, True, h.resource.forcing.table)
    assert snapshot.values == [False, 7, 7]


def test_a_read_only_access_path_refuses_writes_and_forcing_but_its_variable_does_not() -> None:
    h = harness(PLANT)
    assert h.refused("write", variable="FrontOpen", value=True) == "read_only"
    assert h.refused("force", variable="frontopen", value=True) == "read_only"
    reply = h.cmd("write", variable="BackLamp", value=True)
    assert reply["error"]["message"] == "access path 'BackLamp' is READ_ONLY"
    h.ok("write", variable="Main.front.open", value=True)  # the variable itself: as ever
    assert h.value("Main.front.open") is True
    assert h.refused("watch", id="x", variables=["NoSuchPath"]) == "unknown_variable"


def test_a_recording_takes_an_access_path(tmp_path: Path) -> None:
    h = harness(PLANT)
    h.resource.recordings = Recordings(tmp_path / "recordings")
    h.ok("write", variable="Speed", value=3)
    h.ok("record_start", variables=["Speed"], cycles=2, id="r")
    h.cycle(3)
    h.resource.recordings.close()
    assert read_recording(tmp_path / "recordings" / "r-1.mcap").column("Main.speed") == [3, 3]
