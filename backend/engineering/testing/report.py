"""What a test run found, for a terminal (`padt test`) and as JUnit XML for CI systems
(the schema of Jenkins' xUnit plugin, junit-10.xsd, which Jenkins' and GitLab's readers take:
`testsuites` > `testsuite` per suite > `testcase` per test, with `failure` or `error`)."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from collections.abc import Iterable
from dataclasses import dataclass

from backend.engineering.testing.tiers import UnitTestResult


@dataclass(frozen=True)
class Totals:
    passed: int
    failed: int
    errors: int
    seconds: float

    @property
    def total(self) -> int:
        return self.passed + self.failed + self.errors


def totals(results: Iterable[UnitTestResult]) -> Totals:
    listed = list(results)
    count = {
        status: sum(r.outcome.status == status for r in listed)
        for status in ("passed", "failed", "error")
    }
    return Totals(count["passed"], count["failed"], count["error"], sum(r.seconds for r in listed))


def failure_text(result: UnitTestResult) -> str:
    """The lines a failed test prints below its name: where, what, expected and actual."""
    outcome = result.outcome
    where = f"{outcome.place}: " if outcome.place is not None else ""
    lines = [f"  {where}{outcome.message}"]
    if outcome.detail:
        lines.append(f"    {outcome.detail}")
    return "\n".join(lines)


def result_line(result: UnitTestResult) -> str:
    status = {"passed": "PASS", "failed": "FAIL", "error": "ERROR"}[result.outcome.status]
    return f"{status} {result.case.full_name}"


def summary_line(found: Totals, tiers: str) -> str:
    parts = [f"{found.passed} passed"]
    if found.failed:
        parts.append(f"{found.failed} failed")
    if found.errors:
        parts.append(f"{found.errors} errors")
    return f"{', '.join(parts)} of {found.total} tests ({tiers}) in {found.seconds:.2f} s"


def junit_xml(results: list[UnitTestResult], project: str) -> bytes:
    """The JUnit XML of a run: a testsuite per suite, in the order of the results."""
    root = ET.Element("testsuites", name=project)
    suites: dict[str, ET.Element] = {}
    by_suite: dict[str, list[UnitTestResult]] = {}
    for result in results:
        by_suite.setdefault(result.case.suite, []).append(result)
    for suite, listed in by_suite.items():
        found = totals(listed)
        element = ET.SubElement(
            root,
            "testsuite",
            name=suite,
            tests=str(found.total),
            failures=str(found.failed),
            errors=str(found.errors),
            skipped="0",
            time=_seconds(found.seconds),
        )
        suites[suite] = element
        for result in listed:
            case = ET.SubElement(
                element,
                "testcase",
                name=result.case.name,
                classname=suite,
                time=_seconds(result.seconds),
            )
            if result.outcome.status != "passed":
                tag = "failure" if result.outcome.status == "failed" else "error"
                problem = ET.SubElement(case, tag, message=result.outcome.message, type=tag)
                problem.text = failure_text(result).strip()
            # the schema has no place for a test's file and line on its testcase
            declared = f"{result.case.file}:{result.case.line}"
            tiers = ", ".join(result.tiers)
            ET.SubElement(case, "system-out").text = f"{declared}: tiers {tiers}"
    totals_all = totals(results)
    root.set("tests", str(totals_all.total))
    root.set("failures", str(totals_all.failed))
    root.set("errors", str(totals_all.errors))
    root.set("time", _seconds(totals_all.seconds))
    ET.indent(root)
    text: bytes = ET.tostring(root, encoding="utf-8", xml_declaration=True)
    return text + b"\n"


def _seconds(seconds: float) -> str:
    """A time as the schema takes it: at most three decimals."""
    return f"{seconds:.3f}"
