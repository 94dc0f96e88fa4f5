"""The unit tests of a project run over the REST API, on a real HTTP port, each run in a
process of its own: the demo's tests all pass; a failing assert is reported with its place,
expected and actual; one suite or one test; a project whose tests do not compile; a test
that never ends is stopped by the run's time limit, and a run beyond the server's bound is
refused; bad bodies, unknown names and a read-only caller get structured refusals."""

from __future__ import annotations

import shutil
import threading
import time
from collections.abc import Iterator
from contextlib import ExitStack, contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import httpx
import pytest

from backend.api.server import ApiServer
from backend.api.service import PadtService
from backend.engineering.padt_accounts import PadtAccounts
from backend.engineering.project import demo_project_path
from backend.engineering.project_shelf import shelf_of
from backend.engineering.resource_directory import ResourceDirectory
from backend.engineering.testing.project_tests import UnitTestRuns
from runtime.contract.session import open_client
from tests.api.test_rest_api import error
from tests.conftest import free_port
from tests.support.rest_plant import PADT_PASSWORDS, padt_accounts_file
from tests.support.runtime_process import router

ROUTE = "/api/projects/{}/tests"
RUN_S = 3.0  # how long the endless test runs: far beyond what the demo's tests take
TEST_FILE = "test/tank_test.st"
# the demo's low alarm test with a wrong expectation (a level of 100 l is not critical)
WRONG = "ASSERT_FALSE(TankControl.alarmLow, '100 l is not critical');"
WRONG_BY = "ASSERT_TRUE(TankControl.alarmLow, 'critically low at 100 l');"
ENDLESS = """
FUNCTION_BLOCK EndlessTests
METHOD TestForever
VAR turns : DINT; END_VAR
WHILE TRUE DO turns := turns + 1; END_WHILE
END_METHOD
METHOD TestLater
ASSERT_TRUE(TRUE);
END_METHOD
END_FUNCTION_BLOCK
"""


@dataclass
class Api:
    url: str
    http: httpx.Client

    def token(self, user: str) -> str:
        body = {"user": user, "password": PADT_PASSWORDS[user]}
        reply = self.http.post(f"{self.url}/api/login", json=body)
        assert reply.status_code == 200, reply.text
        return str(reply.json()["token"])

    def run(self, project: str, body: Any = None, user: str = "builder") -> httpx.Response:
        headers = {"Authorization": f"Bearer {self.token(user)}"}
        url = f"{self.url}{ROUTE.format(project)}"
        return self.http.post(url, headers=headers, json=body)


def demo_copy(folder: Path, tests: str = "") -> Path:
    """The demo project with its tests, the test file's text changed by `tests`."""
    shutil.copytree(demo_project_path(), folder)
    if tests:
        (folder / TEST_FILE).write_text(tests, encoding="utf-8")
    return folder


@contextmanager
def serving(base: Path, projects: dict[str, Path], runs: UnitTestRuns) -> Iterator[Api]:
    """A REST server of `projects` on a router of its own, its test runs bounded by `runs`."""
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    with ExitStack() as stack:
        stack.enter_context(router(endpoint))
        session = open_client(endpoint)
        stack.callback(session.close)
        accounts = PadtAccounts(padt_accounts_file(base / "accounts.json"), time.monotonic_ns)
        shelf = shelf_of(projects, None, base / "audit.jsonl")
        service = PadtService(ResourceDirectory(session), accounts, shelf, base / "bak", runs)
        stack.callback(service.close)
        server = ApiServer(service)
        stack.callback(server.close)
        http = stack.enter_context(httpx.Client(timeout=300))
        yield Api(server.url, http)


@pytest.fixture(scope="module")
def api(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Api]:
    base = tmp_path_factory.mktemp("rest-unit-tests")
    tests = (demo_project_path() / TEST_FILE).read_text(encoding="utf-8")
    assert WRONG in tests
    projects = {
        "demo": demo_copy(base / "demo"),
        "failing": demo_copy(base / "failing", tests.replace(WRONG, WRONG_BY)),
        "broken": demo_copy(base / "broken", tests.replace("RUN_CYCLES(1);", "RUN_CYCLES(;", 1)),
    }
    with serving(base, projects, UnitTestRuns()) as api:
        yield api


@pytest.fixture
def one_short_run(tmp_path: Path) -> Iterator[Api]:
    """A server that runs one test run at a time and stops a run's tests after RUN_S
    (its building, and a native build, keep the usual limit)."""
    tests = (demo_project_path() / TEST_FILE).read_text(encoding="utf-8")
    projects = {
        "demo": demo_copy(tmp_path / "demo"),
        "endless": demo_copy(tmp_path / "endless", tests + ENDLESS),
    }
    with serving(tmp_path, projects, UnitTestRuns(most=1, run_s=RUN_S)) as api:
        yield api


def test_the_demos_tests_all_pass_on_both_tiers(api: Api) -> None:
    reply = api.run("demo")
    assert reply.status_code == 200, reply.text
    report = reply.json()
    assert report["compiled"] and report["stopped"] is None and report["diagnostics"] == []
    assert report["totals"] == {**report["totals"], "passed": 6, "total": 6, "failed": 0}
    names = [t["id"] for t in report["tests"]]
    assert names == sorted(names, key=str.upper) and "TankTests.TestTheLowAlarm" in names
    low = next(t for t in report["tests"] if t["name"] == "TestTheLowAlarm")
    assert low["status"] == "passed" and low["file"] == TEST_FILE and low["cycles"] == 2
    assert low["tiers"] == ["python", "native"] and low["place"] is None


