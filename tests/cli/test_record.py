"""`padt record` and `padt recordings` as an engineer or a CI job runs them: real
processes against a real runtime over real Zenoh, with `--user` and PADT_PASSWORD; the MCAP
files they write read back with the recording reader."""

from __future__ import annotations

import json
import os
import re
import shutil
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from backend.engineering import recordings
from backend.engineering.project import compile_project, load_project
from backend.engineering.resource_client import ResourceClient
from runtime.contract.recording import read_recording
from tests.conftest import REPO, free_port, padt
from tests.support.lying_resource import FILE, lying_resource
from tests.support.recording_cell import (
    PASSWORDS,
    RESOURCE,
    Cell,
    recording_cell,
    write_project,
)
from tests.support.runtime_process import client_session, router, runtime_process, store_artifact


@pytest.fixture(scope="module")
def cell(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Cell]:
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    with recording_cell(tmp_path_factory.mktemp("record"), endpoint) as found:
        yield found


def as_user(cell: Cell, user: str, command: str, *args: str) -> subprocess.CompletedProcess[str]:
    online = ["--resource", RESOURCE, "--zenoh", cell.endpoint, "--user", user]
    return padt(command, *args, *online, env={"PADT_PASSWORD": PASSWORDS[user]})


SUMMARY = re.compile(r"recorded (\d+) cycles, (\d+) dropped -> (.+) \(([\d.]+ (?:bytes|kB|MB))\)")


def test_record_fifty_cycles_into_a_file(cell: Cell, tmp_path: Path) -> None:
    output = tmp_path / "x.mcap"
    args = ["--var", "Main.count", "--var", "main.level", "--cycles", "50", "-o", str(output)]
    done = as_user(cell, "op", "record", *args)
    assert done.returncode == 0, done.stderr
    summary = SUMMARY.fullmatch(done.stdout.strip())
    assert summary is not None, done.stdout
    assert (summary[1], summary[2], summary[3]) == ("50", "0", str(output))
    assert "recording " in done.stderr and "for 50 cycles" in done.stderr

    recording = read_recording(output)
    assert recording.complete, recording.problem
    assert len(recording.rows) == 50
    assert sorted(path for path, _ in recording.header.variables) == ["Main.count", "Main.level"]
    counts = recording.column("Main.count")
    assert counts == list(range(counts[0], counts[0] + 50))
    assert [p for p in tmp_path.iterdir()] == [output]  # no part file left behind

    # downloaded, so deleted on the resource
    listed = as_user(cell, "viewer", "recordings")
    assert listed.returncode == 0, listed.stderr
    assert recording.header.recording not in listed.stdout


