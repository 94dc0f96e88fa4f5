"""Statement and branch coverage of `padt test` (docs/testing.md, "Coverage"): the figures of
a small program whose branches the tests take in part, counted by hand from the program;
the same figures from worker processes, as Cobertura XML read by pycobertura, as HTML
pages and as the table `padt test --coverage summary` prints."""

from __future__ import annotations

from pathlib import Path

import pytest
from pycobertura import Cobertura

from backend.engineering.testing.coverage.cobertura import cobertura_xml
from backend.engineering.testing.coverage.html import write_html
from backend.engineering.testing.coverage.measure import CoverageMeter, measured_files
from backend.engineering.testing.coverage.model import Coverage, Figures, coverage_of
from backend.engineering.testing.test_build import UnitTestBuild, build_tests
from backend.engineering.testing.test_session import run_session
from tests.conftest import padt

PADT_TOML = """
[project]
name = "plant"
[resource]
name = "R"
target_cycle_ms = 100
[[resource.program]]
name = "Main"
pou = "Main"
id = 1
priority = 1
[[resource.program]]
name = "Seq"
pou = "Seq"
id = 2
priority = 2
"""

PLANT = """\
FUNCTION Classify : INT
VAR_INPUT x : INT; END_VAR
IF x < 0 THEN
  Classify := -1;
ELSIF x = 0 THEN
  Classify := 0;
ELSE
  Classify := 1;
END_IF;
END_FUNCTION

PROGRAM Main
VAR
  mode : INT;
  out : INT;
  n : INT;
  i : INT;
  sum : INT;
END_VAR
CASE mode OF
  1:
    out := 10;
  2, 3:
    out := 20;
  4..6:
    out := 30;
ELSE
  out := 0;
END_CASE;
FOR i := 1 TO n DO
  sum := sum + i;
END_FOR;
IF mode > 100 THEN
  out := 1;
END_IF;
IF mode = 2 THEN out := 2; END_IF;
END_PROGRAM

PROGRAM Seq
VAR go : BOOL; count : INT; END_VAR
INITIAL_STEP Idle:
END_STEP
TRANSITION FROM Idle TO Run := go;
END_TRANSITION
STEP Run:
  Counting(N);
END_STEP
TRANSITION FROM Run TO Idle := count > 5;
END_TRANSITION
ACTION Counting:
  count := count + 1;
END_ACTION
END_PROGRAM
"""

# Main runs 2 cycles in TestMain and 3 in TestSequence; Seq the same 5
TESTS = """\
FUNCTION_BLOCK PlantTests
METHOD TestClassify
ASSERT_EQUAL(-1, Classify(-3));
ASSERT_EQUAL(1, Classify(5));
END_METHOD
METHOD TestMain
Main.mode := 2;
RUN_CYCLES(1);
Main.mode := 9;
RUN_CYCLES(1);
END_METHOD
METHOD TestSequence
Seq.go := TRUE;
RUN_CYCLES(3);
ASSERT_EQUAL(2, Seq.count, 'Run was active in cycles 2 and 3');
END_METHOD
END_FUNCTION_BLOCK
"""

EXPECTED = {
    # statements: the IF and its three assignments; -1 and 1 ran, the ELSIF's 0 did not.
    # branches: THEN, ELSIF, ELSE; the ELSIF never taken
    "Classify": Figures(statements=4, statements_covered=3, branches=3, branches_covered=2),
    # statements: CASE, its four assignments, FOR, its body, the IF, its THEN, the one-line
    # IF: 10; mode was 2, 9 and 0: CASE, `out := 20`, `out := 0`, FOR (n = 0, body never),
    # the IF (THEN never) and the one-line IF ran: 6.
    # branches: the CASE's 3 cases and ELSE (2 and ELSE taken), the FOR's body (never), the
    # IF's THEN (never) and its implicit ELSE (taken); the one-line IF is left out (its
    # line cannot tell whether its THEN ran): 7, 3 taken
    "Main": Figures(statements=10, statements_covered=6, branches=7, branches_covered=3),
    # statements: the two steps' and the two transitions' lines (a transition's is tested
    # every cycle) and the action's assignment, all ran.
    # branches: both steps were active, Idle to Run fired, Run to Idle (count > 5) never
    "Seq": Figures(statements=5, statements_covered=5, branches=4, branches_covered=3),
}


