"""`padt test` as a user runs it (docs/testing.md): the demo's tests pass on both tiers; a
failed assert names its place, expected and actual; -k, -j, --tier and a single test file
choose what runs; a test file that does not compile, or no test, ends with its exit code;
the JUnit XML is valid for xmllint against the JUnit schema of Jenkins' xUnit plugin
(installed by scripts/install-junit-schema.sh)."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from tests.conftest import REPO, padt

DEMO = REPO / "backend" / "projects" / "demo"
SCHEMA = REPO / ".tools" / "junit-schema" / "junit-10.xsd"
DEMO_TESTS = [
    "TankTests.TestAForcedLevelWinsOverThePlant",
    "TankTests.TestALostPlantHoldsTheLevelAndStopsThePump",
    "TankTests.TestTheLevelFollowsThePlant",
    "TankTests.TestTheLowAlarm",
    "TankTests.TestThePumpRestartsAfterTheRefillDelay",
    "TankTests.TestThePumpStopsAtTheHighLevel",
]

# the program reads the level 500 in its cycle: the assert fails, at line 5, column 1
FAILING = """FUNCTION_BLOCK LevelTests
METHOD TestTheLevelIsFourHundred
tankLevel := 500;
RUN_CYCLES(1);
ASSERT_EQUAL(400, TankControl.level, 'the level');
END_METHOD
END_FUNCTION_BLOCK
"""

NOT_COMPILING = """FUNCTION_BLOCK BrokenTests
METHOD TestNothing
RUN_CYCLES(1);
nowhere := 3;
END_METHOD
END_FUNCTION_BLOCK
"""


@pytest.fixture
def project(tmp_path: Path) -> Path:
    """A copy of the demo with one more test file, whose test fails."""
    folder = tmp_path / "tank"
    shutil.copytree(DEMO, folder)
    (folder / "test" / "level_test.st").write_text(FAILING)
    return folder


def results(stdout: str) -> tuple[list[str], str]:
    """Each test's lines (PASS/FAIL with what follows), sorted, and the summary without its
    time."""
    blocks: list[str] = []
    lines = stdout.splitlines()
    for line in lines[:-1]:
        if line.startswith("  ") and blocks:
            blocks[-1] += "\n" + line
        else:
            blocks.append(line)
    summary = re.sub(r" in [0-9.]+ s$", "", lines[-1])
    return sorted(blocks), summary


@pytest.mark.usefixtures("native_tier")
def test_the_demo_passes_on_both_tiers() -> None:
    run = padt("test", str(DEMO))
    assert run.returncode == 0, run.stderr
    passed, summary = results(run.stdout)
    assert passed == [f"PASS {name}" for name in DEMO_TESTS]
    assert summary == "6 passed of 6 tests (native and python)"


@pytest.mark.usefixtures("native_tier")
def test_a_failed_assert_names_its_place_expected_and_actual(project: Path) -> None:
    run = padt("test", str(project))
    assert run.returncode == 1, run.stderr
    found, summary = results(run.stdout)
    assert (
        "FAIL LevelTests.TestTheLevelIsFourHundred\n"
        "  test/level_test.st:5:1: ASSERT_EQUAL failed: the level\n"
        "    expected 400, actual 500"
    ) in found
    assert summary == "6 passed, 1 failed of 7 tests (native and python)"


@pytest.mark.usefixtures("native_tier")
def test_two_workers_find_what_one_process_finds(project: Path) -> None:
    serial = padt("test", str(project))
    parallel = padt("test", str(project), "-j", "2")
    assert serial.returncode == parallel.returncode == 1
    assert results(parallel.stdout) == results(serial.stdout)


def test_k_and_a_test_file_choose_the_tests(project: Path) -> None:
    chosen = padt("test", str(project), "-k", "pumpstops", "--tier", "python")
    assert chosen.returncode == 0, chosen.stderr
    assert results(chosen.stdout) == (
        ["PASS TankTests.TestThePumpStopsAtTheHighLevel"],
        "1 passed of 1 tests (python)",
    )
    one_file = project / "test" / "level_test.st"
    alone = padt("test", str(one_file), "--tier", "python")
    assert alone.returncode == 1, alone.stderr
    names = [block.splitlines()[0] for block in results(alone.stdout)[0]]
    assert names == ["FAIL LevelTests.TestTheLevelIsFourHundred"]


def test_the_python_tier_alone() -> None:
    run = padt("test", str(DEMO), "--tier", "python")
    assert run.returncode == 0, run.stderr
    assert results(run.stdout)[1] == "6 passed of 6 tests (python)"


def test_the_native_tier_alone_without_a_c_compiler_runs_on_python(tmp_path: Path) -> None:
    """As `padt runtime` runs the bodies as Python where no C compiler is, and says so."""
    nothing = tmp_path / "empty-path"  # no cc, no gcc on it
    nothing.mkdir()
    run = padt("test", str(DEMO), "--tier", "native", env={"PATH": str(nothing), "CC": ""})
    assert run.returncode == 0, run.stderr
    assert results(run.stdout)[1] == "6 passed of 6 tests (python)"
    assert "no C compiler or no Python.h here: the native tier was not run, the tests ran on " \
        "Python" in run.stderr  # fmt: skip
    assert "Traceback" not in run.stderr


def test_a_test_file_that_does_not_compile_exits_2_with_its_diagnostic(project: Path) -> None:
    (project / "test" / "x.st").write_text(NOT_COMPILING)
    run = padt("test", str(project))
    assert run.returncode == 2
    assert re.search(r"^test/x\.st:4:1: error: .*nowhere.* \[E\d{4}\]$", run.stderr, re.M)
    assert run.stdout == ""


def test_no_test_exits_5(project: Path) -> None:
    unmatched = padt("test", str(project), "-k", "NoSuchTest")
    assert unmatched.returncode == 5
    assert "no test found" in unmatched.stderr
    shutil.rmtree(project / "test")
    none = padt("test", str(project))
    assert none.returncode == 5
    assert "no test found" in none.stderr


def xmllint_or_skip() -> str:
    """xmllint with the JUnit schema beside it; skips (fails in CI) when either is missing."""
    xmllint = shutil.which("xmllint")
    if xmllint is None or not SCHEMA.is_file():
        message = "xmllint or the JUnit schema missing: run scripts/install-junit-schema.sh"
        if os.environ.get("CI") == "true":
            pytest.fail(f"{message} (make test does; CI never skips it)")
        pytest.skip(message)
    return xmllint


def test_the_junit_xml_is_valid_for_the_junit_schema(project: Path, tmp_path: Path) -> None:
    xmllint = xmllint_or_skip()
    report = tmp_path / "junit.xml"
    run = padt("test", str(project), "--tier", "python", "--junit", str(report))
    assert run.returncode == 1, run.stderr
    checked = subprocess.run(
        [xmllint, "--noout", "--schema", str(SCHEMA), str(report)],
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert checked.returncode == 0, checked.stderr
    root = ET.parse(report).getroot()
    assert (root.get("tests"), root.get("failures")) == ("7", "1")
    assert sorted(suite.get("name") or "" for suite in root) == ["LevelTests", "TankTests"]
    failure = root.find("testsuite[@name='LevelTests']/testcase/failure")
    assert failure is not None and failure.text is not None
    assert "test/level_test.st:5:1: ASSERT_EQUAL failed: the level" in failure.text
    assert "expected 400, actual 500" in failure.text
