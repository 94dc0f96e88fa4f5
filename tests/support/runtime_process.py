"""Start real processes for tests: a Zenoh router in the test process, `padt runtime`,
`padt demo`; stop them all afterwards."""

from __future__ import annotations

import os
import subprocess
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import zenoh

from backend.engineering.project import compile_project, demo_project_path, load_project
from backend.engineering.resource_client import ResourceClient
from runtime.contract.artifact import Artifact
from runtime.contract.session import open_client, open_router
from runtime.contract.state_folder import artifact_path
from tests.conftest import REPO


def store_artifact(state_dir: Path, artifact: Artifact) -> None:
    """Put a configuration where `padt runtime` finds it at power-up."""
    path = artifact_path(state_dir)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(artifact.to_json())


def write_demo_artifact(state_dir: Path) -> str:
    result = compile_project(load_project([demo_project_path()]))
    assert result.artifact is not None
    store_artifact(state_dir, result.artifact)
    return result.artifact.crc


def wait_until_answering(client: ResourceClient, timeout_s: float = 30) -> None:
    client.wait_until_answering(timeout_s)


@contextmanager
def router(endpoint: str) -> Iterator[zenoh.Session]:
    session = open_router(endpoint)
    try:
        yield session
    finally:
        session.close()


@contextmanager
def runtime_process(
    resource: str, state_dir: Path, endpoint: str, *extra: str
) -> Iterator[subprocess.Popen[bytes]]:
    command = [sys.executable, "-m", "padt.cli", "runtime", "--resource", resource]
    command += ["--state-dir", str(state_dir), "--zenoh", endpoint, *extra]
    process = subprocess.Popen(command, cwd=REPO, env=dict(os.environ))
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
    resource: str, state_dir: Path, endpoint: str, *extra: str
) -> Iterator[tuple[subprocess.Popen[bytes], ResourceClient]]:
    """A router, a runtime process for `resource` and a client that it answers."""
    with (
        router(endpoint),
        runtime_process(resource, state_dir, endpoint, *extra) as process,
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
