"""`--project [NAME=]DIR` of `padt api` and `padt ui`."""

from __future__ import annotations

from pathlib import Path

import pytest

from backend.engineering.project_list import named_folder, projects_by_name


def test_a_project_is_named_or_takes_its_folders_name(tmp_path: Path) -> None:
    assert named_folder(f"line1={tmp_path}") == ("line1", tmp_path)
    assert named_folder(str(tmp_path)) == (tmp_path.name, tmp_path)
    # an `=` in a path is part of the path
    assert named_folder("a/b=c") == ("b=c", Path("a/b=c"))
    with pytest.raises(ValueError, match="no folder"):
        named_folder("line1=")


def test_two_projects_of_one_name_or_a_missing_folder_are_refused(tmp_path: Path) -> None:
    assert projects_by_name([("a", tmp_path)]) == {"a": tmp_path}
    with pytest.raises(ValueError, match="two projects are named a"):
        projects_by_name([("a", tmp_path), ("a", tmp_path)])
    with pytest.raises(ValueError, match="not a project folder"):
        projects_by_name([("a", tmp_path / "missing")])
