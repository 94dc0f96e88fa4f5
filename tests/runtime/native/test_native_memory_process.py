"""A runtime process on the native tier, its variables in native memory (issue 34 step 5),
through the protocol a PADT uses: a write and a forced value reach the program, the online
values read them from the image, and the context the process saved from the image
warm-starts it after a SIGKILL with the values a resource on objects restores from it."""

from __future__ import annotations

import json
import os
import signal
from pathlib import Path
from typing import Any

from backend.compiler.pipeline import compile_sources
from backend.compiler.source import SourceFile
from backend.engineering.resource_client import ResourceClient
from runtime.clock import VirtualClock
from runtime.code.native.tier import NativeTier
from runtime.context import ContextInvalid, load_context
from runtime.contract.artifact import Artifact, ProgramConfig, ResourceConfig
from runtime.contract.state_folder import context_path
from runtime.resource import Resource
from runtime.restart import warm_start
from tests.support.runtime_process import running_resource, store_artifact, wait_for

PLANT = """
TYPE Pt : STRUCT x : REAL; ok : BOOL; END_STRUCT; END_TYPE
VAR_GLOBAL level : INT; END_VAR
PROGRAM Main
VAR_EXTERNAL level : INT; END_VAR
VAR n : DINT; seen : INT; pts : ARRAY[1..3] OF Pt; name : STRING[8]; t : TON; END_VAR
n := n + 1;
seen := level;
pts[2].x := DINT_TO_REAL(n);
pts[3].ok := NOT pts[3].ok;
name := 'running';
t(IN := TRUE, PT := T#1h);
END_PROGRAM
"""
IN_NATIVE_MEMORY = "the variables in native memory"


def compiled() -> Artifact:
    config = ResourceConfig(
        name="Plant", target_cycle_ms=10, safety_operation=False, global_forcing_allowed=True
    )
    programs = [ProgramConfig("Main", "Main", 1)]
    result = compile_sources([SourceFile("plant.st", PLANT)], resource=config, programs=programs)
    assert result.artifact is not None, [str(d) for d in result.diagnostics]
    return result.artifact


def in_native_memory(client: ResourceClient) -> bool:
    events = client.command("events")["events"]
    return any(e["kind"] == "native" and IN_NATIVE_MEMORY in e["message"] for e in events)


def restored(artifact: Artifact, state_dir: Path) -> tuple[str, dict[str, Any]]:
    """How a resource on objects starts from the context on disk, and its values."""
    resource = Resource("Plant", VirtualClock())
    resource.load(artifact)
    saved = load_context(context_path(state_dir), artifact.crc)
    if not isinstance(saved, ContextInvalid):
        warm_start(resource, saved)
    return str(resource.status().start), json.loads(json.dumps(resource.variables.values()))


def test_writes_forcing_and_a_warm_start_after_sigkill_in_native_memory(
    tmp_path: Path, zenoh_endpoint: str, native_tier: NativeTier
) -> None:
    artifact = compiled()
    store_artifact(tmp_path, artifact)
    saving = ("--context-period-ms", "5")
    with running_resource("Plant", tmp_path, zenoh_endpoint, *saving) as (process, client):
        wait_for("the variables in native memory", lambda: in_native_memory(client), 120)
        assert client.command("write", variable="level", value=7)["ok"]
        assert client.command("start")["ok"]

        def values() -> dict[str, Any]:
            return dict(client.command("values")["values"])

        wait_for("the program sees the write", lambda: values()["Main.seen"] == 7)
        assert client.command("force", variable="level", value=9)["ok"]
        assert client.command("start_forcing")["ok"]
        wait_for("the program sees the forced value", lambda: values()["Main.seen"] == 9)
        assert client.command("stop_forcing")["ok"]
        now = values()
        assert now["Main.name"] == "running" and now["Main.pts[2].x"] > 0
        wait_for("a few periodic saves", lambda: values()["Main.n"] > now["Main.n"] + 20)
        os.kill(process.pid, signal.SIGKILL)
        process.wait()
    start, expected = restored(artifact, tmp_path)
    assert start == "warm" and expected["Main.seen"] == 9 and expected["Main.n"] > 20
    with running_resource("Plant", tmp_path, zenoh_endpoint) as (_process, client):
        wait_for("the variables in native memory again", lambda: in_native_memory(client), 120)
        assert client.command("status")["status"]["start"] == "warm"
        assert client.command("values")["values"] == expected  # in STOP: as restored
