"""An artifact whose typed form describes code that reaches outside the restricted namespace,
or smuggles Python text in a name, its CRCs redone (as an attacker who read the format
would): a real runtime process refuses it from a transfer and load, and from a reload, with
the reason, runs on, and nothing of it ran; so it does an artifact whose POU name is C for
its native tier; `padt replay` of a recording that carries such a form refuses it too.

Before the check of generated code, `_idiv.__globals__['builtins'].__import__(...)`
appended to a POU's source ran when the configuration was set up: on the controller host
for a download, and in `padt replay`, which then said "identical". Since artifact version 5
there is no source to append to: the runtime prints the Python from the form itself."""

from __future__ import annotations

import subprocess
import sys
from dataclasses import replace
from pathlib import Path

from backend.engineering.download import download
from backend.engineering.reload import ReloadOptions, reload
from backend.engineering.resource_client import ResourceClient
from runtime.contract import protocol as p
from runtime.contract.artifact import Artifact, load_artifact
from runtime.contract.refusal import Refusal
from tests.conftest import REPO
from tests.runtime.test_hostile_clients import PASSWORD, RESOURCE, still_healthy, target
from tests.runtime.test_recording import PLANT, compiled, finished, recordings_of, run, started
from tests.support.crafted_units import (
    ESCAPE_REFUSED,
    SMUGGLED_REFUSED,
    escape,
    first_in_body,
    smuggled,
)


def escaping(artifact: Artifact, written: Path) -> Artifact:
    """`artifact` whose first POU's body begins with a line that writes `written`."""
    return first_in_body(artifact, escape(written))


def test_a_runtime_refuses_foreign_code_by_load_and_by_reload_and_runs_on(
    tmp_path: Path, zenoh_endpoint: str
) -> None:
    written = tmp_path / "escaped"
    with target(tmp_path, zenoh_endpoint) as client:
        admin = ResourceClient(client.session, RESOURCE)
        admin.login("admin", PASSWORD)
        genuine = load_artifact((tmp_path / "config" / "artifact.json").read_bytes())
        hostile = escaping(genuine, written)
        try:
            reload(admin, smuggled(genuine, written), ReloadOptions({}))
            raise AssertionError("a reload took code the compiler does not generate")
        except Refusal as refused:
            assert SMUGGLED_REFUSED in refused.message, refused.message
        try:
            reload(admin, hostile, ReloadOptions({}))
            raise AssertionError("a reload took code the compiler does not generate")
        except Refusal as refused:
            assert ESCAPE_REFUSED in refused.message, refused.message
        still_healthy(client)
        assert admin.command("stop")["ok"]
        try:
            download(admin, hostile)
            raise AssertionError("a load took code the compiler does not generate")
        except Refusal as refused:
            assert refused.code == "transfer"  # refused as the artifact is decoded
            where = "the form of PROGRAM Main: Class.functions[0].body[0].value: "
            assert where in refused.message, refused.message
            assert ESCAPE_REFUSED in refused.message, refused.message
        # a POU name that would close the comment of the native tier's C and add its own
        named = replace(genuine.pous[0], name=f'M */ system("touch {written}"); /*')
        try:
            download(admin, replace(genuine, pous=(named, *genuine.pous[1:])).with_crc())
            raise AssertionError("a load took a unit named otherwise than the compiler names")
        except Refusal as refused:
            assert "is not an identifier" in refused.message, refused.message
        status = admin.command("status")["status"]
        assert status["state"] == "STOP/VALID CONFIGURATION" and status["crc"] == genuine.crc
        assert admin.command("start")["ok"]
        still_healthy(client)
    assert not written.exists()


def test_padt_replay_refuses_a_recording_whose_configuration_escapes(tmp_path: Path) -> None:
    written = tmp_path / "escaped"
    genuine = compiled()
    resource = started(tmp_path, genuine)
    level = [500]
    run(resource, 5, level)
    # the recorder attaches `resource.artifact`: the smuggling one, as a hostile file has it
    resource.artifact = smuggled(genuine, written)
    recordings_of(resource).start(
        resource, p.RecordStart(["Control.*"], all_inputs=True, id="evil")
    )
    run(resource, 20, level)
    recordings_of(resource).stop(resource, "evil")
    finished(resource)
    project = tmp_path / "project"
    project.mkdir()
    (project / "plant.st").write_text(PLANT)
    (project / "padt.toml").write_text(
        '[project]\nname = "Plant"\n\n[resource]\nname = "Plant"\ntarget_cycle_ms = 10\n'
        "safety_operation = false\nglobal_forcing_allowed = true\n\n"
        '[[resource.program]]\nname = "Control"\npou = "Control"\nid = 1\n\n'
        '[[resource.program]]\nname = "Other"\npou = "Other"\nid = 2\n'
    )
    command = [
        sys.executable, "-m", "padt.cli", "replay",
        str(tmp_path / "recordings" / "evil-1.mcap"), str(project),
    ]  # fmt: skip
    done = subprocess.run(command, cwd=REPO, capture_output=True, text=True, timeout=300)
    assert done.returncode != 0, done.stdout
    assert "identical" not in done.stdout
    assert SMUGGLED_REFUSED in done.stderr, done.stderr
    assert "the recorded configuration is damaged: the form of PROGRAM Control" in done.stderr
    assert "start state is damaged" not in done.stderr  # said once, as what it is
    assert "Traceback" not in done.stderr
    assert not written.exists()