def test_a_failed_assert_names_its_place_expected_and_actual(api: Api) -> None:
    reply = api.run("failing")
    assert reply.status_code == 200, reply.text
    report = reply.json()
    assert (report["totals"]["passed"], report["totals"]["failed"]) == (5, 1)
    failed = next(t for t in report["tests"] if t["status"] != "passed")
    assert failed["id"] == "TankTests.TestTheLowAlarm"
    assert failed["message"] == "ASSERT_TRUE failed: critically low at 100 l"
    assert failed["detail"] == "expected TRUE, actual FALSE"
    line = 1 + (demo_project_path() / TEST_FILE).read_text().split("\n").index(WRONG)
    assert failed["place"] == {"file": TEST_FILE, "line": line, "col": 1}


def test_one_suite_or_one_test_on_one_tier(api: Api) -> None:
    suite = api.run("failing", {"suite": "tanktests", "tier": "python"}).json()
    assert suite["totals"]["total"] == 6 and suite["tiers"] == ["python"]
    one = api.run("failing", {"suite": "TankTests", "test": "TestThePumpStopsAtTheHighLevel"})
    assert [t["id"] for t in one.json()["tests"]] == ["TankTests.TestThePumpStopsAtTheHighLevel"]
    assert one.json()["totals"]["passed"] == 1


def test_coverage_of_the_project_the_tests_ran(api: Api) -> None:
    one = {"suite": "TankTests", "test": "TestTheLevelFollowsThePlant", "coverage": True}
    report = api.run("demo", one).json()
    measured = report["coverage"]["files"]
    assert list(measured) == ["tank.st"]  # the project's POUs: not the tests, not stdlib
    tank = (demo_project_path() / "tank.st").read_text(encoding="utf-8").split("\n")
    stop = 1 + tank.index("  pump := FALSE;")  # the high level is never reached
    assert measured["tank.st"]["lines"][str(stop)] == 0
    assert measured["tank.st"]["lines"][str(stop - 1)] == 1  # IF level >= highLevel
    figures = report["coverage"]["figures"]
    assert 0 < figures["statements_covered"] < figures["statements"]
    assert api.run("demo", {"tier": "python"}).json()["coverage"] is None


def test_tests_that_do_not_compile_report_the_diagnostics(api: Api) -> None:
    reply = api.run("broken")
    assert reply.status_code == 200, reply.text
    report = reply.json()
    assert not report["compiled"] and report["tests"] == []
    assert any(d["file"] == TEST_FILE and d["severity"] == "error" for d in report["diagnostics"])


def test_an_endless_test_is_stopped_and_a_run_beyond_the_bound_refused(
    one_short_run: Api,
) -> None:
    api = one_short_run
    ended: list[httpx.Response] = []

    def endless() -> threading.Thread:
        run = threading.Thread(target=lambda: ended.append(api.run("endless", {"tier": "python"})))
        run.start()
        return run

    # the server runs one at a time here: while the endless run lasts, another is refused
    first, refused = endless(), None
    while refused is None:
        reply = api.run("demo", {"suite": "TankTests", "test": "TestTheLowAlarm"})
        if reply.status_code == 503:
            refused = reply
        elif not first.is_alive():  # it came second: refused itself; again
            assert ended.pop().status_code == 503
            first = endless()
    first.join()
    assert "try again" in error(refused, 503, "tests_busy")
    report = ended[0].json()
    assert report["stopped"].startswith("stopped: running the tests took longer than 3 s")
    status = {t["id"]: (t["status"], t["place"]) for t in report["tests"]}
    forever = status.pop("EndlessTests.TestForever")
    assert forever[0] == "error" and forever[1]["file"] == TEST_FILE
    assert status["EndlessTests.TestLater"] == ("not_run", None)
    # the worker is gone: the next run is served at once
    assert api.run("demo", {"suite": "TankTests", "tier": "python"}).status_code == 200


@pytest.mark.parametrize(
    ("body", "status", "code"),
    [
        ({"suite": "NoSuchSuite"}, 404, "unknown_test"),
        ({"suite": "TankTests", "test": "TestNothing"}, 404, "unknown_test"),
        ({"test": "TestTheLowAlarm"}, 400, "bad_request"),
        ({"tier": "quantum"}, 400, "bad_request"),
        ({"tier": "native", "coverage": True}, 400, "bad_request"),
        ({"suite": 12}, 400, "bad_request"),
        ({"suite": "S" * 65}, 400, "bad_request"),
        ([1, 2], 400, "bad_request"),
    ],
)
def test_bad_bodies_are_refused_with_a_reason(api: Api, body: Any, status: int, code: str) -> None:
    error(api.run("demo", body), status, code)


def test_read_only_may_not_run_tests_nor_anyone_an_unknown_project(api: Api) -> None:
    assert "needs read-write" in error(api.run("demo", user="reader"), 403, "forbidden")
    error(api.run("nope"), 404, "unknown_project")
