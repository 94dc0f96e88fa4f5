"""`padt docs` of several projects at once: each a document of its own, made in worker
processes (`--jobs`), the same bytes as made one after another; one that cannot be made
is named and the others are written."""

from __future__ import annotations

from pathlib import Path

import pytest

from backend.engineering.documentation.batch import DocumentError, Request, requests_of
from padt.cli import main
from tests.engineering.documentation.filling_line import write_filling_line

COUNT_ST = """PROGRAM Count
VAR n : INT; (* counted *) on : BOOL; END_VAR
IF on THEN
  n := n + 1; // one more
END_IF;
END_PROGRAM
"""


@pytest.fixture(scope="module")
def projects(tmp_path_factory: pytest.TempPathFactory) -> list[Path]:
    folder = tmp_path_factory.mktemp("batch")
    (folder / "count.st").write_text(COUNT_ST)
    (folder / "blink.st").write_text(
        "PROGRAM Blink\nVAR lamp : BOOL; END_VAR\nlamp := NOT lamp;\nEND_PROGRAM\n"
    )
    return [write_filling_line(folder / "filling-line"), folder / "count.st", folder / "blink.st"]


def files(folder: Path) -> dict[str, bytes]:
    return {path.name: path.read_bytes() for path in sorted(folder.iterdir())}


def test_jobs_give_the_same_bytes_as_one_process(projects: list[Path], tmp_path: Path) -> None:
    paths = [str(path) for path in projects]
    assert main(["docs", "--each", *paths, "-o", str(tmp_path / "one"), "--jobs", "1"]) == 0
    assert main(["docs", "--each", *paths, "-o", str(tmp_path / "three"), "--jobs", "3"]) == 0
    alone = files(tmp_path / "one")
    assert sorted(alone) == [
        "Filling_line.html",
        "Filling_line.pdf",
        "blink.html",
        "blink.pdf",
        "count.html",
        "count.pdf",
    ]
    assert files(tmp_path / "three") == alone


def test_a_project_that_fails_is_named_and_the_others_written(
    projects: list[Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bad = tmp_path / "bad.st"
    bad.write_text("PROGRAM Bad\nx := 1;\nEND_PROGRAM\n")
    paths = [str(projects[0]), str(bad), str(projects[1])]
    out = tmp_path / "out"
    assert main(["docs", "--each", *paths, "-o", str(out), "--jobs", "2"]) == 2
    said = capsys.readouterr()
    assert f"padt docs: {bad} does not compile: {bad}:2:1: error: 'x' is not declared" in said.err
    assert "1 of 3 not documented" in said.err
    assert sorted(path.name for path in out.iterdir()) == [
        "Filling_line.html",
        "Filling_line.pdf",
        "count.html",
        "count.pdf",
    ]
    # told in the order given
    assert said.out.index("Filling_line.pdf") < said.out.index("count.pdf")


def test_two_documents_of_one_name_are_not_written_over(
    projects: list[Path], tmp_path: Path, capsys
) -> None:
    out = tmp_path / "out"
    assert main(["docs", str(projects[0]), str(projects[0]), "-o", str(out), "-j", "2"]) == 2
    assert f"{projects[0]}: its document is named Filling_line, as that of {projects[0]}" in (
        capsys.readouterr().err
    )
    assert sorted(path.name for path in out.iterdir()) == ["Filling_line.html", "Filling_line.pdf"]


def test_loose_files_form_one_project_unless_each(projects: list[Path]) -> None:
    folder, count, blink = projects
    assert requests_of([count, folder, blink]) == [Request((count, blink)), Request((folder,))]
    assert requests_of([count, blink], each=True) == [Request((count,)), Request((blink,))]
    assert requests_of([count, blink], compare=folder) == [Request((count, blink), folder)]
    with pytest.raises(DocumentError, match="--compare compares one project, not 2"):
        requests_of([count, blink], each=True, compare=folder)
