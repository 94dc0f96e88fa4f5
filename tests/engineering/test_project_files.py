"""Editing a project's files through the engineering service, as every adapter does:
reading with a hash, saving against the hash the edit started from (a conflict instead of
a lost edit), paths confined to the project's folder, the compiler's size limits, the
levels, and an audit entry for every change."""

from __future__ import annotations

import json
import os
import stat
import threading
from pathlib import Path

import pytest

from backend.compiler.limits import MAX_FILE_BYTES
from backend.engineering.padt_audit_log import PadtAuditLog
from backend.engineering.project_access import WRITE, Editor
from backend.engineering.project_files import (
    changed_on_disk,
    content_hash,
    delete_file,
    history,
    list_files,
    read_file,
    rename_file,
    save_file,
)
from backend.engineering.project_shelf import ProjectShelf
from backend.engineering.project_tree import project_tree
from runtime.contract.refusal import Refusal
from tests.support.corpus_paths import corpus_dir

ANNA = Editor("anna", "read-write")
BERT = Editor("bert", "read-write")
READER = Editor("rita", "read-only")


class Clock:
    """Wall time for the audit log that moves a second per entry."""

    def __init__(self) -> None:
        self.now = 1_800_000_000 * 10**9

    def __call__(self) -> int:
        self.now += 10**9
        return self.now


@pytest.fixture
def shelf(tmp_path: Path) -> ProjectShelf:
    made = ProjectShelf({}, tmp_path / "projects", PadtAuditLog(tmp_path / "audit.jsonl", Clock()))
    made.new_project("plant", "tank", ANNA)
    return made


def refused(code: str) -> pytest.RaisesExc[Refusal]:
    return pytest.raises(Refusal, check=lambda r: r.code == code)


def test_two_editors_of_one_file_get_a_conflict_not_a_lost_edit(shelf: ProjectShelf) -> None:
    first = read_file(shelf, "plant", "tank.st", ANNA)
    second = read_file(shelf, "plant", "tank.st", BERT)
    saved = save_file(shelf, "plant", "tank.st", first.text + "(* anna *)\n", first.hash, ANNA)
    assert saved.old_hash == first.hash
    with pytest.raises(Refusal) as conflict:
        save_file(shelf, "plant", "tank.st", second.text + "(* bert *)\n", second.hash, BERT)
    assert conflict.value.code == "conflict"
    assert conflict.value.details["current_hash"] == saved.hash
    assert "(* anna *)" in read_file(shelf, "plant", "tank.st", BERT).text
    assert "(* bert *)" not in read_file(shelf, "plant", "tank.st", BERT).text


def test_a_file_changed_by_another_tool_is_noticed_and_never_overwritten(
    shelf: ProjectShelf,
) -> None:
    opened = read_file(shelf, "plant", "tank.st", ANNA)
    assert not changed_on_disk(shelf, "plant", "tank.st", opened.hash, ANNA).changed
    on_disk = shelf.folder("plant") / "tank.st"
    on_disk.write_text(opened.text + "(* vim *)\n")
    state = changed_on_disk(shelf, "plant", "tank.st", opened.hash, ANNA)
    assert state.changed and state.hash == content_hash(on_disk.read_bytes())
    with refused("conflict"):
        save_file(shelf, "plant", "tank.st", opened.text, opened.hash, ANNA)
    assert on_disk.read_text().endswith("(* vim *)\n")
    on_disk.unlink()
    gone = changed_on_disk(shelf, "plant", "tank.st", opened.hash, ANNA)
    assert gone.changed and gone.hash == ""


@pytest.mark.parametrize(
    "path",
    [
        "../outside.st",
        "/etc/passwd",
        "sub/../../x.st",
        "notes.txt",
        ".hidden.st",
        "a\\b.st",
        "sub/padt.toml",
        "",
        "x" * 600 + ".st",
        "bad\x01.st",
    ],
)
def test_paths_outside_the_project_or_not_its_files_are_refused(
    shelf: ProjectShelf, path: str
) -> None:
    with refused("path"):
        read_file(shelf, "plant", path, ANNA)
    with refused("path"):
        save_file(shelf, "plant", path, "x", None, ANNA)


def test_a_symbolic_link_out_of_the_project_is_refused(shelf: ProjectShelf, tmp_path: Path) -> None:
    secret = tmp_path / "secret.st"
    secret.write_text("PROGRAM Secret END_PROGRAM\n")
    folder = shelf.folder("plant")
    (folder / "link.st").symlink_to(secret)
    (folder / "linked").symlink_to(tmp_path)
    for path in ("link.st", "linked/secret.st"):
        with refused("path"):
            read_file(shelf, "plant", path, ANNA)
        with refused("path"):
            save_file(shelf, "plant", path, "", content_hash(secret.read_bytes()), ANNA)
    listed = [f.path for f in list_files(shelf, "plant", ANNA)]
    assert listed == ["padt.toml", "tank.st", "test/tank_test.st"]  # the demo's tests too
    assert secret.read_text() == "PROGRAM Secret END_PROGRAM\n"


