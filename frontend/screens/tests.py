"""The Tests screen: the unit tests of the project chosen in the navigation (docs/testing.md)
as a test explorer. Its suites and tests are listed (read again each time the tab is
opened); Run all, Run suite and Run test run them on the server's test runs (a process of
their own per run, at most a few at a time on the UI server) while a thread of this
browser waits; each result shows its mark, its time, and for a failure the message,
expected and actual and `file:line:col`, which a click opens in the editor at that place.
"""

from __future__ import annotations

import html
import logging
import threading
import time
from dataclasses import dataclass, field
from typing import Any

import viser

from backend.engineering.padt_levels import PADT_LEVELS
from backend.engineering.testing.project_tests import TierChoice, UnitTestChoice, list_tests
from frontend.gui_value import set_value
from frontend.page_clicks import Click
from frontend.screen_registry import Now, Screen, Work
from runtime.contract.refusal import Refusal

log = logging.getLogger("padt.ui")

NO_SUITE = "(no test suite)"
TIERS: dict[str, TierChoice] = {"Python and native": "both", "Python": "python", "Native": "native"}
# a refresh after this long without one: the tab was just opened, the list is read again
OPENED_AFTER_S = 2.0
# status -> (mark, word, colour): the marks of the rest of the UI, never colour alone
MARKS = {
    "passed": ("✓", "PASS", "#2b8a3e"),
    "failed": ("✗", "FAIL", "#c92a2a"),
    "error": ("!", "ERROR", "#e67700"),
    "not_run": ("-", "NOT RUN", "#868e96"),
    "": ("·", "not run", "#868e96"),
}
_MUTED = "#868e96"
_RED = "#c92a2a"
_CELL = "padding:2px 6px;vertical-align:top"
_LINK = "color:#1864ab;cursor:pointer;text-decoration:underline;font-family:monospace"


@dataclass
class Found:
    """What this browser knows of the project's tests: the list, the last results, and the
    run under way; written by the threads, drawn by the refresher."""

    project: str | None = None  # whose tests these are
    tests: list[dict[str, Any]] = field(default_factory=list)  # id, suite, name, file, line
    results: dict[str, dict[str, Any]] = field(default_factory=dict)  # by test id
    diagnostics: list[dict[str, Any]] = field(default_factory=list)  # the build's errors
    report: dict[str, Any] | None = None  # the last run's report
    coverage: list[tuple[str, dict[str, Any]]] = field(default_factory=list)  # by file
    listing: bool = False
    running: tuple[int, int] | None = None  # tests ended, planned (-1: building)
    said: tuple[str, str] = ("", "")  # a message and its colour
    version: int = 0  # changed with each change: the screen is drawn again


@dataclass
class TestsScreen:
    suite: viser.GuiDropdownHandle[str]
    test: viser.GuiDropdownHandle[str]
    tier: viser.GuiDropdownHandle[str]
    run_all: viser.GuiButtonHandle
    run_suite: viser.GuiButtonHandle
    run_test: viser.GuiButtonHandle
    run_coverage: viser.GuiButtonHandle
    status: viser.GuiHtmlHandle
    results: viser.GuiHtmlHandle
    allowed: bool
    found: Found = field(default_factory=Found)
    lock: threading.Lock = field(default_factory=threading.Lock)
    drawn: int = -1  # the version of `found` drawn
    last_refresh: float = 0.0


