"""`padt runtime` as a user starts it: the demo's configuration at power-up, its bodies
built into the state folder and put in place while it runs, with an event that says so
(native code is the default); with `--no-native-code` all of it stays Python."""

from __future__ import annotations

import time
from pathlib import Path

import pytest

from runtime.code.native.tier import NativeTier
from runtime.contract.protocol import GetStatus
from runtime.contract.state_folder import NATIVE_CACHE_ENV, events_path, native_path
from tests.support.runtime_process import running_resource, write_demo_artifact


def _events(state_dir: Path) -> str:
    path = events_path(state_dir)
    return path.read_text() if path.exists() else ""


def test_the_runtime_builds_the_demo_and_runs_it_as_c_by_default(
    tmp_path: Path, zenoh_endpoint: str, native_tier: NativeTier, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.delenv(NATIVE_CACHE_ENV)  # as a user starts it: the cache in the state folder
    write_demo_artifact(tmp_path)
    with running_resource("Tank1", tmp_path, zenoh_endpoint) as (process, _):
        deadline = time.monotonic() + 120
        while "native code in place" not in _events(tmp_path):
            assert time.monotonic() < deadline, _events(tmp_path)[-2000:]
            time.sleep(0.5)
        time.sleep(1)  # a few hundred cycles of native code
        assert process.poll() is None
    assert "2 of 2 POU bodies run as C" in _events(tmp_path)
    assert list(native_path(tmp_path).rglob("*.so"))


def test_a_cache_named_in_the_environment_serves_every_state_folder(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv(NATIVE_CACHE_ENV, str(tmp_path / "shared"))
    assert native_path(tmp_path / "a") == native_path(tmp_path / "b") == tmp_path / "shared"
    monkeypatch.setenv(NATIVE_CACHE_ENV, "")  # empty: as if not set
    assert native_path(tmp_path / "a") == tmp_path / "a" / "native"


def test_with_no_native_code_the_runtime_runs_everything_as_python(
    tmp_path: Path, zenoh_endpoint: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.delenv(NATIVE_CACHE_ENV)
    write_demo_artifact(tmp_path)
    with running_resource("Tank1", tmp_path, zenoh_endpoint, "--no-native-code") as (_, client):
        before = client.ask(GetStatus()).status.cycle
        time.sleep(2)  # what the default needs to build and bind the demo's two bodies
        assert client.ask(GetStatus()).status.cycle > before
    assert "native" not in _events(tmp_path)
    assert not native_path(tmp_path).exists()