def test_ctrl_c_stops_the_recording_and_keep_leaves_it_listed(cell: Cell, tmp_path: Path) -> None:
    output = tmp_path / "open.mcap"
    command = [sys.executable, "-m", "padt.cli", "record", "--var", "Main*", "--keep"]
    command += ["-o", str(output), "--resource", RESOURCE, "--zenoh", cell.endpoint]
    command += ["--user", "op"]
    env = {**os.environ, "PADT_PASSWORD": PASSWORDS["op"]}
    process = subprocess.Popen(
        command, cwd=REPO, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    assert process.stderr is not None
    started = process.stderr.readline()
    assert "until Ctrl-C" in started, started
    recording_id = started.split()[1].rstrip(":")
    viewer = cell.logged_in("viewer")
    while recordings.find(viewer, recording_id).cycles < 10:  # some cycles in: then Ctrl-C
        time.sleep(0.05)
    process.send_signal(signal.SIGINT)
    out, err = process.communicate(timeout=60)
    assert process.returncode == 0, err
    summary = SUMMARY.fullmatch(out.strip())
    assert summary is not None, out
    recording = read_recording(output)
    assert recording.complete and len(recording.rows) == int(summary[1]) > 0
    recorded = {path for path, _ in recording.header.variables}
    assert {"Main.count", "Main.alarm", "Main.elapsed"} <= recorded

    listed = as_user(cell, "viewer", "recordings")
    assert listed.returncode == 0, listed.stderr
    header, *rows = listed.stdout.splitlines()
    assert header.split()[:5] == ["id", "state", "variables", "cycles", "dropped"]
    row = next(line.split() for line in rows if line.startswith(recording_id))
    assert row[1] == "done" and row[3] == summary[1] and f"{recording_id}-1.mcap" in row

    as_json = as_user(cell, "viewer", "recordings", "--json")
    found = {r["id"]: r for r in json.loads(as_json.stdout)}
    assert found[recording_id]["cycles"] == int(summary[1])

    # kept: downloaded again later, then deleted
    again = tmp_path / "again.mcap"
    fetched = as_user(cell, "viewer", "recordings", "--download", recording_id, "-o", str(again))
    assert fetched.returncode == 0, fetched.stderr
    assert fetched.stdout.startswith(f"downloaded {recording_id} -> {again} (")
    assert again.read_bytes() == output.read_bytes()
    refused = as_user(cell, "viewer", "recordings", "--delete", recording_id)
    assert refused.returncode == 1 and "refused (forbidden)" in refused.stderr
    deleted = as_user(cell, "op", "recordings", "--delete", recording_id)
    assert deleted.returncode == 0 and deleted.stdout.startswith(f"deleted {recording_id};")
    gone = as_user(cell, "viewer", "recordings", "--download", recording_id, "-o", str(again))
    assert gone.returncode == 1 and "refused (unknown_recording)" in gone.stderr
    no_output = as_user(cell, "viewer", "recordings", "--download", recording_id)
    assert no_output.returncode == 2 and "--download needs -o FILE.mcap" in no_output.stderr


def test_ctrl_c_before_the_trigger_fired_records_nothing(cell: Cell, tmp_path: Path) -> None:
    output = tmp_path / "never.mcap"
    command = [sys.executable, "-m", "padt.cli", "record", "--var", "Main.count"]
    command += ["--trigger", "Main.count < 0", "--cycles", "5", "-o", str(output)]
    command += ["--resource", RESOURCE, "--zenoh", cell.endpoint, "--user", "op"]
    env = {**os.environ, "PADT_PASSWORD": PASSWORDS["op"]}
    process = subprocess.Popen(
        command, cwd=REPO, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    assert process.stderr is not None
    started = process.stderr.readline()
    assert "after Main.count < 0 becomes true, for 5 cycles" in started, started
    recording_id = started.split()[1].rstrip(":")
    process.send_signal(signal.SIGINT)
    out, err = process.communicate(timeout=60)
    assert process.returncode == 1 and out == ""
    assert f"padt record: recording {recording_id} wrote no file: nothing was recorded" in err
    assert not output.exists()
    listed = recordings.list_recordings(cell.logged_in("viewer"))
    assert recording_id not in {r.id for r in listed}


def test_a_trigger_with_cycles_before_it(cell: Cell, tmp_path: Path) -> None:
    output = tmp_path / "trig.mcap"
    # Main.level rises from 0 to 49.5 every 100 cycles: it passes 25 at every count 50, 150...
    args = ["--var", "Main.count", "--var", "Main.level", "--trigger", "Main.level >= 25.0"]
    args += ["--pre-cycles", "3", "--cycles", "10", "-o", str(output)]
    done = as_user(cell, "op", "record", *args)
    assert done.returncode == 0, done.stderr
    assert "after Main.level >= 25.0 becomes true, for 10 cycles" in done.stderr
    recording = read_recording(output)
    counts, levels = recording.column("Main.count"), recording.column("Main.level")
    assert counts == list(range(counts[0], counts[0] + len(counts)))
    fired = len(counts) - 10  # the trigger's cycle and 9 after it
    # three cycles before it (fewer only when the recording began less than three before)
    assert 0 <= fired <= 3
    assert counts[fired] % 100 == 50 and levels[fired] == 25.0
    assert all(level < 25.0 for level in levels[:fired])


def test_rotated_parts_are_written_beside_the_file(cell: Cell, tmp_path: Path) -> None:
    output = tmp_path / "long.mcap"
    args = ["--var", "Main.count", "--seconds", "3", "--rotate-s", "1", "-o", str(output)]
    done = as_user(cell, "op", "record", *args)
    assert done.returncode == 0, done.stderr
    files = sorted(tmp_path.iterdir(), key=lambda p: (len(p.name), p.name))
    assert files[0] == output and files[1] == tmp_path / "long-2.mcap", files
    assert f"-> {output}, {tmp_path / 'long-2.mcap'}" in done.stdout
    counts = [c for path in files for c in read_recording(path).column("Main.count")]
    assert counts == list(range(counts[0], counts[0] + len(counts)))
    summary = SUMMARY.fullmatch(done.stdout.strip())
    assert summary is not None and summary[1] == str(len(counts))


def test_all_inputs_recorded_replay_identically_and_a_change_is_found(
    cell: Cell, tmp_path: Path
) -> None:
    output = tmp_path / "all.mcap"
    args = ["--all-inputs", "--var", "Main.count", "--cycles", "100", "-o", str(output)]
    done = as_user(cell, "op", "record", *args)
    assert done.returncode == 0, done.stderr
    assert ": 1 variable and all inputs, for 100 cycles" in done.stderr
    assert read_recording(output).artifact is not None

    same = padt("replay", str(output), str(cell.project))
    assert same.returncode == 0, same.stderr
    assert same.stdout.strip() == "replay: 100 cycles, identical"
    changed = tmp_path / "changed"
    shutil.copytree(cell.project, changed)
    main = changed / "main.st"
    main.write_text(main.read_text().replace("count := count + 1;", "count := count + 2;"))
    differs = padt("replay", str(output), str(changed))
    assert differs.returncode == 1, differs.stderr
    assert "(the 1st recorded) differs in Main.count" in differs.stdout


@pytest.mark.usefixtures("native_tier")
def test_a_recording_replays_alike_on_both_tiers(cell: Cell, tmp_path: Path) -> None:
    """The default tier is native, as `padt runtime`'s: Main built as C (into the cache),
    where `--tier python` builds nothing; each tier reproduces the runtime's recording
    and names the same first difference of a changed version."""
    output = tmp_path / "tiers.mcap"
    args = ["--all-inputs", "--var", "Main.count", "--var", "Main.level", "--cycles", "50"]
    done = as_user(cell, "op", "record", *args, "-o", str(output))
    assert done.returncode == 0, done.stderr
    changed = tmp_path / "changed"
    shutil.copytree(cell.project, changed)
    main = changed / "main.st"
    main.write_text(main.read_text().replace("/ 2.0;", "/ 4.0;"))
    cache = tmp_path / "native"
    env = {"PADT_NATIVE_CACHE": str(cache)}
    python = padt("replay", str(output), str(cell.project), "--tier", "python", env=env)
    assert not list(cache.rglob("*.so"))
    native = padt("replay", str(output), str(cell.project), env=env)
    assert list(cache.rglob("*.so")), native.stderr
    assert python.returncode == native.returncode == 0, python.stderr + native.stderr
    assert python.stdout.strip() == native.stdout.strip() == "replay: 50 cycles, identical"
    differs = [
        padt("replay", str(output), str(changed), "--tier", tier, env=env)
        for tier in ("python", "native")
    ]
    assert [d.returncode for d in differs] == [1, 1], differs[0].stderr + differs[1].stderr
    assert differs[0].stdout == differs[1].stdout
    assert "recorded) differs in Main.level: recorded " in differs[0].stdout


def test_refusals_and_bad_options(cell: Cell, tmp_path: Path) -> None:
    output = tmp_path / "no.mcap"
    # recording needs the operator level: a read-level user is refused by the resource
    refused = as_user(cell, "viewer", "record", "--var", "Main.count", "-o", str(output))
    assert refused.returncode == 1
    assert "padt record: refused (forbidden)" in refused.stderr and "operator" in refused.stderr
    assert not output.exists()

    unknown = as_user(cell, "op", "record", "--var", "Main.nothing", "-o", str(output))
    assert unknown.returncode == 1 and "Main.nothing" in unknown.stderr

    bad = as_user(cell, "op", "record", "--var", "Main.count", "--trigger", "Main.count >> 3",
                  "-o", str(output))  # fmt: skip
    assert bad.returncode == 2
    assert "padt record: --trigger: 'Main.count >> 3'" in bad.stderr and "OP one of" in bad.stderr

    nothing = as_user(cell, "op", "record", "-o", str(output))
    assert nothing.returncode == 2 and "--var" in nothing.stderr

    both = as_user(cell, "op", "record", "--var", "Main.count", "--cycles", "5",
                   "--seconds", "5", "-o", str(output))  # fmt: skip
    assert both.returncode == 2 and "not allowed with" in both.stderr

    no_login = padt("record", "--var", "Main.count", "-o", str(output), "--resource", RESOURCE,
                    "--zenoh", cell.endpoint)  # fmt: skip
    assert no_login.returncode == 1 and "unauthenticated" in no_login.stderr
    assert not output.exists()


def test_a_restart_of_the_runtime_during_a_recording_is_waited_out(tmp_path: Path) -> None:
    """The runtime ends (it finishes the file) and comes back: padt record waits, logs in
    again and fetches what was recorded."""
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    project = write_project(tmp_path / "project")
    artifact = compile_project(load_project([project])).artifact
    assert artifact is not None
    state_dir = tmp_path / "state"
    store_artifact(state_dir, artifact)
    output = tmp_path / "restart.mcap"
    command = [sys.executable, "-m", "padt.cli", "record", "--var", "Main.count"]
    command += ["--seconds", "60", "-o", str(output), "--resource", RESOURCE]
    command += ["--zenoh", endpoint, "--user", "op"]
    env = {**os.environ, "PADT_PASSWORD": PASSWORDS["op"]}
    with router(endpoint), client_session(endpoint) as session:
        client = ResourceClient(session, RESOURCE)
        with runtime_process(RESOURCE, state_dir, endpoint):
            client.wait_until_answering()
            client.login("viewer", PASSWORDS["viewer"])
            process = subprocess.Popen(
                command, cwd=REPO, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                text=True,
            )  # fmt: skip
            assert process.stderr is not None
            recording_id = process.stderr.readline().split()[1].rstrip(":")
            while recordings.find(client, recording_id).cycles < 10:
                time.sleep(0.05)
        # the runtime is gone; it comes back with the same state folder
        with runtime_process(RESOURCE, state_dir, endpoint):
            out, err = process.communicate(timeout=90)
    assert process.returncode == 0, err
    recording = read_recording(output)
    assert recording.complete, recording.problem
    counts = recording.column("Main.count")
    assert out.startswith(f"recorded {len(counts)} cycles (the runtime restarted: dropped ones")
    assert f"-> {output} (" in out
    assert len(counts) >= 10 and counts == list(range(counts[0], counts[0] + len(counts)))


@pytest.mark.parametrize("lie", ["none", "offset"])
def test_a_broken_download_leaves_no_file_that_looks_whole(lie: str, tmp_path: Path) -> None:
    output = tmp_path / "x.mcap"
    with lying_resource(f"tcp/127.0.0.1:{free_port()}") as liar:
        liar.lie = lie
        online = ["--resource", "Fake", "--zenoh", liar.endpoint]
        fetched = padt("recordings", "--download", "x", "-o", str(output), *online)
    if lie == "none":
        assert fetched.returncode == 0, fetched.stderr
        assert output.read_bytes() == FILE and list(tmp_path.iterdir()) == [output]
    else:
        assert fetched.returncode == 1
        assert "padt recordings: refused (bad_reply): resource Fake sent bytes from" in (
            fetched.stderr
        )
        assert list(tmp_path.iterdir()) == []  # neither x.mcap nor x.mcap.part
