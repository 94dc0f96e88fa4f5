"""Unit tests written in ST (docs/testing.md), run by the engineering service behind
`padt test` on both tiers: asserts of every kind with what a failure says, cycles on virtual
time, forcing, isolation between tests, faults, and the comparison of the tiers."""

from __future__ import annotations

from pathlib import Path

import pytest

from backend.engineering.project import compile_project, load_project
from backend.engineering.testing.test_build import UnitTestBuild, build_tests, matching
from backend.engineering.testing.test_run import Outcome, UnitTestBench, WatchStop
from backend.engineering.testing.tiers import UnitTestResult, run_tests
from runtime.code.native.tier import NativeTier

PADT_TOML = """
[project]
name = "units"
[resource]
name = "R"
target_cycle_ms = 100
[[resource.program]]
name = "Main"
pou = "Main"
id = 1
priority = 1
"""

PROGRAM = """
TYPE Point : STRUCT x : INT; y : REAL; END_STRUCT; END_TYPE
TYPE Mode : (Idle, Busy); END_TYPE
VAR_GLOBAL
  start : BOOL;
  limit : INT := 10;
END_VAR
PROGRAM Main
VAR
  count : INT;
  ratio : REAL;
  name : STRING[20] := 'tank';
  wide : WSTRING := "wide";
  when : TIME := T#1500ms;
  day : DATE := D#2024-02-29;
  bits : WORD := 16#00F0;
  big : LINT := 9000000000;
  values : ARRAY[1..3] OF INT := [1, 2, 3];
  spot : Point := (x := 1, y := 2.5);
  mode : Mode := Idle;
  timer : TON;
  done : BOOL;
  divisor : INT := 1;
  quotient : INT;
END_VAR
IF start THEN
  count := count + 1;
  mode := Busy;
END_IF;
ratio := INT_TO_REAL(count) / 3.0;
timer(IN := start, PT := T#1s);
done := timer.Q;
quotient := 100 / divisor;
END_PROGRAM
"""

# each passes; the names say what they show
PASSING = """
FUNCTION_BLOCK Passing
VAR calls : INT; END_VAR
METHOD SetUp
calls := calls + 1;
END_METHOD
METHOD TestEveryElementaryTypeStringsArraysAndStructures
VAR expected : Point; values : ARRAY[1..3] OF INT := [1, 2, 3]; END_VAR
ASSERT_EQUAL(0, Main.count);
ASSERT_EQUAL('tank', Main.name, 'a STRING');
ASSERT_EQUAL("wide", Main.wide, 'a WSTRING');
ASSERT_EQUAL(T#1s500ms, Main.when, 'a TIME');
ASSERT_EQUAL(D#2024-02-29, Main.day, 'a DATE');
ASSERT_EQUAL(16#00F0, Main.bits, 'a WORD');
ASSERT_EQUAL(9000000000, Main.big, 'a LINT');
ASSERT_EQUAL(values, Main.values, 'an array');
expected.x := 1;
expected.y := 2.5;
ASSERT_EQUAL(expected, Main.spot, 'a structure');
ASSERT_EQUAL(Idle, Main.mode, 'an enumeration');
ASSERT_NOT_EQUAL(Busy, Main.mode);
ASSERT_FALSE(Main.done);
ASSERT_EQUAL(1, calls, 'SetUp ran once, on a fresh suite');
END_METHOD
METHOD TestCyclesOnVirtualTime
start := TRUE;
RUN_CYCLES(3);
ASSERT_EQUAL(3, Main.count);
ASSERT_NEAR(1.0, Main.ratio, 0.000001, 'a REAL within a tolerance');
ASSERT_EQUAL(Busy, Main.mode);
RUN_UNTIL(Main.done, T#2s);
ASSERT_EQUAL(UDINT#11, TEST_CYCLES(), 'the timer ends in the cycle at 1 s');
RUN_FOR(T#250ms);
ASSERT_EQUAL(UDINT#14, TEST_CYCLES(), '250 ms are three cycles of 100 ms');
END_METHOD
METHOD TestEachTestStartsFromAColdStart
ASSERT_EQUAL(0, Main.count, 'no count left by the test before');
ASSERT_FALSE(start);
ASSERT_EQUAL(UDINT#0, TEST_CYCLES());
END_METHOD
METHOD TestAForcedInputOverrulesWrites
FORCE(start, TRUE);
start := FALSE;
RUN_CYCLES(2);
ASSERT_EQUAL(2, Main.count, 'the forced input counted twice');
RELEASE(start);
start := FALSE;
RUN_CYCLES(1);
ASSERT_EQUAL(2, Main.count, 'released');
END_METHOD
END_FUNCTION_BLOCK
"""

