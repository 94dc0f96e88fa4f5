"""Download, reload and backups: `padt load / start / stop / status / reload` against a real
runtime process over real Zenoh, and the transfer's protection against a corrupted or a
cut-off artifact."""

from __future__ import annotations

import json
import shutil
import time
import zipfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

import backend.engineering.compile_gate as compile_gate
from backend.engineering.backup import BackupError, BackupInfo, restore_backup, write_backup
from backend.engineering.check_twice import CheckTwiceResult, CompileRun, compare
from backend.engineering.compile_gate import compile_checked
from backend.engineering.download import send_artifact
from backend.engineering.resource_client import ResourceClient
from padt.configuration import parse_rename
from runtime.contract.artifact import crc32_hex, load_artifact
from runtime.contract.protocol import MAX_REQUEST_BYTES, pieces
from runtime.contract.refusal import Refusal
from tests.conftest import padt
from tests.support.runtime_process import (
    KNOWN_SETUP_SECRET,
    client_session,
    know_setup_secret,
    router,
    running_resource,
)

RESOURCE = "LoadRes"
STOPPED = "STOP/VALID CONFIGURATION"

PADT_TOML = """\
[project]
name = "Loading test"
version = "1.2"

[resource]
name = "LoadRes"
target_cycle_ms = 20
safety_operation = false
{extra}
[[resource.program]]
name = "Main"
pou = "Main"
id = 1
"""

COUNTER_ST = """\
PROGRAM Main
VAR
  counter : INT := 0;
END_VAR
counter := counter + 1;
END_PROGRAM
"""

# the counter becomes a DINT (converted) and a variable is added (new)
CHANGED_ST = """\
PROGRAM Main
VAR
  counter : DINT := 0;
  extra : INT := 7;
END_VAR
counter := counter + 1;
END_PROGRAM
"""


