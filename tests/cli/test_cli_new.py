"""`padt new`: a project folder from each template, as a user types it; what it refuses,
with the reason and exit code 2, leaving nothing behind."""

from __future__ import annotations

from pathlib import Path

from tests.conftest import padt


def test_a_new_project_compiles_and_says_where_it_is(tmp_path: Path) -> None:
    made = padt("new", "Line 2", "--template", "sequence", "--dir", str(tmp_path))
    assert made.returncode == 0, made.stderr
    folder = tmp_path / "Line 2"
    assert made.stdout == f"padt new: {folder} from template sequence\n"
    assert sorted(p.name for p in folder.iterdir()) == ["Batch.st", "Globals.st", "padt.toml"]
    assert padt("compile", str(folder)).returncode == 0


def test_refusals_say_why_and_leave_nothing(tmp_path: Path) -> None:
    assert padt("new", "p", "--dir", str(tmp_path), "--resource", "R1").returncode == 0
    for args, reason in (
        (["p"], "there is a project 'p' already"),
        (["a/b"], "must not hold '/'"),
        (["q", "--template", "ladder"], "there is no template 'ladder'"),
        (["q", "--resource", "no good"], "cannot name a resource"),
    ):
        refused = padt("new", *args, "--dir", str(tmp_path))
        assert refused.returncode == 2
        assert reason in refused.stderr and refused.stderr.startswith("padt new: ")
    assert [p.name for p in tmp_path.iterdir()] == ["p"]
