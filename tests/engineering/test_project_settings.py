"""padt.toml edited as forms edit it: read into settings, checked field by field as one
types (with the compiler's codes where the compiler finds the problem), written with only
the changed values, comments and order kept; never written with an error."""

from __future__ import annotations

import difflib
import time
from pathlib import Path

import pytest

from backend.engineering.padt_audit_log import PadtAuditLog
from backend.engineering.project_access import Editor
from backend.engineering.project_files import read_file
from backend.engineering.project_settings import (
    ModbusDevice,
    ModbusPoint,
    ProgramSettings,
    read_settings,
    settings_problems,
    write_settings,
)
from backend.engineering.project_shelf import ProjectShelf
from runtime.contract.refusal import Refusal

ANNA = Editor("anna", "read-write")
READER = Editor("rita", "read-only")


@pytest.fixture
def shelf(tmp_path: Path) -> ProjectShelf:
    made = ProjectShelf(
        {}, tmp_path / "projects", PadtAuditLog(tmp_path / "audit.jsonl", time.time_ns)
    )
    made.new_project("tank", "tank", ANNA)
    return made


def config(shelf: ProjectShelf) -> str:
    return (shelf.folder("tank") / "padt.toml").read_text()


def changed_lines(before: str, after: str) -> list[str]:
    diff = difflib.unified_diff(before.splitlines(), after.splitlines(), lineterm="", n=0)
    return [line for line in diff if line[:1] in "+-" and line[:3] not in ("+++", "---")]


def test_the_settings_read_as_padt_toml_has_them(shelf: ProjectShelf) -> None:
    settings = read_settings(shelf, "tank", READER).settings
    assert settings.resource == "Tank1"
    assert settings.parameters["target_cycle_ms"] == 100
    assert [(p.name, p.pou, p.id, p.parameters["priority"]) for p in settings.programs] == [
        ("TankControl", "TankControl", 1, 0)
    ]
    assert settings.modbus == {"host": "127.0.0.1", "port": 5020}
    assert [(d.name, d.port, len(d.points)) for d in settings.devices] == [("plant", 5021, 3)]


def test_a_round_trip_keeps_the_file_and_a_change_is_one_line(shelf: ProjectShelf) -> None:
    before = config(shelf)
    read = read_settings(shelf, "tank", ANNA)
    write_settings(shelf, "tank", read.settings, read.hash, ANNA)
    assert config(shelf) == before
    read = read_settings(shelf, "tank", ANNA)
    read.settings.parameters["target_cycle_ms"] = 50
    write_settings(shelf, "tank", read.settings, read.hash, ANNA)
    assert changed_lines(before, config(shelf)) == [
        "-target_cycle_ms = 100",
        "+target_cycle_ms = 50",
    ]
    assert "# the demo is for trying things" in config(shelf)


def test_a_program_instance_and_a_device_added_and_removed(shelf: ProjectShelf) -> None:
    read = read_settings(shelf, "tank", ANNA)
    read.settings.programs.append(ProgramSettings("Spare", "TankControl", 2, {"priority": 3}))
    read.settings.devices[0].points.pop()
    write_settings(shelf, "tank", read.settings, read.hash, ANNA)
    again = read_settings(shelf, "tank", ANNA)
    assert [(p.name, p.id) for p in again.settings.programs] == [("TankControl", 1), ("Spare", 2)]
    assert len(again.settings.devices[0].points) == 2
    assert "# Field I/O over Modbus TCP" in config(shelf)
    again.settings.programs.pop()
    again.settings.modbus = None
    again.settings.devices = []
    write_settings(shelf, "tank", again.settings, again.hash, ANNA)
    assert "[modbus]" not in config(shelf) and "Spare" not in config(shelf)


