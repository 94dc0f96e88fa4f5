"""Shared test helpers: free loopback ports (`tests/support/ports.py`) and the `padt`
command in a subprocess."""

from __future__ import annotations

import io
import json
import os
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest
from hypothesis import settings

from runtime.code.native.tier import NativeTier
from runtime.contract.state_folder import NATIVE_CACHE_ENV
from tests.support.forked_cli import run_command
from tests.support.ports import free_port as free_port  # tests import it from here

# CI must judge the submission, not the luck of the draw: there the property tests replay
# the same examples every run; on a developer's machine they keep exploring.
settings.register_profile("ci", derandomize=True, database=None)
if os.environ.get("CI") == "true":
    settings.load_profile("ci")

REPO = Path(__file__).resolve().parent.parent


def padt(
    *args: str, env: dict[str, str] | None = None, timeout: float = 120, cwd: Path = REPO
) -> subprocess.CompletedProcess[str]:
    """Run the `padt` command line in a process of its own, as a user would: forked from a
    server that imported it once (tests/support/forked_cli.py), or, where that cannot be
    (PYTHONHASHSEED and the like, another thread's command under way), started afresh."""
    command = [sys.executable, "-m", "padt.cli", *args]
    environment = {**os.environ, **(env or {})}
    forked = run_command(list(args), environment, cwd, timeout)
    if forked is None:
        return subprocess.run(
            command, capture_output=True, text=True, cwd=cwd, env=environment, timeout=timeout
        )
    if forked.returncode is None:
        raise subprocess.TimeoutExpired(command, timeout, forked.stdout, forked.stderr)
    stdout, stderr = (_as_text(output) for output in (forked.stdout, forked.stderr))
    return subprocess.CompletedProcess(command, forked.returncode, stdout, stderr)


def _as_text(output: bytes) -> str:
    """Bytes read as `subprocess.run(..., text=True)` reads them."""
    return io.TextIOWrapper(io.BytesIO(output)).read()


def sim_trace(tmp_path: Path, source: str, cycles: int, *sets: str) -> dict[str, list[object]]:
    """Run ST `source` through `padt sim` on 100 ms cycles; each name's value per cycle."""
    path = tmp_path / "sim.st"
    path.write_text(source)
    args = ["sim", str(path), "--cycles", str(cycles), "--cycle-ms", "100"]
    for setting in sets:
        args += ["--set", setting]
    run = padt(*args)
    assert run.returncode == 0, run.stderr
    rows = [json.loads(line) for line in run.stdout.splitlines()]
    assert [row["t_ms"] for row in rows] == [100 * k for k in range(cycles)]
    return {name: [row["values"][name] for row in rows] for name in rows[0]["values"]}


@pytest.fixture
def zenoh_endpoint() -> str:
    return f"tcp/127.0.0.1:{free_port()}"


@pytest.fixture(autouse=True, scope="module")
def known_resources_of_the_module(tmp_path_factory: pytest.TempPathFactory) -> Iterator[None]:
    """What a module's fixtures pin goes to a file of the module, never to the user's home
    (`known_resources` below gives each test a file of its own)."""
    with pytest.MonkeyPatch.context() as patch:
        path = tmp_path_factory.mktemp("known") / "known_resources"
        patch.setenv("PADT_KNOWN_RESOURCES", str(path))
        yield


@pytest.fixture(autouse=True)
def known_resources(
    known_resources_of_the_module: None,
    tmp_path_factory: pytest.TempPathFactory,
    monkeypatch: pytest.MonkeyPatch,
) -> Path:
    """Each test pins the resources' keys in a file of its own (their runtimes make fresh
    keys; a pin kept from another test, or in the user's home, would refuse them)."""
    path = tmp_path_factory.mktemp("known") / "known_resources"
    monkeypatch.setenv("PADT_KNOWN_RESOURCES", str(path))
    return path


@pytest.fixture(autouse=True, scope="session")
def one_native_cache(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Path]:
    """One cache of the native tier's compiled modules for every runtime, demo and `padt
    test`, `sim` or `replay` the tests start (PADT_NATIVE_CACHE, docs/native-code.md): each
    runtime has a fresh state folder, and with a cache of its own each would translate and
    compile the same bodies again (about 0.7 s of CPU per start of the demo), as a command
    would into the user's home. The tier still runs everywhere, as `padt runtime` runs it;
    what is built where by default is tests/runtime/native/test_native_process.py's. The
    processes of `pytest -n` share it too (their temporary folders have one parent)."""
    if os.environ.get("PYTEST_XDIST_WORKER"):
        path = tmp_path_factory.getbasetemp().parent / "native-cache"
        path.mkdir(exist_ok=True)
    else:
        path = tmp_path_factory.mktemp("native-cache")
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv(NATIVE_CACHE_ENV, str(path))
        yield path


# The native tier needs a C compiler and Python's headers. Both are on the development
# machines and in CI (scripts/install-c-compiler.sh, which `make test` runs); where they are
# missing the tests skip with the reason, except in CI, where they must run.
@pytest.fixture(scope="session")
def native_tier(one_native_cache: Path) -> NativeTier:
    """One tier (and the one cache of compiled modules) for the whole session."""
    tier = NativeTier(one_native_cache)
    if not tier.available:
        if os.environ.get("CI") == "true":
            pytest.fail("the native tier needs a C compiler and Python.h; CI must have both")
        pytest.skip("no C compiler or no Python.h here: the native tier cannot build")
    return tier
