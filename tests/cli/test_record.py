"""`padt record` and `padt recordings` as an engineer or a CI job runs them: real
processes against a real runtime over real Zenoh, with `--user` and PADT_PASSWORD; the MCAP
files they write read back with the recording reader."""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from backend.engineering import recordings
from runtime.contract.protocol import GetValues
from runtime.contract.recording import read_recording
from tests.conftest import REPO, free_port, padt
from tests.support.recording_cell import PASSWORDS, RESOURCE, Cell, recording_cell


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
    now = cell.logged_in("viewer").ask(GetValues()).values["Main.count"]
    trigger = f"Main.count >= {now + 30}"  # fires once the three cycles before it are in
    args = ["--var", "Main.count", "--trigger", trigger]
    args += ["--pre-cycles", "3", "--cycles", "10", "-o", str(output)]
    done = as_user(cell, "op", "record", *args)
    assert done.returncode == 0, done.stderr
    assert f"after {trigger} becomes true" in done.stderr
    counts = read_recording(output).column("Main.count")
    assert counts == list(range(now + 30 - 3, now + 30 + 10))


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