def line_of(text: str) -> int:
    """The line of PLANT that holds `text`."""
    return next(n for n, line in enumerate(PLANT.splitlines(), 1) if text in line)


def plant_project(folder: Path) -> Path:
    (folder / "test").mkdir(parents=True)
    (folder / "padt.toml").write_text(PADT_TOML)
    (folder / "plant.st").write_text(PLANT)
    (folder / "test" / "plant_test.st").write_text(TESTS)
    return folder


@pytest.fixture(scope="module")
def build(tmp_path_factory: pytest.TempPathFactory) -> UnitTestBuild:
    built = build_tests([plant_project(tmp_path_factory.mktemp("plant"))])
    assert built.artifact is not None, [str(d) for d in built.diagnostics]
    return built


def measured(build: UnitTestBuild, jobs: int) -> Coverage:
    assert build.artifact is not None
    meter = CoverageMeter(measured_files(source.name for source in build.project.sources))
    results = list(run_session(build.artifact, build.cases, ("python",), jobs, coverage=meter))
    assert all(result.passed for result in results), [r.outcome for r in results]
    return coverage_of(build.artifact, build.syntax, build.project.sources, meter.files, meter.hits)


@pytest.fixture(scope="module")
def coverage(build: UnitTestBuild) -> Coverage:
    return measured(build, jobs=1)


def test_the_figures_per_pou_are_those_read_from_the_program(coverage: Coverage) -> None:
    assert [file.file for file in coverage.files] == ["plant.st"]  # not the test file
    pous = {pou.name: pou.figures for pou in coverage.files[0].pous}
    assert pous == EXPECTED
    assert coverage.figures == Figures(19, 14, 14, 8)


def test_each_way_is_taken_as_often_as_the_tests_took_it(coverage: Coverage) -> None:
    branches = {
        (branch.line, branch.label): branch.taken
        for pou in coverage.files[0].pous
        for branch in pou.branches
    }
    case = line_of("CASE mode OF")
    assert [taken for (line, _), taken in branches.items() if line == case] == [0, 1, 0, 4]
    assert branches[(line_of("IF mode > 100"), "THEN")] == 0
    assert branches[(line_of("IF mode > 100"), "implicit ELSE")] == 5  # Main ran 5 cycles
    assert branches[(line_of("IF x < 0"), "ELSIF (line 5)")] == 0
    assert branches[(line_of("FOR i"), "loop body")] == 0
    assert branches[(line_of("INITIAL_STEP Idle"), "step Idle active")] == 3
    assert branches[(line_of("FROM Idle TO Run"), "transition Idle to Run fired")] == 1
    assert branches[(line_of("FROM Run TO Idle"), "transition Run to Idle fired")] == 0
    assert not any(line == line_of("IF mode = 2 THEN") for line, _ in branches)
    lines = coverage.files[0].lines
    assert lines[line_of("CASE mode OF")] == 5
    assert lines[line_of("count := count + 1")] == 2
    assert lines[line_of("Classify := 0")] == 0


def test_worker_processes_measure_their_shares_and_the_counts_add_up(
    build: UnitTestBuild, coverage: Coverage
) -> None:
    assert measured(build, jobs=3).as_json() == coverage.as_json()


def test_the_json_gives_each_files_lines_and_branches(coverage: Coverage) -> None:
    found = coverage.as_json()["files"]["plant.st"]
    assert found["lines"][str(line_of("Classify := -1"))] == 1
    assert {"line": line_of("FOR i"), "label": "loop body", "taken": 0} in found["branches"]
    assert found["figures"]["branches"] == 14