def test_each_field_is_checked_as_one_types(shelf: ProjectShelf) -> None:
    draft = read_settings(shelf, "tank", ANNA).settings
    draft.resource = "Tank 1"
    draft.parameters["watchdog_ms"] = 5
    draft.parameters["target_cycle_mode"] = "sometimes"
    draft.programs.append(ProgramSettings("TankControl", "TankControl", 1, {"priority": -1}))
    problems = {(p.field, p.message) for p in settings_problems(shelf, "tank", draft, ANNA)}
    assert problems == {
        (
            "resource.name",
            "'Tank 1' cannot name a resource: a letter or _, then letters, "
            "digits, _ or - (at most 64)",
        ),
        ("resource.watchdog_ms", "watchdog_ms must be from 6 to 7500"),
        (
            "resource.target_cycle_mode",
            "target_cycle_mode must be one of fixed, fixed-tolerant, dynamic, dynamic-tolerant",
        ),
        ("resource.program.1.name", "a second instance named TankControl"),
        ("resource.program.1.id", "id 1 is taken already"),
        ("resource.program.1.priority", "priority must be from 0 to 31"),
    }


def test_what_only_the_compiler_knows_comes_with_its_code_and_field(shelf: ProjectShelf) -> None:
    draft = read_settings(shelf, "tank", ANNA).settings
    draft.devices.append(
        ModbusDevice("more", "127.0.0.1", 5030, {}, [ModbusPoint("noSuchVariable", "coil", 0)])
    )
    problems = settings_problems(shelf, "tank", draft, ANNA)
    assert [(p.field, p.code) for p in problems] == [("modbus.device.1.point.0.variable", "E0613")]
    assert "noSuchVariable" in problems[0].message
    draft.devices.pop()
    draft.programs[0].pou = "NoSuchProgram"
    problems = settings_problems(shelf, "tank", draft, ANNA)
    assert [(p.field, p.code) for p in problems] == [("resource.program.0", "E0601")]


def test_a_draft_with_an_error_is_never_written(shelf: ProjectShelf) -> None:
    before = config(shelf)
    read = read_settings(shelf, "tank", ANNA)
    read.settings.parameters["watchdog_ms"] = 1
    with pytest.raises(Refusal) as refused:
        write_settings(shelf, "tank", read.settings, read.hash, ANNA)
    assert refused.value.code == "settings"
    assert refused.value.details["problems"][0]["field"] == "resource.watchdog_ms"
    assert config(shelf) == before


def test_settings_changed_since_they_were_read_are_a_conflict(shelf: ProjectShelf) -> None:
    read = read_settings(shelf, "tank", ANNA)
    (shelf.folder("tank") / "padt.toml").write_text(config(shelf) + "# by hand\n")
    read.settings.parameters["target_cycle_ms"] = 200
    with pytest.raises(Refusal, match="changed since it was opened"):
        write_settings(shelf, "tank", read.settings, read.hash, ANNA)
    assert config(shelf).endswith("# by hand\n")


def test_read_only_may_read_settings_not_write_them(shelf: ProjectShelf) -> None:
    read = read_settings(shelf, "tank", READER)
    with pytest.raises(Refusal, match="needs read-write"):
        write_settings(shelf, "tank", read.settings, read.hash, READER)
    assert read_file(shelf, "tank", "padt.toml", READER).hash == read.hash


def test_hostile_drafts_and_forms_are_refused_with_a_reason(shelf: ProjectShelf) -> None:
    draft = read_settings(shelf, "tank", ANNA).settings
    draft.programs[0].name = 'x"\n[evil]'
    draft.programs[0].parameters["program_id"] = 3
    draft.parameters["no_such_setting"] = 1
    fields = [p.field for p in settings_problems(shelf, "tank", draft, ANNA)]
    assert fields == [
        "resource.no_such_setting",
        "resource.program.0.name",
        "resource.program.0.program_id",
    ]
    inline = 'resource = { name = "R", program = [{ name = "P", pou = "P", id = 1 }] }\n'
    (shelf.folder("tank") / "padt.toml").write_text(inline)
    read = read_settings(shelf, "tank", ANNA)
    read.settings.programs.append(ProgramSettings("Q", "P", 2))
    with pytest.raises(Refusal, match="edit it as text") as refused:
        write_settings(shelf, "tank", read.settings, read.hash, ANNA)
    assert refused.value.code == "project"
    assert config(shelf) == inline