class Tests(Screen):
    name = "Tests"
    icon = viser.Icon.CHECKLIST

    def __init__(self, work: Work) -> None:
        super().__init__(work)
        gui = work.gui
        allowed = PADT_LEVELS.index(work.level) >= PADT_LEVELS.index("read-write")
        gui.add_html(
            '<div style="color:#495057;font-size:0.9em">The unit tests in the test/ folder of '
            "the project chosen on the left, each run from a cold start on virtual time, on "
            "the Python and the native tier. A failure's place opens in the editor.</div>"
        )
        suite = gui.add_dropdown("Suite", (NO_SUITE,))
        test = gui.add_dropdown("Test", (NO_SUITE,))
        tier = gui.add_dropdown("Tiers", tuple(TIERS))
        why = None if allowed else "running tests needs Read+Write on the PADT"
        # pressable once the tab is open and the project's tests are read (`refresh`): all
        # screens are made at the login, and a press before that would find no list
        run_all = gui.add_button("Run all", color="blue", disabled=True, hint=why)
        run_suite = gui.add_button("Run suite", disabled=True, hint=why)
        run_test = gui.add_button("Run test", disabled=True, hint=why)
        covered = why or "run all and shade the lines they ran in the editor (Python tier)"
        run_coverage = gui.add_button("Run with coverage", disabled=True, hint=covered)
        status = gui.add_html("")
        results = gui.add_html("")
        self.screen = TestsScreen(
            suite, test, tier, run_all, run_suite, run_test, run_coverage, status, results, allowed
        )
        suite.on_update(lambda _: self._offer_tests())
        run_all.on_click(lambda _: self._start(UnitTestChoice()))
        run_suite.on_click(lambda _: self._start(UnitTestChoice(self._suite())))
        run_test.on_click(lambda _: self._start(UnitTestChoice(self._suite(), self._test())))
        run_coverage.on_click(lambda _: self._start(UnitTestChoice(coverage=True)))

    # ---- drawing
    def refresh(self, now: Now) -> None:
        screen = self.screen
        moment = time.monotonic()
        project = self.work.project()
        opened = moment - screen.last_refresh > OPENED_AFTER_S
        screen.last_refresh = moment
        with screen.lock:
            if project != screen.found.project or (opened and screen.found.running is None):
                self._list(project)
            found = screen.found
            if found.version == screen.drawn:
                return
            screen.drawn = found.version
            status, results = render_status(found, screen.allowed), render_results(found)
            busy = found.running is not None or found.listing
            suites = _suites(found.tests)
        screen.status.content = status
        screen.results.content = results
        for button in (screen.run_all, screen.run_suite, screen.run_test, screen.run_coverage):
            disabled = busy or not screen.allowed or not suites
            if button.disabled != disabled:
                button.disabled = disabled
        options = tuple(suites) or (NO_SUITE,)
        if tuple(screen.suite.options) != options:
            screen.suite.options = options  # keeps the choice when it is still there
            self._offer_tests()

    def _offer_tests(self) -> None:
        with self.screen.lock:
            names = tuple(
                t["name"] for t in self.screen.found.tests if t["suite"] == self.screen.suite.value
            )
        options = tuple(dict.fromkeys(names)) or (NO_SUITE,)  # a parameterised test once
        if tuple(self.screen.test.options) != options:
            self.screen.test.options = options

    def _suite(self) -> str | None:
        value = self.screen.suite.value
        return None if value == NO_SUITE else value

    def _test(self) -> str | None:
        value = self.screen.test.value
        return None if value == NO_SUITE else value

    # ---- listing and running, each on a thread of its own
    def _list(self, project: str | None) -> None:
        """Read the project's tests again (called with the lock held)."""
        found = self.screen.found
        if project != found.project:
            self.screen.found = found = Found(project)
        if project is None or found.listing:
            return
        found.listing = True
        found.version += 1
        folder = self.work.context.shelf.folder(project)

        def read() -> None:
            try:
                listing = list_tests(folder)
                problem = ("", "")
            except Refusal as refused:
                listing, problem = None, (refused.message, _RED)
            except Exception:  # the screen stays usable whatever went wrong
                log.exception("listing the tests of %s failed", project)
                listing, problem = None, ("the tests could not be read (see the log)", _RED)
            with self.screen.lock:
                if self.screen.found is not found:
                    return  # another project was chosen meanwhile
                found.listing = False
                found.version += 1
                if listing is None:
                    found.said = problem
                    return
                found.tests = listing.tests
                if not listing.compiled:
                    found.diagnostics = [d for d in listing.diagnostics if d["severity"] == "error"]
                    found.said = ("The project or its tests do not compile.", _RED)
                elif found.diagnostics:
                    found.diagnostics, found.said = [], ("", "")

        threading.Thread(target=read, daemon=True, name="padt-tests-list").start()

    def _start(self, choice: UnitTestChoice) -> None:
        screen = self.screen
        project = self.work.project()
        if not screen.allowed or project is None:
            return
        tier = TIERS.get(screen.tier.value, "both")
        if choice.coverage and tier == "native":
            tier = "python"  # coverage is measured on the Python tier
        chosen = UnitTestChoice(choice.suite, choice.test, tier, choice.coverage)
        with screen.lock:
            if screen.found.project != project:  # chosen on the left since the last list
                screen.found = Found(project)
            found = screen.found
            if found.running is not None:
                return  # the buttons are disabled while a run is under way
            found.running = (0, -1)
            found.said = ("", "")
            found.version += 1
        folder = self.work.context.shelf.folder(project)

        def heard(done: int, planned: int, result: dict[str, Any] | None) -> None:
            with screen.lock:
                found.running = (done, planned)
                if result is not None:
                    found.results[result["id"]] = result
                found.version += 1

        def run() -> None:
            try:
                report = self.work.context.test_runs.run(folder, chosen, heard)
                said = _outcome(report)
            except Refusal as refused:
                report, said = None, (refused.message, _RED)
            except Exception:  # the screen stays usable whatever went wrong
                log.exception("a test run of %s failed", project)
                report, said = None, ("the tests could not be run (see the log)", _RED)
            with screen.lock:
                found.running = None
                found.said = said
                found.version += 1
                if report is None:
                    return
                found.report = report
                found.diagnostics = [d for d in report["diagnostics"] if d["severity"] == "error"]
                for result in report["tests"]:
                    found.results[result["id"]] = result
                if choice.suite is None and report["compiled"]:  # all: the list as run
                    found.tests = [_listed(result) for result in report["tests"]]
                measured = report["coverage"] or {"files": {}}
                found.coverage = sorted(measured["files"].items())
            # the editor shades the lines as the last run measured them: none without coverage
            self.work.show_coverage(project, measured["files"])

        threading.Thread(target=run, daemon=True, name="padt-tests-run").start()

    # ---- a click on a test or on a place
    def clicked(self, click: Click) -> None:
        if click.kind != "test":
            return
        what, _, number = click.name.partition(":")
        if not number.isdigit():
            return
        with self.screen.lock:
            found = self.screen.found
            index = int(number)
            if what == "pick" and index < len(found.tests):
                picked = found.tests[index]
                suite, name = picked["suite"], picked["name"]
            elif what == "goto" and index < len(found.tests):
                result = found.results.get(found.tests[index]["id"])
                place = result and result["place"]
                if not place or found.project is None:
                    return
                self.work.open_in_editor(found.project, place["file"], place["line"], place["col"])
                return
            elif what == "cover" and index < len(found.coverage) and found.project is not None:
                file, measured = found.coverage[index]
                line = _first_uncovered(measured)
                self.work.open_in_editor(found.project, file, line, 1)
                return
            elif what == "problem" and index < len(found.diagnostics):
                d = found.diagnostics[index]
                if found.project is not None:
                    self.work.open_in_editor(found.project, d["file"], d["line"], d["col"])
                return
            else:
                return
        set_value(self.screen.suite, suite)
        self._offer_tests()
        set_value(self.screen.test, name)