def test_pycobertura_reads_the_cobertura_xml_with_our_figures(
    coverage: Coverage, build: UnitTestBuild, tmp_path: Path
) -> None:
    text = cobertura_xml(coverage, build.folder, "1.0", lambda: 1_700_000_000_000)
    assert text == cobertura_xml(coverage, build.folder, "1.0", lambda: 1_700_000_000_000)
    path = tmp_path / "coverage.xml"
    path.write_bytes(text)
    report = Cobertura(str(path))
    assert report.files() == ["plant.st"]
    assert report.total_statements() == 19
    assert report.line_rate() == pytest.approx(14 / 19, abs=1e-4)
    assert report.branch_rate() == pytest.approx(8 / 14, abs=1e-4)
    # pycobertura counts a line as hit when it ran and all its branches were taken: our
    # HTML's green lines
    file = coverage.files[0]
    ways = file.branches_by_line()
    green = [
        line
        for line, hits in file.lines.items()
        if hits and all(way.taken for way in ways.get(line, []))
    ]
    assert sorted(report.hit_statements("plant.st")) == sorted(green)
    assert report.total_misses() == 19 - len(green)
    assert line_of("Classify := 0") in report.missed_statements("plant.st")
    assert b'timestamp="1700000000000"' in text
    assert b'condition-coverage="50% (2/4)" />' in text  # the CASE


def test_the_html_report_shades_the_source(coverage: Coverage, tmp_path: Path) -> None:
    pages = write_html(coverage, tmp_path / "html", "plant <1>")
    assert [p.name for p in pages] == ["index.html", "plant.st.html"]
    index = pages[0].read_text()
    assert "Coverage of plant &lt;1&gt;" in index and 'href="plant.st.html#L3"' in index
    page = pages[1].read_text()
    assert f'<tr id="L{line_of("IF x < 0")}" class="partial">' in page
    assert "IF x &lt; 0 THEN" in page  # escaped
    assert "2/3 branches taken; never: ELSIF (line 5)" in page
    assert f'<tr id="L{line_of("Classify := 0")}" class="missed">' in page
    assert f'<tr id="L{line_of("Classify := 1")}" class="run">' in page
    assert f'<tr id="L{line_of("VAR_INPUT")}"><td' in page  # a declaration: no statement


def test_padt_test_prints_the_table_and_writes_cobertura(tmp_path: Path) -> None:
    folder = plant_project(tmp_path / "plant")
    xml = tmp_path / "out" / "plant.xml"
    xml.parent.mkdir()
    ran = padt(
        "test", str(folder), "--coverage", "summary", "--coverage", "cobertura",
        "--coverage-output", str(xml), "-j", "2",
    )  # fmt: skip
    assert ran.returncode == 0, ran.stderr
    table = ran.stdout.split(" tests (", 1)[1].splitlines()[1:]
    assert table[:6] == [
        "POU       File      Statements  Branches  Cover",
        "--------  --------  ----------  --------  -----",
        "Classify  plant.st         3/4       2/3    71%",
        "Main      plant.st        6/10       3/7    53%",
        "Seq       plant.st         5/5       3/4    89%",
        "--------  --------  ----------  --------  -----",
    ]
    assert table[6] == "TOTAL                    14/19      8/14    67%"
    assert Cobertura(str(xml)).total_statements() == 19


def test_padt_test_refuses_coverage_without_the_python_tier(tmp_path: Path) -> None:
    folder = plant_project(tmp_path / "plant")
    refused = padt("test", str(folder), "--coverage", "html", "--tier", "native")
    assert refused.returncode == 2
    assert "measured on the Python tier" in refused.stderr
    both = padt("test", str(folder), "--coverage", "html", "--coverage", "cobertura",
                "--coverage-output", str(tmp_path / "x"))  # fmt: skip
    assert both.returncode == 2 and "--coverage-output goes with one" in both.stderr
