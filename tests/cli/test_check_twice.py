"""`padt check-twice`: two compiles in two processes under different hash seeds agree."""

from __future__ import annotations

from pathlib import Path

from backend.engineering.check_twice import CompileRun, check_twice, compare
from backend.engineering.project import demo_project_path
from tests.conftest import padt


def test_the_demo_project_compiles_to_the_same_crcs_twice() -> None:
    result = padt("check-twice", str(demo_project_path()))
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    assert lines[0].startswith("compile 1 (PYTHONHASHSEED=1): configuration CRC ")
    assert lines[1].startswith("compile 2 (PYTHONHASHSEED=2): configuration CRC ")
    assert lines[0].rsplit(" ", 1)[1] == lines[1].rsplit(" ", 1)[1]
    assert lines[2].startswith("check-twice: OK")


def test_check_twice_reports_every_crc() -> None:
    result = check_twice([demo_project_path()])
    assert result.ok and result.compiled and result.mismatches == ()
    assert result.first.seed != result.second.seed
    assert result.first.configuration == result.second.configuration is not None
    assert result.first.pous == result.second.pous
    assert set(result.first.pous) == {"TON", "TankControl"}
    assert set(result.first.programs) == {"TankControl"}


def test_a_failing_compile_exits_1_with_its_diagnostics(tmp_path: Path) -> None:
    path = tmp_path / "bad.st"
    path.write_text("PROGRAM P\nVAR x : INT; END_VAR\nx := nothing;\nEND_PROGRAM\n")
    result = padt("check-twice", str(path))
    assert result.returncode == 1
    assert f"{path}:3:6: error: 'nothing' is not declared [E0201]" in result.stderr
    assert "does not compile" in result.stderr


def test_a_missing_file_is_a_failure_not_a_crash(tmp_path: Path) -> None:
    result = check_twice([tmp_path / "missing.st"])
    assert not result.ok and not result.compiled
    assert result.first.failure is not None and "no such file" in result.first.failure


def test_compare_names_each_crc_that_differs() -> None:
    first = CompileRun(
        "1", True, configuration="AAAA0000", pous={"A": "11", "B": "22"}, programs={"A": "33"}
    )
    second = CompileRun(
        "2", True, configuration="BBBB0000", pous={"A": "11", "B": "99"}, programs={"A": "33"}
    )
    assert compare(first, second) == (
        "configuration CRC: AAAA0000 != BBBB0000",
        "POU B CRC: 22 != 99",
    )
    assert compare(first, first) == ()
