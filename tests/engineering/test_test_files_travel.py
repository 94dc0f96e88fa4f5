"""A project's tests (its `test/` folder, docs/testing.md) travel with the project and never
reach a downloaded configuration: a new project from the tank template brings them and they
pass; the download's artifact is the same with and without them; its backup keeps them, and
a project rebuilt from it has them, while the documentation and the online change's source
diff show only the configuration's files; the browser's tree shows them apart, and a
PLCopen import over the project leaves them. The editor's language services read a test
file as `padt test` compiles it (tests/lsp/test_lsp_test_files.py has the rest)."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from backend.compiler.language.hover import TEST_FUNCTION_HELP
from backend.compiler.test_functions import TEST_FUNCTIONS
from backend.engineering.backup import restore_backup
from backend.engineering.compile_gate import CheckedCompile, compile_checked
from backend.engineering.documentation.document import document_html
from backend.engineering.documentation.subject import load_subject
from backend.engineering.download import keep_backup
from backend.engineering.language_service import ProjectLanguage
from backend.engineering.online_change import running_sources
from backend.engineering.project import demo_project_path
from backend.engineering.project_tree import read_tree
from frontend.project_tree_view import render
from tests.conftest import padt

TESTS = "test/tank_test.st"
FIXTURES = Path(__file__).parent / "plcopen" / "fixtures"
TWICE = """FUNCTION Twice : INT
VAR_INPUT x : INT; END_VAR
Twice := 2 * x;
END_FUNCTION
PROGRAM Main
VAR y : INT; END_VAR
y := Twice(3);
END_PROGRAM
"""
TWICE_TEST = """FUNCTION_BLOCK TwiceTests
METHOD TestTwice
ASSERT_EQUAL(4, Twice(2), 'twice 2');
END_METHOD
END_FUNCTION_BLOCK
"""


@pytest.fixture
def demo(tmp_path: Path) -> Path:
    return Path(shutil.copytree(demo_project_path(), tmp_path / "demo"))


@pytest.fixture(scope="module")
def checked(tmp_path_factory: pytest.TempPathFactory) -> CheckedCompile:
    folder = tmp_path_factory.mktemp("gate") / "demo"
    shutil.copytree(demo_project_path(), folder)
    return compile_checked([folder])


def test_a_project_from_the_tank_template_brings_its_tests_and_they_pass(tmp_path: Path) -> None:
    made = padt("new", "mytank", "--template", "tank", "--dir", str(tmp_path))
    assert made.returncode == 0, made.stderr
    folder = tmp_path / "mytank"
    assert (folder / TESTS).read_text() == (demo_project_path() / TESTS).read_text()
    run = padt("test", str(folder))
    assert run.returncode == 0, run.stdout + run.stderr
    assert "TankTests.TestThePumpStopsAtTheHighLevel" in run.stdout


def test_the_download_holds_no_test_and_has_the_crc_of_the_project_without_them(
    checked: CheckedCompile, tmp_path: Path
) -> None:
    assert not [p.name for p in checked.artifact.pous if p.name.upper() == "TANKTESTS"]
    assert [s.name for s in checked.project.sources] == ["tank.st"]
    without = Path(shutil.copytree(demo_project_path(), tmp_path / "without"))
    shutil.rmtree(without / "test")
    assert compile_checked([without]).artifact.crc == checked.artifact.crc
    compiled = padt("compile", str(without))
    assert checked.artifact.crc in compiled.stdout  # as `padt compile` says of the folder


def test_the_backup_keeps_the_tests_the_documentation_and_the_diff_do_not_show_them(
    checked: CheckedCompile, tmp_path: Path
) -> None:
    kept = keep_backup(checked, tmp_path / "backups", "Tank1", "load", "padt load")
    assert kept.path is not None, kept.error
    _, files = restore_backup(kept.path)
    assert files[TESTS] == (demo_project_path() / TESTS).read_text()
    assert set(files) == {"padt.toml", "tank.st", TESTS}

    # documented from the backup: its sources prove the CRC; no test is printed
    subject = load_subject([kept.path])
    assert subject.crc == checked.artifact.crc
    html = document_html(subject, None)
    assert "TankControl" in html and "TankTests" not in html and TESTS not in html

    # the sources of the running configuration, for an online change's diff: no test file
    running = running_sources(checked.artifact.crc, tmp_path / "backups", {})
    assert running is not None and set(running.files) == {"padt.toml", "tank.st"}


def test_the_tree_shows_the_tests_apart_from_the_project_s_pous(demo: Path) -> None:
    tree = read_tree(demo, "demo")
    assert TESTS in [f.path for f in tree.files]  # listed, and opened in the editor by a click
    html = render(tree, None)
    blocks = html.split('data-testid="tree-pous-function_block"', 1)[1].split("</details>")[0]
    tests = html.split('data-testid="tree-tests"', 1)[1].split("</details>")[0]
    assert "TankTests" not in blocks
    assert f'data-tree="file:TankTests@{TESTS}:4"' in tests
    assert "demo: 1 POUs, 0 types, 3 files" in html


def test_a_plcopen_import_over_the_project_leaves_its_tests(demo: Path) -> None:
    run = padt("import", str(FIXTURES / "plant.xml"), "-o", str(demo), "--force")
    assert run.returncode == 0, run.stderr
    assert not (demo / "tank.st").exists()
    assert (demo / TESTS).read_text() == (demo_project_path() / TESTS).read_text()


def test_every_test_function_is_explained_on_hover() -> None:
    assert set(TEST_FUNCTION_HELP) == set(TEST_FUNCTIONS)


def test_the_editor_s_problems_of_a_test_file_are_its_own(demo: Path) -> None:
    language = ProjectLanguage(demo)
    assert language.problems() == []
    tests = (demo / TESTS).read_text()
    language.open(TESTS, tests.replace("RUN_CYCLES(1);", "RUN_CYCLES(TRUE);", 1))
    [problem] = language.problems()
    assert problem.file == TESTS and "RUN_CYCLES" in problem.message
    assert language.diagnostics("tank.st") == []


def test_a_rename_in_the_project_s_file_renames_the_tests_uses(tmp_path: Path) -> None:
    (tmp_path / "twice.st").write_text(TWICE)
    (tmp_path / "test").mkdir()
    (tmp_path / "test" / "twice_test.st").write_text(TWICE_TEST)
    language = ProjectLanguage(tmp_path)
    assert language.problems() == []
    renamed = language.rename("twice.st", 1, len("FUNCTION ") + 1, "Double")
    assert {edits.file for edits in renamed.files} == {"twice.st", "test/twice_test.st"}, (
        renamed.refusal
    )
