"""Adding, renaming and deleting POUs, types and global variable lists: a file each, from
a skeleton that compiles; a rename carried into the file's name and padt.toml; a delete
refused while the resource runs the POU; each change audited and checked for the level."""

from __future__ import annotations

import time
import tomllib
from pathlib import Path

import pytest

from backend.engineering.padt_audit_log import PadtAuditLog
from backend.engineering.project_access import Editor
from backend.engineering.project_edits import (
    NEW_KINDS,
    add_declaration,
    delete_declaration,
    rename_declaration,
)
from backend.engineering.project_files import read_file, save_file
from backend.engineering.project_shelf import ProjectShelf
from backend.engineering.project_tree import project_tree
from runtime.contract.refusal import Refusal
from tests.conftest import padt

ANNA = Editor("anna", "read-write")
READER = Editor("rita", "read-only")


@pytest.fixture
def shelf(tmp_path: Path) -> ProjectShelf:
    made = ProjectShelf(
        {}, tmp_path / "projects", PadtAuditLog(tmp_path / "audit.jsonl", time.time_ns)
    )
    made.new_project("line", "empty", ANNA)
    return made


def compiles(shelf: ProjectShelf) -> str:
    result = padt("compile", str(shelf.folder("line")))
    assert result.returncode == 0, result.stdout + result.stderr
    return result.stdout


def test_every_kind_is_added_as_a_file_of_its_own_that_compiles(shelf: ProjectShelf) -> None:
    for kind in NEW_KINDS:
        name = "New" + kind.title().replace("_", "")
        saved = add_declaration(shelf, "line", kind, name, ANNA)
        assert saved.path == f"{name}.st" and saved.old_hash == ""
    add_declaration(shelf, "line", "FUNCTION", "Scale", ANNA, return_type="REAL", folder="lib")
    add_declaration(shelf, "line", "FUNCTION", "Origin", ANNA, return_type="NewStruct")
    compiles(shelf)
    tree = project_tree(shelf, "line", ANNA)
    assert [(p.kind, p.name) for p in tree.pous] == [
        ("PROGRAM", "Main"),
        ("PROGRAM", "NewProgram"),
        ("FUNCTION_BLOCK", "NewFunctionBlock"),
        ("FUNCTION", "NewFunction"),
        ("FUNCTION", "Origin"),
        ("FUNCTION", "Scale"),
    ]
    assert next(p for p in tree.pous if p.name == "Scale").file == "lib/Scale.st"
    assert [t.name for t in tree.types] == ["NewEnum", "NewStruct"]
    assert [g.name for g in tree.globals] == ["NewGlobals"]


def test_a_function_block_and_a_program_using_it_compile(shelf: ProjectShelf) -> None:
    add_declaration(shelf, "line", "FUNCTION_BLOCK", "Motor", ANNA)
    opened = read_file(shelf, "line", "Main.st", ANNA)
    text = "PROGRAM Main\nVAR\n  m : Motor;\nEND_VAR\nm();\nEND_PROGRAM\n"
    save_file(shelf, "line", "Main.st", text, opened.hash, ANNA)
    assert "POU Motor: CRC" in compiles(shelf)


@pytest.mark.parametrize(
    ("name", "reason"),
    [
        ("9lives", "is no name"),
        ("has space", "is no name"),
        ("IF", "it is a keyword"),
        ("ton", "standard type, function or block"),
        ("Int", "standard type, function or block"),
        ("ABS", "standard type, function or block"),
        ("double__under", "cannot be declared"),
        ("main", "Main.st declares Main already"),
        ("x" * 65, "at most 64"),
    ],
)
def test_names_the_compiler_would_refuse_or_the_project_has_are_refused(
    shelf: ProjectShelf, name: str, reason: str
) -> None:
    with pytest.raises(Refusal, match=reason):
        add_declaration(shelf, "line", "FUNCTION_BLOCK", name, ANNA)
    assert [p.name for p in project_tree(shelf, "line", ANNA).pous] == ["Main"]


def test_a_rename_changes_the_declaration_the_file_and_the_program_instance(
    shelf: ProjectShelf,
) -> None:
    written = rename_declaration(shelf, "line", "Main", "Cell", ANNA)
    assert [w.path for w in written] == ["Main.st", "Cell.st", "padt.toml"]
    folder = shelf.folder("line")
    assert not (folder / "Main.st").exists()
    assert (folder / "Cell.st").read_text().startswith("PROGRAM Cell\n")
    config = (folder / "padt.toml").read_text()
    assert "# A new project" in config  # its comments kept
    program = tomllib.loads(config)["resource"]["program"][0]
    assert (program["name"], program["pou"]) == ("Main", "Cell")
    compiles(shelf)


def test_a_function_renamed_assigns_its_result_by_its_new_name(shelf: ProjectShelf) -> None:
    add_declaration(shelf, "line", "FUNCTION", "Twice", ANNA, return_type="INT")
    rename_declaration(shelf, "line", "twice", "Double", ANNA)
    text = (shelf.folder("line") / "Double.st").read_text()
    assert "FUNCTION Double : INT" in text and "Double := 0;" in text
    compiles(shelf)


def test_a_delete_is_refused_while_the_resource_runs_the_pou(shelf: ProjectShelf) -> None:
    with pytest.raises(Refusal, match=r"runs as program instance Main of padt\.toml") as refused:
        delete_declaration(shelf, "line", "Main", ANNA)
    assert refused.value.code == "in_use"
    add_declaration(shelf, "line", "STRUCT", "Point", ANNA)
    delete_declaration(shelf, "line", "Point", ANNA)
    assert not (shelf.folder("line") / "Point.st").exists()
    with pytest.raises(Refusal, match="declares no 'Point'"):
        delete_declaration(shelf, "line", "Point", ANNA)


def test_edits_need_read_write_and_are_audited(shelf: ProjectShelf) -> None:
    for edit in (
        lambda: add_declaration(shelf, "line", "PROGRAM", "P", READER),
        lambda: rename_declaration(shelf, "line", "Main", "P", READER),
        lambda: delete_declaration(shelf, "line", "Main", READER),
    ):
        with pytest.raises(Refusal, match="needs read-write"):
            edit()
    add_declaration(shelf, "line", "ENUM", "Mode", ANNA)
    rename_declaration(shelf, "line", "Mode", "State", ANNA)
    delete_declaration(shelf, "line", "State", ANNA)
    entries = shelf.audit_log().entries()
    assert [(e.user, e.action, e.file, e.new_file) for e in entries[1:]] == [
        ("anna", "create", "Mode.st", ""),
        ("anna", "save", "Mode.st", ""),
        ("anna", "rename", "Mode.st", "State.st"),
        ("anna", "delete", "State.st", ""),
    ]
