"""`padt values / write / force / freeze / step / unfreeze / events / params` as a person at a
terminal or a CI job runs them: real processes against a real runtime over real Zenoh, with
`--user` and PADT_PASSWORD, and the refusals they get."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from backend.engineering.project import user_entry
from backend.engineering.resource_client import ResourceClient
from runtime.contract.accounts import hash_password
from runtime.contract.artifact import UserAccount
from tests.conftest import REPO, padt
from tests.support.runtime_process import running_resource, setup_env

RESOURCE = "Cell"
PASSWORDS = {"admin": "Admin-1", "engineer": "Engineer-2", "viewer": "Viewer-3"}
LEVELS = {"admin": "administrator", "engineer": "read-write", "viewer": "read"}

PADT_TOML = """\
[project]
name = "Online commands"

[resource]
name = "Cell"
target_cycle_ms = 20
safety_operation = false
global_forcing_allowed = true

[[resource.program]]
name = "Main"
pou = "Main"
id = 1
local_forcing_allowed = true
"""

MAIN_ST = """\
PROGRAM Main
VAR
  counter : DINT := 0;
  limit : INT := 100;
  run : BOOL := TRUE;
  delay : TIME := T#1s500ms;
  label : STRING[16] := 'cell';
END_VAR
IF run THEN counter := counter + 1; END_IF;
END_PROGRAM
"""


def write_project(folder: Path) -> Path:
    folder.mkdir(parents=True)
    accounts = "".join(
        "\n" + user_entry(UserAccount(name, LEVELS[name], hash_password(password)))
        for name, password in PASSWORDS.items()
    )
    (folder / "padt.toml").write_text(PADT_TOML + accounts)
    (folder / "main.st").write_text(MAIN_ST)
    return folder


def as_user(user: str, command: str, endpoint: str, *args: str) -> subprocess.CompletedProcess[str]:
    resource = ["--resource", RESOURCE, "--zenoh", endpoint, "--user", user]
    return padt(command, *args, *resource, env={"PADT_PASSWORD": PASSWORDS[user]})


@contextmanager
def loaded_cell(tmp_path: Path, endpoint: str) -> Iterator[ResourceClient]:
    project = write_project(tmp_path / "project")
    with running_resource(RESOURCE, tmp_path / "state", endpoint) as (_, client):
        # a resource with nothing loaded has no accounts yet: the first load logs in with
        # the setup secret the runtime made
        online = ["--resource", RESOURCE, "--zenoh", endpoint]
        backups = ["--backup-dir", str(tmp_path / "backups")]
        loaded = padt("load", str(project), *online, *backups, env=setup_env(tmp_path / "state"))
        assert loaded.returncode == 0, loaded.stderr
        started = as_user("engineer", "start", endpoint)
        assert started.returncode == 0, started.stderr
        yield client


def follow(args: list[str], lines: int, user: str = "viewer") -> list[str]:
    """A `--follow` command: its first lines, then Ctrl-C as a person would."""
    command = [sys.executable, "-m", "padt.cli", *args, "--user", user]
    env = {**os.environ, "PADT_PASSWORD": PASSWORDS[user]}
    process = subprocess.Popen(command, cwd=REPO, env=env, stdout=subprocess.PIPE, text=True)
    assert process.stdout is not None
    seen = [process.stdout.readline() for _ in range(lines)]
    process.send_signal(signal.SIGINT)
    assert process.wait(timeout=15) == 0
    return seen


def test_values_write_force_and_single_step(tmp_path: Path, zenoh_endpoint: str) -> None:
    with loaded_cell(tmp_path, zenoh_endpoint):
        shown = as_user("viewer", "values", zenoh_endpoint)
        assert shown.returncode == 0, shown.stderr
        rows = {line.split()[0]: line.split()[1:] for line in shown.stdout.splitlines()[1:]}
        assert rows["Main.delay"] == ["TIME", "T#1s500ms"]
        assert rows["Main.run"] == ["BOOL", "TRUE"]
        assert rows["Main.label"] == ["STRING[16]", "'cell'"]

        as_json = as_user("viewer", "values", zenoh_endpoint, "main.limit", "--json")
        assert json.loads(as_json.stdout)["values"] == {"Main.limit": 100}

        # writing needs read-write: the viewer is refused by the resource itself
        refused = as_user("viewer", "write", zenoh_endpoint, "Main.limit", "7")
        assert refused.returncode == 1 and "refused (forbidden)" in refused.stderr
        written = as_user("engineer", "write", zenoh_endpoint, "Main.limit", "INT#7")
        assert written.returncode == 0, written.stderr
        assert written.stdout.strip() == "Main.limit := 7"
        text = as_user("engineer", "write", zenoh_endpoint, "Main.label", "'line 2'")
        assert text.stdout.strip() == "Main.label := 'line 2'"
        wrong = as_user("engineer", "write", zenoh_endpoint, "Main.limit", "TRUE")
        assert wrong.returncode == 2 and "not an ST literal of type INT" in wrong.stderr
        outside = as_user("engineer", "write", zenoh_endpoint, "Main.limit", "40000")
        assert outside.returncode == 1 and "refused (bad_value)" in outside.stderr

        # forcing: a value prepared, forcing started, the value holds, forcing ends
        force = ["force", "set", "Main.run", "FALSE"]
        assert as_user("engineer", *force[:1], zenoh_endpoint, *force[1:]).returncode == 0
        started = as_user("engineer", "force", zenoh_endpoint, "start", "--program", "Main")
        assert started.returncode == 0, started.stderr
        assert "forcing started: Main" in started.stdout
        assert any(
            line.split()[:5] == ["Main.run", "Main", "FALSE", "ON", "forced"]
            for line in started.stdout.splitlines()
        ), started.stdout
        frozen_at = json.loads(as_user("viewer", "values", zenoh_endpoint, "--json").stdout)
        time.sleep(0.3)
        later = json.loads(as_user("viewer", "values", zenoh_endpoint, "--json").stdout)
        assert later["values"]["Main.counter"] == frozen_at["values"]["Main.counter"]
        shown = as_user("viewer", "force", zenoh_endpoint, "show", "--json")
        assert json.loads(shown.stdout)["started"] == ["Main"]
        assert (
            as_user("engineer", "force", zenoh_endpoint, "stop", "--program", "Main").returncode
            == 0
        )
        cleared = as_user("engineer", "force", zenoh_endpoint, "clear", "Main.run")
        assert "forcing started: nowhere" in cleared.stdout and "Main.run" not in cleared.stdout
        as_user("engineer", "write", zenoh_endpoint, "Main.run", "TRUE")

        # single step: frozen, three program cycles, running again
        frozen = as_user("engineer", "freeze", zenoh_endpoint, "--program", "Main")
        assert frozen.returncode == 0 and "program Main: RUN_FREEZE" in frozen.stdout
        before = json.loads(as_user("viewer", "values", zenoh_endpoint, "--json").stdout)
        stepped = as_user("engineer", "step", zenoh_endpoint, "--program", "Main", "--cycles", "3")
        assert stepped.returncode == 0, stepped.stderr
        after = json.loads(as_user("viewer", "values", zenoh_endpoint, "--json").stdout)
        assert after["values"]["Main.counter"] == before["values"]["Main.counter"] + 3
        thawed = as_user("engineer", "unfreeze", zenoh_endpoint, "--program", "Main")
        assert "program Main: RUN" in thawed.stdout


def test_follow_events_and_parameters(tmp_path: Path, zenoh_endpoint: str) -> None:
    with loaded_cell(tmp_path, zenoh_endpoint):
        online = ["--resource", RESOURCE, "--zenoh", zenoh_endpoint]
        lines = follow(["values", "Main.counter", "--follow", "--period-ms", "50", *online], 3)
        counters = [int(line.split("Main.counter=")[1]) for line in lines]
        assert counters == sorted(counters) and counters[0] < counters[-1]
        messages = follow(["values", "Main.counter", "--follow", "--json", *online], 2)
        assert all(json.loads(m)["values"]["Main.counter"]["quality"] == "live" for m in messages)

        events = as_user("viewer", "events", zenoh_endpoint, "--json")
        kinds = [json.loads(line)["kind"] for line in events.stdout.splitlines()]
        assert "load" in kinds and "start" in kinds
        # following: the log so far, then what happens next (a parameter change)
        command = [sys.executable, "-m", "padt.cli", "events", "--follow", *online]
        command += ["--user", "viewer"]
        env = {**os.environ, "PADT_PASSWORD": PASSWORDS["viewer"]}
        process = subprocess.Popen(command, cwd=REPO, env=env, stdout=subprocess.PIPE, text=True)
        try:
            assert process.stdout is not None
            while "logged in" not in process.stdout.readline():  # its own login is the last
                pass
            changed = as_user("admin", "params", zenoh_endpoint, "--set", "target_cycle_ms=30")
            assert changed.returncode == 0, changed.stderr
            assert changed.stdout.strip() == "parameter target_cycle_ms: 30"
            line = process.stdout.readline()
            while "parameter" not in line:
                line = process.stdout.readline()
            assert "target_cycle_ms changed from 20 to 30" in line and "admin" in line
        finally:
            process.send_signal(signal.SIGINT)
            assert process.wait(timeout=15) == 0

        shown = as_user("viewer", "params", zenoh_endpoint)
        table = dict(line.split(None, 1) for line in shown.stdout.splitlines() if line.strip())
        assert table["target_cycle_ms"].strip() == "30"
        assert table["local_forcing_allowed"].strip() == "ON"  # program Main's
        refused = as_user(
            "engineer", "params", zenoh_endpoint, "--set", "allow_online_settings=off"
        )
        assert refused.returncode == 1 and "refused (forbidden)" in refused.stderr
        bad = as_user("admin", "params", zenoh_endpoint, "--set", "watchdog_ms=1")
        assert bad.returncode == 1 and "refused (bad_value)" in bad.stderr


def test_without_a_login_the_refusal_says_how(tmp_path: Path, zenoh_endpoint: str) -> None:
    with loaded_cell(tmp_path, zenoh_endpoint):
        online = ["--resource", RESOURCE, "--zenoh", zenoh_endpoint]
        anonymous = padt("values", *online)
        assert anonymous.returncode == 1
        assert "refused (unauthenticated)" in anonymous.stderr
        assert "log in with --user NAME" in anonymous.stderr
        assert "Traceback" not in anonymous.stderr
        # --user without a terminal to ask the password at (a script): said, not a traceback
        unasked = padt("values", *online, "--user", "admin")
        assert unasked.returncode == 2, unasked.stderr
        assert "set PADT_PASSWORD" in unasked.stderr and "Traceback" not in unasked.stderr


def test_a_reader_that_stops_reading_ends_padt_quietly(tmp_path: Path, zenoh_endpoint: str) -> None:
    with loaded_cell(tmp_path, zenoh_endpoint):
        online = f"--resource {RESOURCE} --zenoh {zenoh_endpoint} --user viewer"
        env = {**os.environ, "PADT_PASSWORD": PASSWORDS["viewer"]}
        padt_command = f"{sys.executable} -m padt.cli"
        pipelines = [
            # the reader is gone before padt writes a line
            *(f"{padt_command} {command} {online} | true" for command in ("status", "events")),
            # the reader stops after two lines while padt goes on printing
            f"{padt_command} values --follow --period-ms 20 {online} | head -2",
        ]
        for pipeline in pipelines:
            piped = subprocess.run(
                f"set -o pipefail; {pipeline}",
                shell=True,
                executable="/bin/bash",
                cwd=REPO,
                env=env,
                capture_output=True,
                text=True,
                timeout=60,
            )
            assert piped.stderr == "", (pipeline, piped.stderr)
            assert piped.returncode in (0, 141), (pipeline, piped.returncode)