def _first_uncovered(measured: dict[str, Any]) -> int:
    """Where to look first in a file: its first line never run, else its first line run."""
    lines = sorted((int(line), hits) for line, hits in measured["lines"].items())
    never = [line for line, hits in lines if hits == 0]
    return never[0] if never else lines[0][0] if lines else 1


def _listed(result: dict[str, Any]) -> dict[str, Any]:
    return {k: result[k] for k in ("id", "suite", "name", "file", "line")}


def _suites(tests: list[dict[str, Any]]) -> list[str]:
    return list(dict.fromkeys(t["suite"] for t in tests))


def _outcome(report: dict[str, Any]) -> tuple[str, str]:
    """What the screen says after a run, beside its results."""
    if not report["compiled"]:
        return "The project or its tests do not compile.", _RED
    if report["stopped"]:
        return str(report["stopped"]), _RED
    return " ".join(report["notes"]), _MUTED


# ---- HTML


def render_status(found: Found, allowed: bool) -> str:
    """The line above the results: what is under way, the totals of the last run, or
    what stands in the way."""
    parts = []
    if found.project is None:
        parts.append("Choose a project on the left.")
    elif found.running is not None:
        done, planned = found.running
        parts.append(
            "Building the tests ..."
            if planned < 0
            else f"Running: {done} of {planned} test{'s' * (planned != 1)} ended ..."
        )
    elif found.listing and not found.tests:
        parts.append("Reading the tests ...")
    elif found.report is not None and found.report["compiled"]:
        parts.append(_totals(found.report))
    elif found.tests:
        suites = len(_suites(found.tests))
        parts.append(
            f"{len(found.tests)} test{'s' * (len(found.tests) != 1)} in {suites} "
            f"suite{'s' * (suites != 1)}: not run yet."
        )
    elif found.project is not None and not found.listing and not found.said[0]:
        parts.append("No tests: a test suite is a FUNCTION_BLOCK of a .st file below test/.")
    text = f'<div data-testid="tests-status">{html.escape(" ".join(parts))}</div>'
    message, colour = found.said
    if message:
        text += (
            f'<div data-testid="tests-message" style="color:{colour}">{html.escape(message)}</div>'
        )
    if not allowed:
        text += (
            f'<div data-testid="tests-note" style="color:{_MUTED}">Running tests needs '
            "Read+Write on the PADT.</div>"
        )
    return text


