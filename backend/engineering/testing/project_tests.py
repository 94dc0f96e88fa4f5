"""The unit tests of a project run for a server (the REST API, the browser UI): all of them,
one suite or one test, as a report ready for JSON (docs/rest-api.md, "Unit tests").

A server never runs tests in its own process: each run is a process of its own (spawned,
not forked: the server has threads), which a run's time limit ends whatever the tests do
(a test method has no watchdog: an endless loop in it never returns). `UnitTestRuns` holds the
runs of one server: at most a few at a time, each waited for on the caller's thread (a
request's worker thread, a browser's thread), never on an event loop."""

from __future__ import annotations

import logging
import multiprocessing
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from multiprocessing.connection import Connection
from pathlib import Path
from typing import Any, Literal

from backend.compiler.ast import key
from backend.engineering.project import ProjectError
from backend.engineering.testing.coverage.of_build import coverage_measured, meter_for
from backend.engineering.testing.test_build import UnitTest, build_tests
from backend.engineering.testing.test_session import run_session
from backend.engineering.testing.tiers import UnitTestResult
from backend.engineering.tiers import Tier
from runtime.contract.refusal import Refusal

log = logging.getLogger("padt.tests")

TierChoice = Literal["both", "python", "native"]
MOST_RUNS = 2  # runs at the same time on one server: each takes a core
TIME_LIMIT_S = 300.0  # for building the tests, and again for running them (native build included)
NOT_RUN, STOPPED = "not_run", "error"  # the status of a test a stopped run did not end
STATUSES = ("passed", "failed", "error", NOT_RUN)


@dataclass(frozen=True)
class UnitTestChoice:
    """What to run: every test, a suite's (`suite`), or one test (`suite` and `test`);
    `coverage`: measure which lines of the project's POUs they run (on the Python tier)."""

    suite: str | None = None
    test: str | None = None
    tier: TierChoice = "both"
    coverage: bool = False

    @property
    def tiers(self) -> tuple[Tier, ...]:
        return ("python", "native") if self.tier == "both" else (self.tier,)


@dataclass(frozen=True)
class UnitTestListing:
    """The suites and tests of a project, without running them."""

    compiled: bool
    diagnostics: list[dict[str, object]]  # as the compiler reports them
    tests: list[dict[str, Any]]  # `test_json` of each, by suite and name


def test_json(case: UnitTest) -> dict[str, Any]:
    return {
        "id": case.full_name,
        "suite": case.suite,
        "name": case.name,
        "file": case.file,
        "line": case.line,
    }


def result_json(result: UnitTestResult) -> dict[str, Any]:
    outcome = result.outcome
    place = outcome.place
    return {
        **test_json(result.case),
        "status": outcome.status,
        "message": outcome.message,
        "place": None
        if place is None
        else {"file": place.file, "line": place.line, "col": place.col},
        "detail": outcome.detail,
        "cycles": outcome.cycles,
        "tiers": list(result.tiers),
        "seconds": result.seconds,
    }


def list_tests(folder: Path) -> UnitTestListing:
    """The tests of a project folder (compiled with them: a parameterised test's cases come
    from its compiled array); raises Refusal when the folder is no project."""
    try:
        build = build_tests([folder])
    except ProjectError as exc:
        raise Refusal("project", str(exc)) from None
    return UnitTestListing(
        build.artifact is not None,
        [d.as_json() for d in build.diagnostics],
        [test_json(case) for case in build.cases],
    )


def chosen(cases: tuple[UnitTest, ...], choice: UnitTestChoice) -> tuple[UnitTest, ...]:
    """The tests a choice names (names in any case, as ST); refused when it names none."""
    if choice.test is not None and choice.suite is None:
        raise Refusal("bad_request", "a test is named with its suite")
    if choice.coverage and choice.tier == "native":
        raise Refusal("bad_request", "coverage is measured on the Python tier: not with native")
    found = cases
    if choice.suite is not None:
        found = tuple(c for c in found if key(c.suite) == key(choice.suite))
        if not found:
            raise Refusal("unknown_test", f"no test suite {choice.suite} in the project")
    if choice.test is not None:
        found = tuple(c for c in found if key(c.name) == key(choice.test))
        if not found:
            raise Refusal("unknown_test", f"no test {choice.suite}.{choice.test} in the project")
    return found


# ---- the report


@dataclass
class _Run:
    """What the worker said so far."""

    project: str = ""
    compiled: bool = False
    diagnostics: tuple[dict[str, object], ...] = ()
    planned: tuple[dict[str, Any], ...] = ()
    results: dict[str, dict[str, Any]] | None = None  # by test id, as they ended
    native_missing: bool = False
    coverage: dict[str, Any] | None = None  # `Coverage.as_json()`, when it was measured
    stopped: str = ""  # why the run ended before its tests did


