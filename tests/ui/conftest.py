"""The fixtures of the browser tests: `padt demo` in its own process, with the URL and the
administrator password it printed; and `plant`, the demo resource with users of every
level and the UI in this process, for what needs more than one account or the resource's
client at hand."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from contextlib import closing
from pathlib import Path

import pytest

from backend.engineering.padt_accounts import PadtAccounts, write_accounts
from backend.engineering.project import compile_project, load_project
from backend.engineering.resource_directory import ResourceDirectory
from backend.engineering.watch_lists import WatchLists
from frontend.app import PadtUi
from frontend.ui_context import UiContext
from padt.demo import demo_project_with_accounts
from padt.demo_plant import DemoPlant
from runtime.contract.accounts import hash_password
from runtime.contract.artifact import UserAccount
from tests.conftest import REPO, free_port
from tests.support.browser import one_browser_for_the_tests_within
from tests.support.forked_process import CommandServer
from tests.support.ports import wait_until_listening
from tests.support.runtime_process import running_resource, store_artifact
from tests.ui.browser_steps import PASSWORD, Demo, Plant

URL_LINE = re.compile(r"padt demo: open (http://\S+)")
PASSWORD_LINE = re.compile(r"administrator 'admin', password (\S+)")


@pytest.fixture(autouse=True, scope="module")
def one_browser_per_module(request: pytest.FixtureRequest) -> Iterator[None]:
    """The browser tests of a module share one Chromium process, each test with its own
    pages and contexts (tests/support/browser.py); a module that runs an asyncio loop in
    the tests' thread says SHARED_BROWSER = False and starts one per test."""
    if not getattr(request.module, "SHARED_BROWSER", True):
        yield
        return
    with one_browser_for_the_tests_within():
        yield


@pytest.fixture(scope="session")
def demo_server() -> Iterator[CommandServer]:
    """The server the session's demos are forked from, their parts imported once
    (tests/support/forked_process.py)."""
    server = CommandServer()
    try:
        yield server
    finally:
        server.close()


@pytest.fixture
def demo(
    tmp_path: Path, request: pytest.FixtureRequest, demo_server: CommandServer
) -> Iterator[Demo]:
    """`padt demo`, forked from the session's server (or, where that cannot be, started
    afresh); without its OPC UA server (2 s of CPU to start) unless the test asks for it
    (`@pytest.mark.parametrize("demo", ["opcua"], indirect=True)`)."""
    args = ["demo", "--state-dir", str(tmp_path)]
    zenoh_port = free_port()
    args += ["--port", str(free_port()), "--zenoh-port", str(zenoh_port), "--api-port", "0"]
    modbus_port = free_port()  # never the fixed 5020: demos of parallel tests would collide
    args += ["--modbus-port", str(modbus_port)]
    opcua_port = free_port() if getattr(request, "param", None) == "opcua" else 0
    args += ["--opcua-port", str(opcua_port)] if opcua_port else ["--no-opcua"]
    env = dict(os.environ)
    process = demo_server.start(args, env, REPO) or subprocess.Popen(
        [sys.executable, "-m", "padt.cli", *args],
        cwd=REPO,
        stdout=subprocess.PIPE,
        text=True,
        env=env,
    )
    assert process.stdout is not None
    url = password = None
    started = time.monotonic()
    for line in process.stdout:
        password = password or _group(PASSWORD_LINE, line)
        url = _group(URL_LINE, line)
        if url:
            break
    assert url is not None, "padt demo printed no URL"
    assert password is not None, "padt demo printed no administrator password"
    assert time.monotonic() - started < 60
    if opcua_port:  # the runtime comes up after the UI
        wait_until_listening(opcua_port)
    try:
        yield Demo(url, password, modbus_port, opcua_port, f"tcp/127.0.0.1:{zenoh_port}")
    finally:
        process.send_signal(signal.SIGINT)  # Ctrl-C
        assert process.wait(timeout=15) == 0


def _group(pattern: re.Pattern[str], line: str) -> str | None:
    match = pattern.search(line)
    return match.group(1) if match else None


# what the plant's project adds for `@pytest.mark.parametrize("plant", ["exchange"],
# indirect=True)`: a publication of the tank's level to other resources, and a global that
# takes the level of another resource's publication (docs/exchange.md)
EXCHANGE_ST = "VAR_GLOBAL fillerLevel : REAL; END_VAR\n"
EXCHANGE_TOML = """
[[exchange.publish]]
name = "tank"
variables = ["tankLevel", "pumpRunning"]
period_ms = 100

[[exchange.subscribe]]
resource = "Filler"
publication = "levels"
timeout_ms = 300

[[exchange.subscribe.variable]]
variable = "fillerLevel"
from = "level"
safe_value = -1.0
"""


@pytest.fixture
def plant(tmp_path: Path, zenoh_endpoint: str, request: pytest.FixtureRequest) -> Iterator[Plant]:
    """The demo resource, polling its simulated plant, with a read-only user `viewer`, and
    the UI with three PADT accounts: `admin` (security administrator), `viewer`
    (read-write), `guest` (read-only); the UI knows the demo's project as `demo`. With the
    parameter "exchange", the project also exchanges variables with other resources."""
    verifier = hash_password(PASSWORD)
    resource_users = [
        UserAccount("admin", "administrator", verifier),
        UserAccount("viewer", "read", verifier),
    ]
    tank = DemoPlant()  # the level moves as in `padt demo`: the plant fills and drains it
    folder = demo_project_with_accounts(tmp_path, resource_users, tank.start())
    if getattr(request, "param", None) == "exchange":
        (folder / "Exchange.st").write_text(EXCHANGE_ST)
        with (folder / "padt.toml").open("a") as config:
            config.write(EXCHANGE_TOML)
    result = compile_project(load_project([folder]))
    assert result.artifact is not None
    store_artifact(tmp_path, result.artifact)
    accounts_file = tmp_path / "padt-accounts.json"
    write_accounts(
        accounts_file,
        (
            UserAccount("admin", "security-administrator", verifier),
            UserAccount("viewer", "read-write", verifier),
            UserAccount("guest", "read-only", verifier),
        ),
    )
    with (
        closing(tank),
        running_resource("Tank1", tmp_path, zenoh_endpoint, "--modbus-port", "0") as (
            runtime,
            client,
        ),
    ):
        session = client.session
        accounts = PadtAccounts(accounts_file, time.monotonic_ns)
        lists = WatchLists(tmp_path / "watch-lists.json")
        directory = ResourceDirectory(session)
        projects = {"demo": folder}
        context = UiContext(directory, accounts, zenoh_endpoint, lists, projects, tmp_path / "bak")
        ui = PadtUi(context, port=free_port())
        try:
            yield Plant(ui.url, client, ui, runtime, tmp_path, zenoh_endpoint)
        finally:
            ui.close()