def _totals(report: dict[str, Any]) -> str:
    totals = report["totals"]
    parts = [f"{totals['passed']} passed"]
    for key, word in (("failed", "failed"), ("errors", "errors"), ("not_run", "not run")):
        if totals[key]:
            parts.append(f"{totals[key]} {word}")
    tiers = " and ".join(report["tiers"]) or "no tier"
    seconds = totals["seconds"]
    tests = f"{totals['total']} test{'s' * (totals['total'] != 1)}"
    return f"{', '.join(parts)} of {tests} ({tiers}) in {seconds:.2f} s."


def render_results(found: Found) -> str:
    """The explorer: the tests by suite, each with its last result; a failure's message,
    expected and actual and its place below it; the build's errors when it failed."""
    rows: list[str] = []
    for index, d in enumerate(found.diagnostics):
        place = f"{d['file']}:{d['line']}:{d['col']}"
        rows.append(
            f'<tr data-problem="{index}"><td style="{_CELL};color:{_RED}">{html.escape(d["code"])}'
            f'</td><td style="{_CELL}" colspan="2"><span data-test-click="problem:{index}" '
            f'style="{_LINK}">{html.escape(place)}</span> {html.escape(d["message"])}</td></tr>'
        )
    suite = None
    for index, test in enumerate(found.tests):
        if test["suite"] != suite:
            suite = test["suite"]
            rows.append(_suite_row(suite, found))
        rows.append(_test_rows(index, test, found.results.get(test["id"])))
    if not rows:
        return ""
    return (
        '<table data-testid="tests-results" style="border-collapse:collapse;width:100%;'
        'font-size:0.9em;table-layout:fixed"><colgroup><col style="width:92px"><col>'
        f'<col style="width:56px"></colgroup>{"".join(rows)}</table>{render_coverage(found)}'
    )


