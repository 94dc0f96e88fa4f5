"""`padt runtime --native-code` as a user starts it: the demo's configuration at power-up,
its bodies built into the state folder and put in place while it runs, with an event that
says so."""

from __future__ import annotations

import time
from pathlib import Path

from runtime.contract.state_folder import events_path, native_path
from runtime.native.tier import NativeTier
from tests.support.runtime_process import running_resource, write_demo_artifact


def test_the_runtime_builds_the_demo_and_runs_it_as_c(
    tmp_path: Path, zenoh_endpoint: str, native_tier: NativeTier
) -> None:
    write_demo_artifact(tmp_path)
    with running_resource("Tank1", tmp_path, zenoh_endpoint, "--native-code") as (process, _):
        deadline = time.monotonic() + 120
        text = ""
        while "native code in place" not in text:
            assert time.monotonic() < deadline, text[-2000:]
            time.sleep(0.5)
            path = events_path(tmp_path)
            text = path.read_text() if path.exists() else ""
        time.sleep(1)  # a few hundred cycles of native code
        assert process.poll() is None
    assert "2 of 2 POU bodies run as C" in text
    assert list(native_path(tmp_path).rglob("*.so"))
