"""`padt convert` (docs/cli.md): drawn bodies rewritten as ST in their files; the project
runs exactly as before, cycle by cycle; a project that would not compile is left as it was."""

from __future__ import annotations

from pathlib import Path

from tests.compiler.test_drawn_vs_text import _project
from tests.conftest import padt


def _trace(folder: Path) -> str:
    run = padt("sim", str(folder), "--cycles", "30", "--cycle-ms", "100")
    assert run.returncode == 0, run.stderr
    return run.stdout


def test_converted_bodies_run_exactly_as_the_drawings_did(tmp_path: Path) -> None:
    folder = _project(tmp_path / "project")
    before = _trace(folder)
    run = padt("convert", str(folder), "--pou", "drawn_ladder")
    assert run.returncode == 0, run.stderr
    assert run.stdout == "ladder.st: Drawn_ladder (LD, 20 elements) is now ST\n"
    assert "END_LD" not in (folder / "ladder.st").read_text()
    assert "END_FBD" in (folder / "flow.st").read_text()
    run = padt("convert", str(folder))
    assert run.returncode == 0, run.stderr
    assert sorted(run.stdout.splitlines()) == [
        "actions.st: Drawn_actions.Count (LD, 7 elements) is now ST",
        "actions.st: Drawn_actions.Latch (LD, 5 elements) is now ST",
        "blocks.st: Drawn_blocks (FBD, 17 elements) is now ST",
        "flow.st: Drawn_flow (FBD, 18 elements) is now ST",
        "functions.st: Drawn_functions (FBD, 14 elements) is now ST",
        "ordered.st: Drawn_ordered (FBD, 11 elements) is now ST",
    ]
    assert _trace(folder) == before  # every variable, hidden ones included, every cycle
    again = padt("convert", str(folder))
    assert (again.returncode, again.stdout) == (0, "padt convert: no drawn POU in the project\n")


def test_a_project_that_would_not_compile_is_left_as_it_was(tmp_path: Path) -> None:
    folder = _project(tmp_path / "project")
    broken = folder / "functions.st"
    text = broken.read_text().replace("14: OUT n := 13", "14: OUT n := 99")
    broken.write_text(text)
    run = padt("convert", str(folder))
    assert run.returncode == 1
    assert "functions.st:18:3: error: a wire comes from element 99" in run.stderr
    assert run.stderr.endswith("padt convert: nothing written\n")
    assert broken.read_text() == text
    assert "END_LD" in (folder / "ladder.st").read_text()
    unknown = padt("convert", str(folder), "--pou", "Nothing")
    assert (unknown.returncode, unknown.stderr) == (
        2,
        "padt convert: no drawn POU named NOTHING\n",
    )