def test_the_compilers_size_limit_applies_on_save(shelf: ProjectShelf) -> None:
    opened = read_file(shelf, "plant", "tank.st", ANNA)
    with refused("too_large"):
        save_file(shelf, "plant", "tank.st", "(*" + "x" * MAX_FILE_BYTES + "*)", opened.hash, ANNA)
    with refused("too_large"):  # two bytes a character
        save_file(shelf, "plant", "tank.st", "é" * (MAX_FILE_BYTES // 2 + 1), opened.hash, ANNA)
    (shelf.folder("plant") / "huge.st").write_bytes(b" " * (MAX_FILE_BYTES + 1))
    with refused("too_large"):
        read_file(shelf, "plant", "huge.st", ANNA)
    assert read_file(shelf, "plant", "tank.st", ANNA).hash == opened.hash


def test_read_only_may_read_and_not_change(shelf: ProjectShelf) -> None:
    opened = read_file(shelf, "plant", "tank.st", READER)
    for change in (
        lambda: save_file(shelf, "plant", "tank.st", "", opened.hash, READER),
        lambda: delete_file(shelf, "plant", "tank.st", opened.hash, READER),
        lambda: rename_file(shelf, "plant", "tank.st", "t.st", READER),
        lambda: shelf.new_project("mine", "empty", READER),
    ):
        with refused("forbidden"):
            change()
    assert read_file(shelf, "plant", "tank.st", READER).hash == opened.hash


def test_without_an_audit_log_nothing_is_changed(tmp_path: Path) -> None:
    folder = tmp_path / "p"
    folder.mkdir()
    (folder / "main.st").write_text("PROGRAM Main END_PROGRAM\n")
    shelf = ProjectShelf({"p": folder})
    opened = read_file(shelf, "p", "main.st", ANNA)
    with pytest.raises(Refusal, match="no audit log"):
        save_file(shelf, "p", "main.st", "", opened.hash, ANNA)


def test_every_change_is_in_the_audit_log_with_who_what_and_both_hashes(
    shelf: ProjectShelf, tmp_path: Path
) -> None:
    opened = read_file(shelf, "plant", "tank.st", ANNA)
    saved = save_file(shelf, "plant", "tank.st", opened.text + "\n", opened.hash, ANNA)
    made = save_file(shelf, "plant", "sub/extra.st", "PROGRAM Extra END_PROGRAM\n", None, BERT)
    with refused("exists"):
        save_file(shelf, "plant", "sub/extra.st", "", None, BERT)
    moved = rename_file(shelf, "plant", "sub/extra.st", "extra.st", BERT)
    delete_file(shelf, "plant", "extra.st", moved.hash, ANNA)
    log = tmp_path / "audit.jsonl"
    assert stat.S_IMODE(log.stat().st_mode) == 0o600
    entries = [json.loads(line) for line in log.read_text().splitlines()]
    rows = [(e["user"], e["action"], e["file"], e["old_hash"], e["new_hash"]) for e in entries]
    assert rows == [
        ("anna", "new-project", "template:tank", "", ""),
        ("anna", "save", "tank.st", opened.hash, saved.hash),
        ("bert", "save", "sub/extra.st", "", made.hash),
        ("bert", "rename", "sub/extra.st", made.hash, made.hash),
        ("anna", "delete", "extra.st", made.hash, ""),
    ]
    assert entries[3]["new_file"] == "extra.st"
    assert all(e["project"] == "plant" for e in entries)
    times = [e["time_ns"] for e in entries]
    assert times == sorted(times) and len(set(times)) == len(times)
    assert shelf.audit_log().entries()[-1].action == "delete"
    extra = history(shelf, "plant", READER, "extra.st")
    assert [(e.action, e.file, e.new_file) for e in extra] == [
        ("delete", "extra.st", ""),
        ("rename", "sub/extra.st", "extra.st"),
    ]
    assert len(history(shelf, "plant", READER)) == 5
    assert history(shelf, "plant", READER, limit=1)[0].action == "delete"


def test_a_save_replaces_the_file_whole_and_keeps_its_mode(shelf: ProjectShelf) -> None:
    path = shelf.folder("plant") / "tank.st"
    os.chmod(path, 0o640)
    opened = read_file(shelf, "plant", "tank.st", ANNA)
    save_file(shelf, "plant", "tank.st", "(* new *)\n", opened.hash, ANNA)
    assert path.read_text() == "(* new *)\n"
    assert stat.S_IMODE(path.stat().st_mode) == 0o640
    assert not [p for p in path.parent.iterdir() if p.name.startswith(".")]


def test_the_tree_lists_pous_types_globals_resource_modbus_and_accounts(
    shelf: ProjectShelf,
) -> None:
    folder = shelf.folder("plant")
    (folder / "types.st").write_text(
        "TYPE Mode : (Auto, Manual); END_TYPE\nTYPE Point : STRUCT x : REAL; END_STRUCT; END_TYPE\n"
    )
    (folder / "plant_io.st").write_text("VAR_GLOBAL spare : INT; alarm : BOOL; END_VAR\n")
    (folder / "scale.st").write_text(
        "FUNCTION Scale : REAL\nVAR_INPUT x : INT; END_VAR\nScale := x / 10.0;\nEND_FUNCTION\n"
        "FUNCTION_BLOCK Pump\nVAR_INPUT run : BOOL; END_VAR\nEND_FUNCTION_BLOCK\n"
    )
    (folder / "broken.st").write_text("PROGRAM Broken\nx := ;\nEND_PROGRAM\n")
    with (folder / "padt.toml").open("a") as config:
        config.write(
            '\n[[resource.user]]\nname = "op"\nlevel = "operator"\npassword_hash = "scrypt$x"\n'
        )
    tree = project_tree(shelf, "plant", READER)
    assert [(p.kind, p.name, p.file) for p in tree.pous] == [
        ("PROGRAM", "Broken", "broken.st"),  # listed while it does not parse
        ("PROGRAM", "TankControl", "tank.st"),
        ("FUNCTION_BLOCK", "Pump", "scale.st"),
        ("FUNCTION_BLOCK", "TankTests", "test/tank_test.st"),  # the demo's tests (a group)
        ("FUNCTION", "Scale", "scale.st"),
    ]
    assert next(p for p in tree.pous if p.name == "Scale").detail == "REAL"
    assert [(t.name, t.detail) for t in tree.types] == [("Mode", "Enum"), ("Point", "Struct")]
    assert [(g.name, g.file, g.detail) for g in tree.globals] == [
        ("plant_io", "plant_io.st", "2 variables"),
        ("tank", "tank.st", "3 variables"),
    ]
    assert tree.resource is not None and tree.resource.name == "Tank1"
    assert tree.resource.settings["target_cycle_ms"] == 100
    assert [(p.name, p.pou, p.id) for p in tree.resource.programs] == [
        ("TankControl", "TankControl", 1)
    ]
    assert [(d.name, d.port, d.points) for d in tree.modbus] == [("plant", 5021, 3)]
    assert [(a.name, a.level) for a in tree.accounts] == [("op", "operator")]
    assert "scrypt" not in repr(tree)
    assert tree.problems == ()
    (folder / "padt.toml").write_text("[resource\n")
    assert project_tree(shelf, "plant", READER).problems[0].startswith("padt.toml: ")


def test_saves_racing_from_one_base_one_wins_the_others_conflict(shelf: ProjectShelf) -> None:
    opened = read_file(shelf, "plant", "tank.st", ANNA)
    outcomes: list[str] = []

    def save(n: int) -> None:
        try:
            save_file(
                shelf, "plant", "tank.st", f"(* {n} *)\n", opened.hash, Editor(f"u{n}", WRITE)
            )
            outcomes.append("saved")
        except Refusal as refused:
            outcomes.append(refused.code)

    threads = [threading.Thread(target=save, args=(n,)) for n in range(8)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join(timeout=60)
    assert sorted(outcomes) == ["conflict"] * 7 + ["saved"]
    saves = [e for e in shelf.audit_log().entries() if e.action == "save"]
    assert len(saves) == 1 and saves[0].old_hash == opened.hash


def test_the_oscat_project_opens_in_the_tree() -> None:
    folder = corpus_dir("oscat") / "st"
    tree = project_tree(ProjectShelf({"oscat": folder}), "oscat", READER)
    kinds = {
        kind: sum(p.kind == kind for p in tree.pous) for kind in ("FUNCTION", "FUNCTION_BLOCK")
    }
    assert kinds["FUNCTION"] > 300 and kinds["FUNCTION_BLOCK"] > 300
    assert len(tree.types) > 30 and tree.problems == ()


def test_a_change_the_audit_log_cannot_take_is_not_made(tmp_path: Path) -> None:
    blocked = tmp_path / "audit-is-a-folder"
    blocked.mkdir()
    shelf = ProjectShelf({}, tmp_path / "projects", PadtAuditLog(blocked, Clock()))
    folder = tmp_path / "projects" / "p"
    folder.mkdir(parents=True)
    (folder / "main.st").write_text("PROGRAM Main END_PROGRAM\n")
    shelf.refresh()
    opened = read_file(shelf, "p", "main.st", ANNA)
    with pytest.raises(Refusal, match="audit log cannot be written") as unaudited:
        save_file(shelf, "p", "main.st", "(* unaudited *)\n", opened.hash, ANNA)
    assert unaudited.value.code == "audit"
    with refused("audit"):
        delete_file(shelf, "p", "main.st", opened.hash, ANNA)
    assert (folder / "main.st").read_text() == "PROGRAM Main END_PROGRAM\n"
    assert sorted(p.name for p in folder.iterdir()) == ["main.st"]  # no temporary left