def _report(run: _Run, choice: UnitTestChoice) -> dict[str, Any]:
    """The JSON of a run: the tests in their order, each with its result (a run stopped
    by its time limit: the test it was in as an error, the ones after it not run)."""
    results = run.results or {}
    tests = []
    stopped_in: str | None = None
    for test in run.planned:
        found = results.get(test["id"])
        if found is None:
            status = STOPPED if stopped_in is None else NOT_RUN
            stopped_in = stopped_in or test["id"]
            message = run.stopped if status == STOPPED else "not run: the run was stopped"
            # the test it was in: its place is the test's own
            place = {"file": test["file"], "line": test["line"], "col": 1}
            found = {**test, "status": status, "message": message}
            found["place"] = place if status == STOPPED else None
            found.update(detail="", cycles=0, tiers=[], seconds=0.0)
        tests.append(found)
    count = {status: sum(t["status"] == status for t in tests) for status in STATUSES}
    ran = sorted({tier for t in tests for tier in t["tiers"]})
    notes = []
    if "native" in choice.tiers and run.native_missing:
        notes.append("no C compiler on the server: the native tier was not run")
    return {
        "project": run.project,
        "compiled": run.compiled,
        "diagnostics": list(run.diagnostics),
        "tests": tests,
        "totals": {
            "passed": count["passed"],
            "failed": count["failed"],
            "errors": count["error"],
            "not_run": count[NOT_RUN],
            "total": len(tests),
            "seconds": sum(t["seconds"] for t in tests),
        },
        "tiers": ran,
        "notes": notes,
        "stopped": run.stopped or None,
        "coverage": run.coverage,
    }


# ---- the worker process


def _work(folder: str, choice: UnitTestChoice, out: Connection) -> None:
    """In the worker: build, choose, run; each step said to the server as it happens."""
    try:
        try:
            build = build_tests([Path(folder)])
        except ProjectError as exc:
            raise Refusal("project", str(exc)) from None
        diagnostics = [d.as_json() for d in build.diagnostics]
        out.send(("built", build.project.name, build.artifact is not None, diagnostics))
        if build.artifact is None:
            return
        cases = chosen(build.cases, choice)
        out.send(("planned", [test_json(case) for case in cases]))
        ran: set[str] = set()
        meter = None
        if choice.coverage:
            meter = meter_for(build)
        session = run_session(
            build.artifact, cases, choice.tiers, project=build.folder, coverage=meter
        )
        for result in session:
            ran.update(result.tiers)
            out.send(("result", result_json(result)))
        out.send(("native", "native" in choice.tiers and "native" not in ran and bool(cases)))
        if meter is not None:
            out.send(("coverage", coverage_measured(build, meter).as_json()))
    except Refusal as refused:
        out.send(("refused", refused.code, refused.message))
    except Exception as exc:  # a defect: the server says so in one line, the log in full
        log.exception("a test run of %s failed", folder)
        out.send(("refused", "internal", f"internal error: {type(exc).__name__}: {exc}"))
    finally:
        out.send(("end",))
        out.close()


Progress = Callable[[int, int, dict[str, Any] | None], None]  # tests ended, planned, result


class UnitTestRuns:
    """The test runs of one server: at most `most` at a time (one more is refused as
    `tests_busy`), each stopped after `build_s` seconds of building or `run_s` of running."""

    def __init__(
        self, most: int = MOST_RUNS, build_s: float = TIME_LIMIT_S, run_s: float = TIME_LIMIT_S
    ) -> None:
        self.most, self.build_s, self.run_s = most, build_s, run_s
        self._slots = threading.BoundedSemaphore(most)

    def run(
        self, folder: Path, choice: UnitTestChoice, progress: Progress | None = None
    ) -> dict[str, Any]:
        """The report of a run (blocks the calling thread until it ends); `progress` is
        told of each test that ends. Refused: too many runs, no project, a choice naming no test."""
        if not self._slots.acquire(blocking=False):
            raise Refusal(
                "tests_busy",
                f"{self.most} test runs are under way on this server: try again when one ends",
            )
        try:
            return self._run(folder, choice, progress or _quiet)
        finally:
            self._slots.release()

    def _run(self, folder: Path, choice: UnitTestChoice, progress: Progress) -> dict[str, Any]:
        context = multiprocessing.get_context("spawn")
        receive, send = context.Pipe(duplex=False)
        worker = context.Process(
            target=_work, args=(str(folder), choice, send), daemon=True, name="padt-tests"
        )
        worker.start()
        send.close()  # the worker's end: a worker gone is then an end of file here
        run = _Run()
        deadline, limit_s = time.monotonic() + self.build_s, self.build_s
        try:
            while True:
                left = deadline - time.monotonic()
                if left <= 0 or not receive.poll(left):
                    phase = "running the tests" if run.planned else "building the tests"
                    run.stopped = (
                        f"stopped: {phase} took longer than {limit_s:g} s, the time "
                        "limit of a test run on this server"
                    )
                    break
                try:
                    said = receive.recv()
                except EOFError:
                    run.stopped = "stopped: the test run's process ended unexpectedly"
                    break
                if said[0] == "end":
                    break
                if said[0] == "refused":
                    raise Refusal(said[1], said[2])
                if said[0] == "planned":
                    limit_s = self.run_s  # the tests' own time
                    deadline = time.monotonic() + limit_s
                _heard(run, said, progress)
        finally:
            receive.close()
            if worker.is_alive():
                worker.kill()
            worker.join()
        return _report(run, choice)


def _heard(run: _Run, said: tuple[Any, ...], progress: Progress) -> None:
    kind = said[0]
    if kind == "built":
        run.project, run.compiled, run.diagnostics = said[1], said[2], tuple(said[3])
    elif kind == "planned":
        run.planned, run.results = tuple(said[1]), {}
        progress(0, len(run.planned), None)
    elif kind == "result" and run.results is not None:
        run.results[said[1]["id"]] = said[1]
        progress(len(run.results), len(run.planned), said[1])
    elif kind == "native":
        run.native_missing = said[1]
    elif kind == "coverage":
        run.coverage = said[1]


def _quiet(done: int, planned: int, result: dict[str, Any] | None) -> None:
    """No one to tell of a run's progress."""