@pytest.fixture(autouse=True)
def commissioning(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The runtimes here start without a configuration: the first `padt load` of each
    logs in with the setup secret (PADT_SETUP_SECRET), one the tests know."""
    know_setup_secret(tmp_path / "state")
    monkeypatch.setenv("PADT_SETUP_SECRET", KNOWN_SETUP_SECRET)


def write_project(folder: Path, source: str = COUNTER_ST, extra: str = "") -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "padt.toml").write_text(PADT_TOML.format(extra=extra))
    (folder / "main.st").write_text(source)
    return folder


def wait_for(condition: Callable[[], bool], timeout_s: float = 20) -> None:
    deadline = time.monotonic() + timeout_s
    while not condition():
        assert time.monotonic() < deadline, "condition not met in time"
        time.sleep(0.05)


def status(client: ResourceClient) -> dict[str, Any]:
    reply = client.command("status")
    assert reply["ok"], reply
    result: dict[str, Any] = reply["status"]
    return result


def values(client: ResourceClient) -> dict[str, Any]:
    reply = client.command("values")
    assert reply["ok"], reply
    result: dict[str, Any] = reply["values"]
    return result


def online(command: str, endpoint: str, *args: str) -> list[str]:
    return [command, *args, "--resource", RESOURCE, "--zenoh", endpoint]


def load_and_start(project: Path, endpoint: str, backup_dir: Path, client: ResourceClient) -> None:
    """`padt load`, then start the resource and wait until its counter runs."""
    loaded = padt(*online("load", endpoint, str(project), "--backup-dir", str(backup_dir)))
    assert loaded.returncode == 0, loaded.stderr
    assert client.command("start")["ok"]
    wait_for(lambda: values(client)["Main.counter"] > 2)


def backups(folder: Path) -> list[Path]:
    """Oldest first: by when written (the name has the CRC before the time, and two
    archives of one test may share the second)."""
    return sorted(folder.glob("*.zip"), key=lambda archive: archive.stat().st_mtime_ns)


# ---- against a running resource


def test_load_start_refusal_and_backup(tmp_path: Path, zenoh_endpoint: str) -> None:
    project = write_project(tmp_path / "project")
    backup_dir = tmp_path / "backups"
    with running_resource(RESOURCE, tmp_path / "state", zenoh_endpoint) as (_, client):
        assert status(client)["state"] == "STOP/INVALID CONFIGURATION"

        loaded = padt(
            *online("load", zenoh_endpoint, str(project), "--backup-dir", str(backup_dir))
        )
        assert loaded.returncode == 0, loaded.stderr
        now = status(client)
        assert now["state"] == STOPPED
        assert f"configuration CRC {now['crc']}" in loaded.stdout

        (archive,) = backups(backup_dir)
        assert f"backup: {archive}" in loaded.stdout
        assert archive.name.startswith(f"Loading_test_{now['crc']}_")
        artifact_text, files = restore_backup(archive)
        assert load_artifact(artifact_text).crc == now["crc"]
        assert files == {
            "main.st": COUNTER_ST,
            "padt.toml": (project / "padt.toml").read_text(),
        }
        with zipfile.ZipFile(archive) as opened:
            manifest = json.loads(opened.read("MANIFEST.json"))
        assert manifest["crc"]["configuration"] == now["crc"]
        assert manifest["project_version"] == "1.2" and manifest["resource"] == RESOURCE
        assert manifest["command"].startswith("padt load ")

        shown = padt(*online("status", zenoh_endpoint))
        assert shown.returncode == 0, shown.stderr
        assert f"resource {RESOURCE}: {STOPPED}" in shown.stdout
        assert f"configuration CRC {now['crc']}" in shown.stdout
        assert "Main" in shown.stdout

        started = padt(*online("start", zenoh_endpoint))
        assert started.returncode == 0, started.stderr
        assert f"resource {RESOURCE}: RUN" in started.stdout
        wait_for(lambda: values(client)["Main.counter"] > 2)

        again = padt(*online("load", zenoh_endpoint, str(project), "--backup-dir", str(backup_dir)))
        assert again.returncode == 1
        assert "padt load: refused (state): a download is only possible in STOP" in again.stderr
        assert "Traceback" not in again.stderr
        assert status(client)["state"] == "RUN"
        assert len(backups(backup_dir)) == 1  # nothing loaded, nothing backed up

        as_json = padt(*online("status", zenoh_endpoint, "--json"))
        assert json.loads(as_json.stdout)["state"] == "RUN"

        stopped = padt(*online("stop", zenoh_endpoint))
        assert stopped.returncode == 0, stopped.stderr
        assert status(client)["state"] == STOPPED
        assert values(client)["Main.counter"] > 2

        reloaded = padt(
            *online("load", zenoh_endpoint, str(project), "--backup-dir", str(backup_dir))
        )
        assert reloaded.returncode == 0, reloaded.stderr
        assert values(client)["Main.counter"] == 0  # a download is a cold start
        assert status(client)["state"] == STOPPED


def test_corrupted_or_cut_transfer_keeps_the_old_configuration(
    tmp_path: Path, zenoh_endpoint: str
) -> None:
    project = write_project(tmp_path / "project")
    backup_dir = tmp_path / "backups"
    with running_resource(RESOURCE, tmp_path / "state", zenoh_endpoint) as (_, client):
        load_and_start(project, zenoh_endpoint, backup_dir, client)
        assert client.command("stop")["ok"]
        before, crc = values(client), status(client)["crc"]

        # another configuration, which a load would take with a cold start
        other = write_project(tmp_path / "other", CHANGED_ST)
        text = compile_checked([other]).artifact.to_json()
        assert load_artifact(text).crc != crc

        changed = text[:200] + ("A" if text[200] != "A" else "B") + text[201:]
        begun = client.command("transfer_begin", size=len(text), crc=crc32_hex(text))
        assert begun["ok"], begun
        assert client.command("transfer_chunk", offset=0, data=changed)["ok"]
        refused = client.command("load")
        assert refused["ok"] is False and refused["error"]["code"] == "transfer"
        assert "CRC" in refused["error"]["message"]

        (_, first), *_ = pieces(text, len(text) // 2)
        assert client.command("transfer_begin", size=len(text), crc=crc32_hex(text))["ok"]
        assert client.command("transfer_chunk", offset=0, data=first)["ok"]
        cut = client.command("load")
        assert cut["ok"] is False and cut["error"]["code"] == "transfer"
        assert "incomplete" in cut["error"]["message"]

        assert status(client)["crc"] == crc
        assert status(client)["state"] == STOPPED
        assert values(client) == before

        # every load consumes the transfer: a load with nothing transferred is refused
        assert client.command("load")["error"]["code"] == "transfer"

        send_artifact(client, load_artifact(text))  # the whole, correct text is taken
        assert client.command("load")["status"]["crc"] == load_artifact(text).crc


def test_reload_preview_confirm_and_perform(tmp_path: Path, zenoh_endpoint: str) -> None:
    project = write_project(tmp_path / "project")
    backup_dir = tmp_path / "backups"
    with running_resource(RESOURCE, tmp_path / "state", zenoh_endpoint) as (_, client):
        load_and_start(project, zenoh_endpoint, backup_dir, client)
        # the counter holds still while its program is stopped, so the value carried over
        # can be compared exactly; the resource stays running (RUN/UP STOP), as reload needs
        held = padt(*online("stop", zenoh_endpoint, "--program", "Main"))
        assert held.returncode == 0, held.stderr
        assert "program Main: STOP" in held.stdout
        counter, old_crc = values(client)["Main.counter"], status(client)["crc"]

        # a target cycle changed online, which a reload puts back to the project's 20
        faster = padt(*online("params", zenoh_endpoint, "--set", "target_cycle_ms=10"))
        assert faster.returncode == 0, faster.stderr
        write_project(project, CHANGED_ST)
        preview = padt(
            *online(
                "reload", zenoh_endpoint, str(project), "--preview", "--backup-dir", str(backup_dir)
            )
        )
        assert preview.returncode == 0, preview.stderr
        lines = preview.stdout.splitlines()
        assert any(line.split()[:3] == ["Main.counter", "converted", "INT"] for line in lines)
        assert any(line.split()[:2] == ["Main.extra", "new"] for line in lines)
        assert "summary: 0 kept, 1 converted, 0 initialised, 1 new, 0 deleted" in lines
        assert (
            "parameter reset: target_cycle_ms: 10 online, 20 in the project; the reload sets 20 "
            "(--keep-online target_cycle_ms keeps it)"
        ) in lines
        # what changed since the download, against the backup of what was loaded
        assert f"source diff against backup {backups(backup_dir)[0].name}:" in lines
        at = lines.index("--- main.st (changed)")
        assert lines[at + 1 :] == [
            "@@ -1,6 +1,7 @@",
            " PROGRAM Main",
            " VAR",
            "-  counter : INT := 0;",
            "+  counter : DINT := 0;",
            "+  extra : INT := 7;",
            " END_VAR",
            " counter := counter + 1;",
            " END_PROGRAM",
        ]
        assert status(client)["crc"] == old_crc
        assert not backups(backup_dir)[1:]  # a preview loads nothing

        done = padt(
            *online(
                "reload",
                zenoh_endpoint,
                str(project),
                "--yes",
                "--keep-online",
                "target_cycle_ms",
                "--backup-dir",
                str(backup_dir),
            )
        )
        assert done.returncode == 0, done.stderr
        new_crc = status(client)["crc"]
        assert new_crc != old_crc
        assert f"reload done: configuration CRC {old_crc} -> {new_crc}" in done.stdout
        assert "kept online: target_cycle_ms 10" in done.stdout.splitlines()
        now = values(client)
        assert now["Main.counter"] == counter and now["Main.extra"] == 7
        archive = backups(backup_dir)[-1]
        assert new_crc in archive.name
        assert restore_backup(archive)[1]["main.st"] == CHANGED_ST

        # a change that loses a value (DINT -> INT cannot convert) needs --yes
        write_project(project, COUNTER_ST)
        unconfirmed = padt(
            *online("reload", zenoh_endpoint, str(project), "--backup-dir", str(backup_dir))
        )
        assert unconfirmed.returncode == 1
        assert "initialised" in unconfirmed.stdout
        assert "confirm with --yes" in unconfirmed.stderr
        assert status(client)["crc"] == new_crc

        # a renamed variable keeps its value when the rename is given (OLD=NEW)
        write_project(project, CHANGED_ST.replace("counter", "total"))
        renamed = padt(
            *online(
                "reload",
                zenoh_endpoint,
                str(project),
                "--rename",
                "Main.counter=Main.total",
                "--yes",
                "--backup-dir",
                str(backup_dir),
            )
        )
        assert renamed.returncode == 0, renamed.stderr
        assert "summary: 2 kept, 0 converted, 0 initialised, 0 new, 0 deleted" in renamed.stdout
        assert values(client)["Main.total"] == counter

        restarted = padt(*online("start", zenoh_endpoint, "--program", "Main"))
        assert restarted.returncode == 0, restarted.stderr
        wait_for(lambda: values(client)["Main.total"] > counter)


def test_reload_that_needs_a_download_is_refused(tmp_path: Path, zenoh_endpoint: str) -> None:
    project = write_project(tmp_path / "project")
    backup_dir = tmp_path / "backups"
    with running_resource(RESOURCE, tmp_path / "state", zenoh_endpoint) as (_, client):
        loaded = padt(
            *online("load", zenoh_endpoint, str(project), "--backup-dir", str(backup_dir))
        )
        assert loaded.returncode == 0, loaded.stderr
        assert client.command("start")["ok"]
        crc = status(client)["crc"]

        write_project(project, extra="safety_time_ms = 700\n")
        refused = padt(
            *online(
                "reload", zenoh_endpoint, str(project), "--yes", "--backup-dir", str(backup_dir)
            )
        )
        assert refused.returncode == 1
        assert "needs STOP and download" in refused.stderr
        assert "safety_time_ms changes (600 -> 700)" in refused.stderr
        assert status(client)["crc"] == crc
        assert status(client)["state"] == "RUN"
        assert len(backups(backup_dir)) == 1


def test_load_refuses_a_project_for_another_resource(tmp_path: Path, zenoh_endpoint: str) -> None:
    project = write_project(tmp_path / "project")
    (project / "padt.toml").write_text(PADT_TOML.format(extra="").replace(RESOURCE, "Other"))
    with running_resource(RESOURCE, tmp_path / "state", zenoh_endpoint) as (_, client):
        refused = padt(
            *online("load", zenoh_endpoint, str(project), "--backup-dir", str(tmp_path / "b"))
        )
        assert refused.returncode == 1
        assert "refused (resource): the project is for resource Other" in refused.stderr
        assert status(client)["crc"] is None


def test_a_resource_that_does_not_answer(tmp_path: Path, zenoh_endpoint: str) -> None:
    with router(zenoh_endpoint), client_session(zenoh_endpoint):
        run = padt(*online("status", zenoh_endpoint))
    assert run.returncode == 1
    assert run.stderr.startswith(f"padt status: resource '{RESOURCE}' did not answer")
    assert len(run.stderr.splitlines()) == 1


def test_compile_errors_and_bad_options(tmp_path: Path, zenoh_endpoint: str) -> None:
    project = write_project(tmp_path / "project", COUNTER_ST.replace("+ 1;", "+ ;"))
    broken = padt(*online("load", zenoh_endpoint, str(project)))
    assert broken.returncode == 1
    assert "main.st:5:" in broken.stderr
    assert "padt load: refused (compile)" in broken.stderr
    missing = padt(*online("load", zenoh_endpoint, str(tmp_path / "none.st")))
    assert missing.returncode == 2
    bad_rename = padt(*online("reload", zenoh_endpoint, str(project), "--rename", "x"))
    assert bad_rename.returncode == 2 and "OLD=NEW" in bad_rename.stderr


# ---- without a resource


def test_rename_is_written_old_equals_new() -> None:
    assert parse_rename("Main.count=Main.total") == ("Main.total", "Main.count")
    for bad in ("x", "=y", "x=", "a=b=c"):
        with pytest.raises(Exception, match="OLD=NEW"):
            parse_rename(bad)


def test_chunks_fit_the_request_limit_even_after_escaping() -> None:
    text = '"\\' * 60_000  # every character doubles when JSON-encoded again
    cut = pieces(text)
    assert "".join(data for _, data in cut) == text
    assert [offset for offset, _ in cut] == [
        sum(len(data) for _, data in cut[:i]) for i in range(len(cut))
    ]
    for offset, data in cut:
        request = {"cmd": "transfer_chunk", "offset": offset, "data": data}
        assert len(json.dumps(request).encode()) <= MAX_REQUEST_BYTES


def _run(seed: str, configuration: str, pou: str = "11111111") -> CompileRun:
    return CompileRun(seed, True, (), configuration, {"Main": pou}, {"Main": "22222222"})


def test_compile_twice_gate(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    project = write_project(tmp_path / "project")
    checked = compile_checked([project])
    assert checked.config_text == (project / "padt.toml").read_text()
    crc = checked.artifact.crc

    def differing(paths: object, resource: str | None = None) -> CheckTwiceResult:
        first, second = _run("1", crc), _run("2", "0BADC0DE", "33333333")
        return CheckTwiceResult(first, second, compare(first, second))

    monkeypatch.setattr(compile_gate, "check_twice", differing)
    with pytest.raises(Refusal) as mismatch:
        compile_checked([project])
    assert mismatch.value.code == "check_twice"
    assert f"configuration CRC: {crc} != 0BADC0DE" in mismatch.value.message
    assert "POU Main CRC: 11111111 != 33333333" in mismatch.value.message

    def agreeing_elsewhere(paths: object, resource: str | None = None) -> CheckTwiceResult:
        return CheckTwiceResult(_run("1", "0BADC0DE"), _run("2", "0BADC0DE"), ())

    monkeypatch.setattr(compile_gate, "check_twice", agreeing_elsewhere)
    with pytest.raises(Refusal) as elsewhere:
        compile_checked([project])
    assert f"this compile gives configuration CRC {crc}" in elsewhere.value.message
    assert "0BADC0DE" in elsewhere.value.message


def test_backups_are_reproducible_and_proven(tmp_path: Path) -> None:
    checked = compile_checked([write_project(tmp_path / "project")])
    text = checked.artifact.to_json()
    info = BackupInfo("Loading test/1", "1.2", RESOURCE, "load", "padt load project")
    sources = {s.name: s.text for s in checked.project.sources}

    def write(folder: Path) -> Path:
        clock = iter([1_700_000_000_123_456_789]).__next__
        return write_backup(folder, info, text, sources, checked.config_text, clock)

    first, second = write(tmp_path / "a"), write(tmp_path / "b")
    assert first.name == f"Loading_test_1_{checked.artifact.crc}_20231114T221320Z.zip"
    assert first.read_bytes() == second.read_bytes()
    assert write(tmp_path / "a").name == first.name.replace(".zip", "-2.zip")
    with zipfile.ZipFile(first) as archive:
        assert archive.namelist() == sorted(archive.namelist())
        assert {i.date_time for i in archive.infolist()} == {(1980, 1, 1, 0, 0, 0)}
        manifest = json.loads(archive.read("MANIFEST.json"))
    assert manifest["time_utc"] == "2023-11-14T22:13:20Z"
    assert restore_backup(first) == (
        text,
        {"main.st": COUNTER_ST, "padt.toml": checked.config_text},
    )

    # a backup whose sources were altered afterwards no longer proves anything
    tampered = tmp_path / "tampered.zip"
    with zipfile.ZipFile(first) as source, zipfile.ZipFile(tampered, "w") as target:
        for item in source.infolist():
            data = source.read(item)
            if item.filename == "project/main.st":
                data = data.replace(b"+ 1", b"+ 2")
            target.writestr(item, data)
    with pytest.raises(BackupError, match="do not match the manifest"):
        restore_backup(tampered)


def test_a_configuration_that_cannot_be_kept_is_refused_before_anything_changes(
    tmp_path: Path, zenoh_endpoint: str
) -> None:
    state = tmp_path / "state"
    (state / "config").parent.mkdir(parents=True, exist_ok=True)
    (state / "config").write_text("not a folder")  # nothing can be stored below it
    project = write_project(tmp_path / "project")
    with running_resource(RESOURCE, state, zenoh_endpoint) as (_, client):
        loaded = padt(*online("load", zenoh_endpoint, str(project)), timeout=60)
        assert loaded.returncode == 1
        assert "padt load: refused (storage): the configuration cannot be kept in" in loaded.stderr
        assert status(client)["state"] == "STOP/INVALID CONFIGURATION"
        # mended, a load goes through; then the folder goes again, and a reload is refused
        (state / "config").unlink()
        loaded = padt(*online("load", zenoh_endpoint, str(project)), timeout=60)
        assert loaded.returncode == 0, loaded.stderr
        assert client.command("start")["ok"]
        stored = state / "config" / "artifact.json"
        assert stored.stat().st_mode & 0o777 == 0o600  # it holds the accounts' verifiers
        crc = status(client)["crc"]
        shutil.rmtree(state / "config")
        (state / "config").write_text("not a folder")
        write_project(tmp_path / "project", CHANGED_ST)
        reloaded = padt(*online("reload", zenoh_endpoint, str(project), "--yes"), timeout=60)
        assert reloaded.returncode == 1
        assert "refused (storage): the configuration cannot be kept in" in reloaded.stderr
        assert status(client)["crc"] == crc and status(client)["state"] == "RUN"
        assert values(client)["Main.counter"] > 0