def render_coverage(found: Found) -> str:
    """After a run with coverage: per file of the project, its statements and branches
    run; a click on the file opens it at its first line never run."""
    if not found.coverage:
        return ""
    rows = []
    for index, (file, measured) in enumerate(found.coverage):
        figures = measured["figures"]
        rows.append(
            f'<tr data-coverage-file="{html.escape(file)}"><td style="{_CELL}">'
            f'<span data-test-click="cover:{index}" style="{_LINK}" title="open it at its '
            f'first line never run">{html.escape(file)}</span></td>'
            f'<td style="{_CELL};text-align:right">'
            f"{_share(figures['statements_covered'], figures['statements'])}</td>"
            f'<td style="{_CELL};text-align:right">'
            f"{_share(figures['branches_covered'], figures['branches'])}</td></tr>"
        )
    head = f'<th style="{_CELL};text-align:right;font-weight:normal;color:{_MUTED}">'
    return (
        '<div style="margin-top:12px"><b>Coverage</b> <span style="color:#868e96">(Python '
        "tier; the editor shades the lines: green ran, red never ran, amber a way not "
        'taken)</span></div><table data-testid="tests-coverage" style="border-collapse:'
        'collapse;width:100%;font-size:0.9em"><tr><th></th>'
        f"{head}statements</th>{head}branches</th></tr>{''.join(rows)}</table>"
    )


def _share(covered: int, total: int) -> str:
    if not total:
        return "-"
    return f"{covered}/{total} ({100 * covered // total} %)"


def _suite_row(suite: str, found: Found) -> str:
    tests = [t for t in found.tests if t["suite"] == suite]
    ended = [found.results[t["id"]] for t in tests if t["id"] in found.results]
    failing = sum(r["status"] in ("failed", "error") for r in ended)
    summary = f"{len(tests)} test{'s' * (len(tests) != 1)}"
    if failing:
        summary += f", {failing} failing"
    elif ended and len(ended) == len(tests):
        summary += ", all passing"
    return (
        f'<tr data-suite="{html.escape(suite)}"><td colspan="3" style="{_CELL};padding-top:8px;'
        f'border-bottom:1px solid #dee2e6"><b>{html.escape(suite)}</b> '
        f'<span style="color:{_MUTED}">{html.escape(summary)}</span></td></tr>'
    )


def _test_rows(index: int, test: dict[str, Any], result: dict[str, Any] | None) -> str:
    status = result["status"] if result is not None else ""
    mark, word, colour = MARKS.get(status, MARKS[""])
    ran = result is not None and status != "not_run"
    took = f"{result['seconds'] * 1000:.0f} ms" if result is not None and ran else ""
    row = (
        f'<tr data-test="{html.escape(test["id"])}" data-status="{status or "none"}">'
        f'<td style="{_CELL};white-space:nowrap;color:{colour};font-weight:600">'
        f"{mark} {word}</td>"
        f'<td style="{_CELL};overflow-wrap:anywhere;cursor:pointer" '
        f'data-test-click="pick:{index}" title="choose it for Run test">'
        f"{html.escape(test['name'])}</td>"
        f'<td style="{_CELL};text-align:right;color:{_MUTED}">{took}</td></tr>'
    )
    if result is None or status in ("passed", ""):
        return row
    lines = [f'<div style="color:{colour}">{html.escape(result["message"])}</div>']
    if result["detail"]:
        lines.append(f"<div>{html.escape(result['detail'])}</div>")
    place = result["place"]
    if place:
        where = f"{place['file']}:{place['line']}:{place['col']}"
        lines.append(
            f'<div><span data-test-click="goto:{index}" data-place="{html.escape(where)}" '
            f'style="{_LINK}" title="open it in the editor">{html.escape(where)}</span></div>'
        )
    return row + (
        f'<tr data-failure="{html.escape(test["id"])}"><td></td><td colspan="2" '
        f'style="{_CELL};padding-bottom:6px;overflow-wrap:anywhere">{"".join(lines)}</td></tr>'
    )
