"""Start real processes for tests: a Zenoh router in the test process, `padt runtime`,
`padt demo`; stop them all afterwards."""

from __future__ import annotations

import os
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import IO

import zenoh

from backend.engineering.project import compile_project, demo_project_path, load_project
from backend.engineering.resource_client import ResourceClient
from runtime.contract.artifact import Artifact
from runtime.contract.private_files import write_private
from runtime.contract.session import open_client, open_router
from runtime.contract.setup_secret import SETUP_USER, read_secret
from runtime.contract.state_folder import artifact_path, setup_secret_path
from tests.conftest import REPO


def store_artifact(state_dir: Path, artifact: Artifact) -> None:
    """Put a configuration where `padt runtime` finds it at power-up."""
    path = artifact_path(state_dir)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(artifact.to_json())


def stored_project(folder: Path, name: str, source: str, settings: str) -> Path:
    """The project `folder/name` of one ST file and its padt.toml, compiled, with its
    configuration stored where `padt runtime` finds it at power-up: in the state folder
    `folder/name-state`, which is returned."""
    project = folder / name
    project.mkdir(parents=True)
    (project / "padt.toml").write_text(settings)
    (project / "main.st").write_text(source)
    result = compile_project(load_project([project]))
    assert result.artifact is not None, [str(d) for d in result.diagnostics[:5]]
    state = folder / f"{name}-state"
    store_artifact(state, result.artifact)
    return state


def write_demo_artifact(state_dir: Path) -> str:
    result = compile_project(load_project([demo_project_path()]))
    assert result.artifact is not None
    store_artifact(state_dir, result.artifact)
    return result.artifact.crc


def setup_secret(state_dir: Path) -> str:
    """The setup secret a runtime without a configuration made in its state folder (there
    once the runtime answers)."""
    return read_secret(setup_secret_path(state_dir))


# a setup secret known to the tests that commission many runtimes with `padt load`
KNOWN_SETUP_SECRET = "Known-to-the-tests-0123456789"


def know_setup_secret(state_dir: Path) -> None:
    """Give the runtime of `state_dir` KNOWN_SETUP_SECRET as its setup secret: one it finds
    in its state folder at its start, as if an earlier start had made it."""
    write_private(setup_secret_path(state_dir), KNOWN_SETUP_SECRET.encode("ascii"))


def setup_env(state_dir: Path) -> dict[str, str]:
    """The environment in which `padt load` commissions the runtime of `state_dir` while it
    has no configuration (PADT_SETUP_SECRET; none once the secret is spent)."""
    path = setup_secret_path(state_dir)
    return {"PADT_SETUP_SECRET": read_secret(path)} if path.exists() else {}


def commissioning(client: ResourceClient, state_dir: Path) -> ResourceClient:
    """`client` logged in as the setup account of a runtime without a configuration, for
    its first download (runtime/commissioning.py)."""
    client.login(SETUP_USER, setup_secret(state_dir))
    return client


def wait_until_answering(client: ResourceClient, timeout_s: float = 30) -> None:
    client.wait_until_answering(timeout_s)


def wait_for(what: str, check: Callable[[], bool], timeout_s: float = 30) -> None:
    """Until `check()` holds (what a process does takes its time), at most `timeout_s`."""
    deadline = time.monotonic() + timeout_s
    while not check():
        assert time.monotonic() < deadline, f"waited {timeout_s:g} s for {what}"
        time.sleep(0.05)


@contextmanager
def router(endpoint: str) -> Iterator[zenoh.Session]:
    session = open_router(endpoint)
    try:
        yield session
    finally:
        session.close()


@contextmanager
def runtime_process(
    resource: str, state_dir: Path, endpoint: str, *extra: str, log: IO[bytes] | None = None
) -> Iterator[subprocess.Popen[bytes]]:
    """`log`: where its standard error (its log) goes; the test's by default."""
    command = [sys.executable, "-m", "padt.cli", "runtime", "--resource", resource]
    command += ["--state-dir", str(state_dir), "--zenoh", endpoint, *extra]
    process = subprocess.Popen(command, cwd=REPO, env=dict(os.environ), stderr=log)
    try:
        yield process
    finally:
        process.terminate()
        try:
            process.wait(timeout=10)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait()


@contextmanager
def running_resource(
    resource: str, state_dir: Path, endpoint: str, *extra: str, log: IO[bytes] | None = None
) -> Iterator[tuple[subprocess.Popen[bytes], ResourceClient]]:
    """A router, a runtime process for `resource` (its log to `log`) and a client that it
    answers."""
    with (
        router(endpoint),
        runtime_process(resource, state_dir, endpoint, *extra, log=log) as process,
        client_session(endpoint) as session,
    ):
        client = ResourceClient(session, resource)
        wait_until_answering(client)
        yield process, client


@contextmanager
def client_session(endpoint: str) -> Iterator[zenoh.Session]:
    session = open_client(endpoint)
    try:
        yield session
    finally:
        session.close()