FAILING = """
FUNCTION_BLOCK Failing
METHOD TestAnInteger
ASSERT_EQUAL(4, Main.count + 3, 'the count');
END_METHOD
METHOD TestAReal
ASSERT_NEAR(0.5, Main.ratio, 0.01, 'the ratio');
END_METHOD
METHOD TestAString
ASSERT_EQUAL('pump', Main.name);
END_METHOD
METHOD TestAnArray
VAR wanted : ARRAY[1..3] OF INT := [1, 2, 4]; END_VAR
ASSERT_EQUAL(wanted, Main.values, 'the values');
END_METHOD
METHOD TestATime
ASSERT_EQUAL(T#2s, Main.when);
END_METHOD
METHOD TestACondition
ASSERT_TRUE(Main.done, 'done at once');
END_METHOD
METHOD TestFail
FAIL('not written yet');
END_METHOD
METHOD TestAConditionThatNeverComes
RUN_UNTIL(Main.done, T#500ms);
END_METHOD
METHOD TestAProgramThatFaults
Main.divisor := 0;
RUN_CYCLES(5);
END_METHOD
METHOD TestCodeOfTheTestThatFaults
VAR zero, n : INT; END_VAR
n := 10 / zero;
END_METHOD
METHOD TestTheFirstFailedAssertEndsTheTest
ASSERT_TRUE(FALSE, 'first');
ASSERT_TRUE(FALSE, 'second');
END_METHOD
END_FUNCTION_BLOCK
"""


def project(folder: Path, **tests: str) -> Path:
    (folder / "test").mkdir(parents=True)
    (folder / "padt.toml").write_text(PADT_TOML)
    (folder / "main.st").write_text(PROGRAM)
    for name, text in tests.items():
        (folder / "test" / f"{name}.st").write_text(text)
    return folder


@pytest.fixture(scope="module")
def build(tmp_path_factory: pytest.TempPathFactory) -> UnitTestBuild:
    folder = project(tmp_path_factory.mktemp("units"), passing=PASSING, failing=FAILING)
    built = build_tests([folder])
    assert built.artifact is not None, [str(d) for d in built.diagnostics]
    return built


@pytest.fixture(scope="module")
def results(build: UnitTestBuild, native_tier: NativeTier) -> dict[str, UnitTestResult]:
    tier = NativeTier(native_tier.cache, native_tier.toolchain)
    assert build.artifact is not None
    ran = run_tests(build.artifact, build.cases, ("python", "native"), tier)
    return {result.case.full_name: result for result in ran}


def test_every_test_is_found_by_suite_and_name(build: UnitTestBuild) -> None:
    names = [case.full_name for case in build.cases]
    assert names == sorted(names, key=str.upper)
    assert len(names) == 4 + 11
    assert [c.full_name for c in matching(build.cases, "passing.testcycles")] == [
        "Passing.TestCyclesOnVirtualTime"
    ]
    assert len(matching(build.cases, "*Assert*")) == 1


def test_passing_tests_pass_on_both_tiers(results: dict[str, UnitTestResult]) -> None:
    for name, result in results.items():
        if name.startswith("Passing."):
            assert result.passed, (name, result.outcome)
            assert result.tiers == ("python", "native")


