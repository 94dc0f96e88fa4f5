"""The projects a PADT knows: new ones from each template (each compiles with `padt
compile`), names that are folder names and nothing else, and the folder for projects
listed again when another tool adds one."""

from __future__ import annotations

import json
import time
import tomllib
from pathlib import Path

import pytest

from backend.engineering.padt_audit_log import PadtAuditLog
from backend.engineering.project_access import Editor
from backend.engineering.project_shelf import ProjectShelf, templates
from runtime.contract.refusal import Refusal
from tests.conftest import padt

ANNA = Editor("anna", "read-write")


@pytest.fixture
def shelf(tmp_path: Path) -> ProjectShelf:
    return ProjectShelf({}, tmp_path / "projects", PadtAuditLog(tmp_path / "a.jsonl", time.time_ns))


@pytest.mark.parametrize("template", [t.name for t in templates()])
def test_each_template_makes_a_project_that_compiles(shelf: ProjectShelf, template: str) -> None:
    folder = shelf.new_project(f"new {template}", template, ANNA, resource="Line_2")
    assert shelf[f"new {template}"] == folder
    compiled = padt("compile", str(folder))
    assert compiled.returncode == 0, compiled.stdout + compiled.stderr
    assert "configuration CRC" in compiled.stdout
    config = tomllib.loads((folder / "padt.toml").read_text())
    assert config["project"]["name"] == f"new {template}"
    assert config["resource"]["name"] == "Line_2"


def test_the_sequence_template_runs_its_steps(shelf: ProjectShelf) -> None:
    folder = shelf.new_project("batch", "sequence", ANNA)
    ran = padt("sim", str(folder), "--cycles", "60", "--trace", "Batch.batches,level")
    assert ran.returncode == 0, ran.stderr
    last = ran.stdout.splitlines()[-1]
    assert '"Batch.batches": 1' in last


def test_the_conveyor_template_runs_its_drawings(shelf: ProjectShelf) -> None:
    folder = shelf.new_project("belt", "conveyor", ANNA)
    ran = padt("sim", str(folder), "--cycles", "140", "--trace", "motorOn,overTemp,serviceDue")
    assert ran.returncode == 0, ran.stderr
    seen = [json.loads(line)["values"] for line in ran.stdout.splitlines()]
    # the LD latches the drive on, the FBD's alarm drops it, the run timer flags service
    for name in ("motorOn", "overTemp", "serviceDue"):
        assert {cycle[name] for cycle in seen} == {True, False}, name


def test_a_template_keeps_its_comments(shelf: ProjectShelf) -> None:
    folder = shelf.new_project("tank", "tank", ANNA)
    assert "# Field I/O over Modbus TCP" in (folder / "padt.toml").read_text()


@pytest.mark.parametrize(
    ("name", "reason"),
    [
        ("a/b", "must not hold '/'"),
        ("a\\b", "must not hold"),
        ("..", "must not start with '.'"),
        (".git", "must not start with '.'"),
        ("tab\there", "must not hold '\\t'"),
        ("", "must not be empty"),
        (" x", "must not be empty nor start or end with a space"),
        ("x" * 65, "at most 64"),
    ],
)
def test_a_project_name_is_a_folder_name_and_nothing_else(
    shelf: ProjectShelf, name: str, reason: str
) -> None:
    with pytest.raises(Refusal) as refused:
        shelf.new_project(name, "empty", ANNA)
    assert refused.value.code == "bad_value" and reason in refused.value.message
    assert not list(shelf.new_dir.iterdir())  # type: ignore[union-attr]


def test_a_taken_name_an_unknown_template_and_a_bad_resource_are_refused(
    shelf: ProjectShelf,
) -> None:
    shelf.new_project("Line", "empty", ANNA)
    with pytest.raises(Refusal, match="there is a project 'line' already"):
        shelf.new_project("line", "empty", ANNA)
    with pytest.raises(Refusal, match=r"no template 'ladder'.*empty, tank, sequence, conveyor"):
        shelf.new_project("other", "ladder", ANNA)
    with pytest.raises(Refusal, match="cannot name a resource"):
        shelf.new_project("other", "empty", ANNA, resource="Line/**")
    assert list(shelf) == ["Line"]


def test_without_a_folder_for_projects_none_is_made(tmp_path: Path) -> None:
    shelf = ProjectShelf({}, None, PadtAuditLog(tmp_path / "a.jsonl", time.time_ns))
    with pytest.raises(Refusal, match="no folder for new projects"):
        shelf.new_project("x", "empty", ANNA)


def test_projects_given_and_found_in_the_folder_are_listed(
    shelf: ProjectShelf, tmp_path: Path
) -> None:
    given = tmp_path / "elsewhere"
    given.mkdir()
    (given / "main.st").write_text("PROGRAM Main END_PROGRAM\n")
    assert shelf.new_dir is not None
    (shelf.new_dir / "by_git").mkdir()
    (shelf.new_dir / "by_git" / "padt.toml").write_text('[resource]\nname = "R"\n')
    (shelf.new_dir / "not_a_project").mkdir()
    both = ProjectShelf({"given": given}, shelf.new_dir, shelf.audit)
    assert dict(both) == {"by_git": shelf.new_dir / "by_git", "given": given}
    (shelf.new_dir / "later").mkdir()
    (shelf.new_dir / "later" / "a.st").write_text("PROGRAM A END_PROGRAM\n")
    both.refresh()
    assert list(both) == ["by_git", "given", "later"]
    with pytest.raises(Refusal) as unknown:
        both.folder("nope")
    assert unknown.value.code == "unknown_project"


def test_a_project_the_audit_log_cannot_record_is_not_made(tmp_path: Path) -> None:
    blocked = tmp_path / "audit-is-a-folder"
    blocked.mkdir()
    shelf = ProjectShelf({}, tmp_path / "projects", PadtAuditLog(blocked, time.time_ns))
    with pytest.raises(Refusal, match="no project made") as refused:
        shelf.new_project("line", "empty", ANNA)
    assert refused.value.code == "audit"
    assert list(shelf) == [] and not list((tmp_path / "projects").iterdir())


def test_a_padt_may_keep_a_template_elsewhere(tmp_path: Path) -> None:
    own = tmp_path / "demo-copy"
    own.mkdir()
    (own / "tank.st").write_text("PROGRAM TankControl END_PROGRAM\n")
    (own / "padt.toml").write_text(
        '[project]\nname = "Demo tank"\n\n[resource]\nname = "Tank1"\n\n'
        '[[resource.user]]\nname = "admin"\nlevel = "administrator"\npassword_hash = "h"\n'
    )
    shelf = ProjectShelf(
        {}, tmp_path / "projects", PadtAuditLog(tmp_path / "a.jsonl", time.time_ns), {"tank": own}
    )
    folder = shelf.new_project("mine", "tank", ANNA)
    config = tomllib.loads((folder / "padt.toml").read_text())
    assert config["project"]["name"] == "mine"
    assert config["resource"]["user"][0]["name"] == "admin"
    assert (folder / "tank.st").read_text() == "PROGRAM TankControl END_PROGRAM\n"
