"""`padt test PATH...`: the unit tests of a project, written in ST, run on virtual time on
both tiers (docs/testing.md)."""

from __future__ import annotations

import argparse
import sys
import time
from importlib import metadata
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from backend.engineering.testing.coverage.model import Coverage

# exit codes past 0 (all passed) and 1 (a test failed)
TEST_NOT_COMPILED = 2  # the project or its tests do not compile, or bad options
NO_TESTS = 5  # nothing to run (as pytest)

COVERAGE_FORMATS = ("html", "cobertura", "summary")
DEFAULT_HTML = "coverage-html"
DEFAULT_COBERTURA = "coverage.xml"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "paths",
        nargs="+",
        type=Path,
        metavar="PATH",
        help="a project folder (all its tests), or test files or folders below its test/",
    )
    parser.add_argument(
        "-k", dest="pattern", metavar="PATTERN", help="only tests whose Suite.Test contains PATTERN"
    )
    parser.add_argument("--junit", type=Path, metavar="FILE", help="write the results as JUnit XML")
    parser.add_argument(
        "--library",
        action="append",
        type=Path,
        default=[],
        metavar="PATH",
        help="a .st file or folder compiled with the project (repeatable)",
    )
    parser.add_argument(
        "--tier",
        choices=("both", "python", "native"),
        default="both",
        help="run each test on both tiers and compare them (default), or on one",
    )
    parser.add_argument(
        "--coverage",
        action="append",
        choices=COVERAGE_FORMATS,
        default=[],
        help="statement and branch coverage of the POUs, measured on the Python tier: an HTML "
        "report, Cobertura XML or a table after the results (repeatable)",
    )
    parser.add_argument(
        "--coverage-output",
        type=Path,
        metavar="PATH",
        help=f"where --coverage html (a folder, default {DEFAULT_HTML}/) or cobertura (a file, "
        f"default {DEFAULT_COBERTURA}) is written",
    )
    parser.add_argument(
        "-j",
        dest="jobs",
        type=int,
        default=1,
        metavar="N",
        help="run the tests in N worker processes",
    )


def run(args: argparse.Namespace) -> int:
    # imported here: building the command line's parser loads no compiler
    from backend.engineering.project import ProjectError
    from backend.engineering.testing.coverage.of_build import coverage_measured, meter_for
    from backend.engineering.testing.report import (
        failure_text,
        junit_xml,
        result_line,
        summary_line,
        totals,
    )
    from backend.engineering.testing.test_build import build_tests, matching
    from backend.engineering.testing.test_session import run_session
    from backend.engineering.tiers import NO_COMPILER, Tier

    if args.jobs < 1:
        print("padt test: -j takes a number of workers from 1", file=sys.stderr)
        return TEST_NOT_COMPILED
    problem = _coverage_problem(args)
    if problem:
        print(f"padt test: {problem}", file=sys.stderr)
        return TEST_NOT_COMPILED
    try:
        build = build_tests(args.paths, tuple(args.library))
    except ProjectError as exc:
        print(f"padt test: {exc}", file=sys.stderr)
        return TEST_NOT_COMPILED
    for diagnostic in build.diagnostics:
        print(diagnostic, file=sys.stderr)
    if build.artifact is None:
        return TEST_NOT_COMPILED
    cases = matching(build.cases, args.pattern)
    if not cases:
        print(
            "padt test: no test found (docs/testing.md says how tests are written)", file=sys.stderr
        )
        return NO_TESTS
    tiers: tuple[Tier, ...] = ("python", "native") if args.tier == "both" else (args.tier,)
    order = {case: index for index, case in enumerate(cases)}
    results = []
    meter = None
    if args.coverage:
        meter = meter_for(build)
    session = run_session(
        build.artifact, cases, tiers, args.jobs, project=build.folder, coverage=meter
    )
    for result in session:
        results.append(result)
        print(result_line(result))
        if not result.passed:
            print(failure_text(result))
    results.sort(key=lambda r: order[r.case])
    ran = sorted({tier for r in results for tier in r.tiers})
    if "native" in tiers and "native" not in ran:
        instead = ", the tests ran on Python" if tiers == ("native",) else ""
        print(f"padt test: {NO_COMPILER}: the native tier was not run{instead}", file=sys.stderr)
    found = totals(results)
    print(summary_line(found, " and ".join(ran) or "no tier"))
    if args.junit is not None:
        args.junit.write_bytes(junit_xml(results, build.project.name))
    if meter is not None:
        _write_coverage(args, coverage_measured(build, meter), build.folder, build.project.name)
    return 0 if found.passed == found.total else 1


def _coverage_problem(args: argparse.Namespace) -> str:
    if args.coverage and args.tier == "native":
        return "--coverage is measured on the Python tier: not with --tier native"
    written = {"html", "cobertura"} & set(args.coverage)
    if args.coverage_output is not None and len(written) != 1:
        return "--coverage-output goes with one of --coverage html or --coverage cobertura"
    return ""


def _write_coverage(
    args: argparse.Namespace, coverage: Coverage, folder: Path, project: str
) -> None:
    from backend.engineering.testing.coverage.cobertura import cobertura_xml
    from backend.engineering.testing.coverage.html import write_html
    from backend.engineering.testing.coverage.summary import summary_table

    asked = set(args.coverage)
    if "summary" in asked:
        print(summary_table(coverage))
    if "html" in asked:
        pages = args.coverage_output or Path(DEFAULT_HTML)
        write_html(coverage, pages, project)
        print(f"padt test: coverage report in {pages / 'index.html'}")
    if "cobertura" in asked:
        path = args.coverage_output or Path(DEFAULT_COBERTURA)
        path.write_bytes(cobertura_xml(coverage, folder, _padt_version(), _now_ms))
        print(f"padt test: coverage as Cobertura XML in {path}")


def _now_ms() -> int:
    return int(time.time() * 1000)


def _padt_version() -> str:
    try:
        return metadata.version("padt")
    except metadata.PackageNotFoundError:
        return "0"