@pytest.mark.parametrize(
    ("test", "line", "message", "detail"),
    [
        ("TestAnInteger", 4, "ASSERT_EQUAL failed: the count", "expected 4, actual 3"),
        ("TestAReal", 7, "ASSERT_NEAR failed: the ratio", "expected 0.5 within 0.01, actual 0.0"),
        ("TestAString", 10, "ASSERT_EQUAL failed", "expected 'pump', actual 'tank'"),
        (
            "TestAnArray",
            14,
            "ASSERT_EQUAL failed: the values",
            "expected [1, 2, 4], actual [1, 2, 3]",
        ),
        ("TestATime", 17, "ASSERT_EQUAL failed", "expected T#2s, actual T#1s500ms"),
        ("TestACondition", 20, "ASSERT_TRUE failed: done at once", "expected TRUE, actual FALSE"),
        ("TestFail", 23, "FAIL failed: not written yet", ""),
        (
            "TestTheFirstFailedAssertEndsTheTest",
            37,
            "ASSERT_TRUE failed: first",
            "expected TRUE, actual FALSE",
        ),
    ],
)
def test_a_failed_assert_names_its_place_expected_and_actual(
    results: dict[str, UnitTestResult], test: str, line: int, message: str, detail: str
) -> None:
    outcome = results[f"Failing.{test}"].outcome
    assert outcome.status == "failed"
    assert str(outcome.place) == f"test/failing.st:{line}:1"
    assert outcome.message == message
    assert outcome.detail == detail


def test_run_until_fails_when_its_time_passes(results: dict[str, UnitTestResult]) -> None:
    outcome = results["Failing.TestAConditionThatNeverComes"].outcome
    assert outcome.status == "failed"
    assert outcome.message == "RUN_UNTIL: the condition was not TRUE within T#500ms"
    assert outcome.cycles == 5
    assert str(outcome.place) == "test/failing.st:26:1"


def test_a_program_that_faults_fails_the_test_where_it_ran_cycles(
    results: dict[str, UnitTestResult],
) -> None:
    outcome = results["Failing.TestAProgramThatFaults"].outcome
    assert outcome.status == "failed"
    assert outcome.message == "cycle 1: program Main faulted"
    assert "division by zero" in outcome.detail
    assert str(outcome.place) == "test/failing.st:30:1"


def test_code_of_the_test_that_faults_is_an_error_at_its_line(
    results: dict[str, UnitTestResult],
) -> None:
    outcome = results["Failing.TestCodeOfTheTestThatFaults"].outcome
    assert outcome.status == "error"
    assert "division by zero" in outcome.message.lower()
    assert outcome.place is not None
    assert (outcome.place.file, outcome.place.line) == ("test/failing.st", 34)


def test_the_tests_never_reach_the_configuration(build: UnitTestBuild) -> None:
    downloaded = compile_project(load_project([build.folder]))
    assert downloaded.artifact is not None
    assert "PASSING" not in {pou.name.upper() for pou in downloaded.artifact.pous}
    assert all(
        not source.name.startswith("test/") for source in load_project([build.folder]).sources
    )


def test_a_difference_between_the_tiers_fails_with_its_cycle_and_variable(
    tmp_path: Path, native_tier: NativeTier
) -> None:
    """Two builds that differ in one initial value stand for two tiers that disagree: the
    native run is compared with the other's cycles as `run_tests` compares the tiers."""
    one = build_tests([project(tmp_path / "one", passing=PASSING)])
    other_program = PROGRAM.replace(
        "ratio := INT_TO_REAL(count) / 3.0;",
        "ratio := INT_TO_REAL(count) / 3.0;\nIF count = 2 THEN count := 7; END_IF;",
    )
    other_folder = project(tmp_path / "other", passing=PASSING)
    (other_folder / "main.st").write_text(other_program)
    other = build_tests([other_folder])
    assert one.artifact is not None and other.artifact is not None
    case = next(c for c in one.cases if c.name == "TestCyclesOnVirtualTime")
    cycles: list[dict[str, object]] = []
    reference = UnitTestBench(one.artifact, None).run(case, lambda _, values: cycles.append(values))
    assert reference.status == "passed"
    from backend.engineering.testing.tiers import _comparer

    types = {v.path: v.type for v in UnitTestBench(one.artifact, None).resource.variables.infos()}
    native = UnitTestBench(other.artifact, NativeTier(native_tier.cache, native_tier.toolchain))
    with pytest.raises(WatchStop) as stopped:
        native.run(case, _comparer(cycles, types))
    assert str(stopped.value) == (
        "the tiers disagree after cycle 2: Main.count is 2 on Python, 7 on native"
    )


def test_on_the_native_tier_what_translates_runs_as_c(
    build: UnitTestBuild, native_tier: NativeTier
) -> None:
    assert build.artifact is not None
    bench = UnitTestBench(build.artifact, NativeTier(native_tier.cache, native_tier.toolchain))
    assert "TON" in bench.native_bodies  # Main has strings and enums: Python (issue 34)
    case = next(c for c in build.cases if c.name == "TestCyclesOnVirtualTime")
    outcome: Outcome = bench.run(case)
    assert (outcome.status, outcome.cycles) == ("passed", 14)


TWO_PROGRAMS_TOML = (
    PADT_TOML
    + """
[[resource.program]]
name = "Watcher"
pou = "Watcher"
id = 2
priority = 2
"""
)

WATCHER = """
PROGRAM Watcher
VAR seen : INT; END_VAR
IF start THEN seen := seen + 1; END_IF;
END_PROGRAM
"""

SHARED_AND_PARAMETERISED = """
TYPE AddCase : STRUCT a, b, sum : INT; END_STRUCT; END_TYPE
FUNCTION_BLOCK Shared
VAR
  timer : TON;
  TestAdd_Cases : ARRAY[0..2] OF AddCase :=
    [(a := 1, b := 2, sum := 3), (a := 2, b := 2, sum := 4), (a := -1, b := 1, sum := 1)];
END_VAR
METHOD TestBothProgramsSeeTheGlobalsATestWrites
start := TRUE;
RUN_CYCLES(2);
ASSERT_EQUAL(2, Main.count);
ASSERT_EQUAL(2, Watcher.seen);
start := FALSE;
RUN_CYCLES(1);
ASSERT_EQUAL(2, Watcher.seen, 'the write reached the second program too');
END_METHOD
METHOD TestATimerOfTheSuiteRunsOnTheTestsClock
timer(IN := TRUE, PT := T#300ms);
RUN_CYCLES(3);
timer(IN := TRUE, PT := T#300ms);
ASSERT_TRUE(timer.Q, '300 ms after the start of the test');
END_METHOD
METHOD TestAdd
VAR_INPUT case : AddCase; END_VAR
ASSERT_EQUAL(case.sum, case.a + case.b, 'the sum');
END_METHOD
METHOD TestWithoutCases
VAR_INPUT n : INT; END_VAR
END_METHOD
END_FUNCTION_BLOCK
"""


def test_globals_clock_and_parameterised_tests(tmp_path: Path, native_tier: NativeTier) -> None:
    folder = project(tmp_path, shared=SHARED_AND_PARAMETERISED)
    (folder / "padt.toml").write_text(TWO_PROGRAMS_TOML)
    (folder / "watcher.st").write_text(WATCHER)
    built = build_tests([folder])
    assert built.artifact is not None, [str(d) for d in built.diagnostics]
    tier = NativeTier(native_tier.cache, native_tier.toolchain)
    # the clock test runs after a test that ran cycles: time starts again at 0
    ran = run_tests(built.artifact, built.cases, ("python", "native"), tier)
    results = {r.case.full_name: r.outcome for r in ran}
    assert list(results) == [
        "Shared.TestAdd[0]",
        "Shared.TestAdd[1]",
        "Shared.TestAdd[2]",
        "Shared.TestATimerOfTheSuiteRunsOnTheTestsClock",
        "Shared.TestBothProgramsSeeTheGlobalsATestWrites",
        "Shared.TestWithoutCases",
    ]
    assert [results[f"Shared.TestAdd[{i}]"].status for i in range(3)] == ["passed"] * 2 + ["failed"]
    assert results["Shared.TestAdd[2]"].detail == "expected 1, actual 0"
    assert results["Shared.TestATimerOfTheSuiteRunsOnTheTestsClock"].status == "passed"
    assert results["Shared.TestBothProgramsSeeTheGlobalsATestWrites"].status == "passed"
    problem = results["Shared.TestWithoutCases"]
    assert problem.status == "error"
    assert problem.message == (
        "TestWithoutCases takes an input: declare TestWithoutCases_Cases, an array of its "
        "cases, in the suite"
    )
    assert [c.full_name for c in matching(built.cases, "testadd[1]")] == ["Shared.TestAdd[1]"]
