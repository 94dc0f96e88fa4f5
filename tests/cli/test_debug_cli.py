"""`padt debug` as an engineer at a terminal runs it: real processes against one real
runtime over real Zenoh, with accounts, from inside the project folder (files named by
their paths there). Breakpoints for one FB instance, a condition, stepping into a method
called through an interface and out, a FUNCTION's frame, writes and forcing at a break,
the other program running on, the silent client's automatic continue, and refusals."""

from __future__ import annotations

import json
import subprocess
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest

from backend.engineering.project import compile_project, load_project, user_entry
from runtime.contract.accounts import hash_password
from runtime.contract.artifact import UserAccount
from tests.conftest import free_port, padt
from tests.support.runtime_process import running_resource, store_artifact

RESOURCE = "Cell"
PASSWORDS = {
    "admin": "Admin-1",
    "engineer": "Engineer-2",
    "op": "Operator-3",
    "viewer": "Viewer-4",
}
LEVELS = {"admin": "administrator", "engineer": "read-write", "op": "operator", "viewer": "read"}

PADT_TOML = """\
[project]
name = "Debugging"

[resource]
name = "Cell"
target_cycle_ms = 50
safety_time_ms = 10000
watchdog_ms = 5000
safety_operation = {safety}
global_forcing_allowed = true
autostart = "cold"

[[resource.program]]
name = "Main"
pou = "Main"
id = 1
priority = 1
local_forcing_allowed = true

[[resource.program]]
name = "Other"
pou = "Other"
id = 2
priority = 0
"""

COUNTER_ST = """\
INTERFACE ICount
  METHOD Bump : DINT
  VAR_INPUT by : DINT; END_VAR
  END_METHOD
END_INTERFACE

FUNCTION Twice : DINT
VAR_INPUT x : DINT; END_VAR
VAR tmp : DINT; END_VAR
tmp := x * 2;
Twice := tmp;
END_FUNCTION

FUNCTION_BLOCK Counter IMPLEMENTS ICount
VAR_INPUT step : DINT; END_VAR
VAR_OUTPUT total : DINT; END_VAR
total := total + step;
total := Twice(total) / 2;
METHOD PUBLIC Bump : DINT
VAR_INPUT by : DINT; END_VAR
total := total + by;
Bump := total;
END_METHOD
END_FUNCTION_BLOCK
"""

MAIN_ST = """\
PROGRAM Main
VAR a, b : Counter; i : DINT; n : DINT; c : ICount; END_VAR
a(step := 1);
b(step := 2);
c := a;
n := c.Bump(by := 3);
FOR i := 1 TO 3 DO
  n := n + i;
END_FOR;
END_PROGRAM

PROGRAM Other
VAR ticks : DINT; END_VAR
ticks := ticks + 1;
END_PROGRAM
"""


def write_project(folder: Path, safety: bool = False) -> Path:
    (folder / "lib").mkdir(parents=True, exist_ok=True)
    accounts = "".join(
        "\n" + user_entry(UserAccount(name, LEVELS[name], hash_password(password)))
        for name, password in PASSWORDS.items()
    )
    toml = PADT_TOML.format(safety="true" if safety else "false")
    (folder / "padt.toml").write_text(toml + accounts)
    (folder / "main.st").write_text(MAIN_ST)
    (folder / "lib" / "counter.st").write_text(COUNTER_ST)
    return folder


@dataclass(frozen=True)
class Cell:
    project: Path
    endpoint: str

    def padt(
        self, *args: str, user: str = "engineer", cwd: Path | None = None
    ) -> subprocess.CompletedProcess[str]:
        """`padt ARGS` against the cell, run from inside the project folder."""
        online = ["--resource", RESOURCE, "--zenoh", self.endpoint, "--user", user]
        environment = {"PADT_PASSWORD": PASSWORDS[user]}
        while True:
            done = padt(*args, *online, env=environment, cwd=cwd or self.project)
            # each command logs in; an account may begin 30 logins at once, then 2 a
            # second: a command refused for that is tried again, as its message says
            if "login refused (busy)" not in done.stderr:
                return done
            time.sleep(0.5)

    def ok(self, *args: str, user: str = "engineer", cwd: Path | None = None) -> str:
        done = self.padt(*args, user=user, cwd=cwd)
        assert done.returncode == 0, (args, done.stdout, done.stderr)
        return done.stdout

    def json(self, *args: str, user: str = "engineer") -> Any:
        return json.loads(self.ok(*args, "--json", user=user))

    def program(self, name: str) -> dict[str, Any]:
        status = self.json("status", user="viewer")
        found: dict[str, Any] = next(x for x in status["programs"] if x["name"] == name)
        return found


@pytest.fixture(scope="module")
def cell(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Cell]:
    base = tmp_path_factory.mktemp("debug")
    project = write_project(base / "project")
    artifact = compile_project(load_project([project])).artifact
    assert artifact is not None
    store_artifact(base / "state", artifact)
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    with running_resource(RESOURCE, base / "state", endpoint):
        yield Cell(project, endpoint)


@pytest.fixture(autouse=True)
def nothing_armed_after(cell: Cell) -> Iterator[None]:
    yield
    cell.padt("debug", "clear")


def until(what: Callable[[], Any], timeout_s: float = 60) -> Any:
    """`what()` once it is truthy; patient on a loaded machine."""
    deadline = time.monotonic() + timeout_s
    while True:
        found = what()
        if found:
            return found
        assert time.monotonic() < deadline, "not within the time"
        time.sleep(0.2)


def variables(cell: Cell, *args: str) -> dict[str, dict[str, Any]]:
    shown = cell.json("debug", "vars", "Main", *args)["variables"]
    return {v["name"]: v for v in shown}


def test_a_condition_stops_only_for_the_chosen_instance(cell: Cell) -> None:
    # one Counter FB, called by Main.a (step 1) and Main.b (step 2)
    armed = cell.ok("debug", "set", "lib/counter.st:17", "--condition", "step = 2")
    assert armed.strip().endswith("at lib/counter.st:17 if step = 2"), armed
    for _ in range(2):  # each stop is in b, never in a
        stopped = cell.ok("debug", "wait", "--timeout", "60")
        assert stopped.startswith("Main stopped at lib/counter.st:17 in Counter (instance Main.b)")
        assert ", breakpoint " in stopped
        shown = variables(cell)
        assert shown["step"]["value"] == 2 and shown["step"]["path"] == "Main.b.step"
        assert cell.ok("debug", "continue", "Main").strip() == "Main continues"
    listed = cell.json("debug", "list")["breakpoints"]
    assert [(b["file"], b["line"], b["verified"]) for b in listed] == [("lib/counter.st", 17, True)]
    assert listed[0]["hits"] >= 2

    # the same line for instance a only, named by the file's absolute path; clearing
    # every breakpoint lets Main continue if it stands at b's again
    assert cell.ok("debug", "clear").strip() == "every breakpoint cleared"
    path = str(cell.project / "lib" / "counter.st")
    cell.ok("debug", "set", f"{path}:17", "--instance", "Main.a")
    stopped = cell.ok("debug", "wait", "--timeout", "60")
    assert stopped.startswith("Main stopped at lib/counter.st:17 in Counter (instance Main.a)")
    frames = cell.json("debug", "stack", "Main")["frames"]
    assert [(f["name"], f["instance"], f["line"]) for f in frames] == [
        ("Counter", "Main.a", 17),
        ("Main", "Main", 3),
    ]
    table = cell.ok("debug", "stack", "Main").splitlines()
    assert table[0].split() == ["#", "frame", "kind", "instance", "at"]
    assert table[1].split() == ["0", "Counter", "function", "block", "Main.a", "lib/counter.st:17"]

    # the other program runs on while Main stands in BKPT
    main = cell.program("Main")
    assert main["state"] == "BKPT" and main["paused_at"] == "lib/counter.st:17 (POU Counter)"
    before = cell.program("Other")["cycles"]
    until(lambda: cell.program("Other")["cycles"] > before + 5)
    assert cell.program("Main")["cycles"] == main["cycles"]


def test_step_into_a_method_through_an_interface_and_out(cell: Cell) -> None:
    cell.ok("debug", "set", "main.st:6")  # n := c.Bump(by := 3);
    stopped = cell.ok("debug", "wait", "--timeout", "60").strip()
    assert stopped.startswith("Main stopped at main.st:6 in Main, breakpoint "), stopped
    into = cell.ok("debug", "step", "Main", "--into").strip()
    assert into == "Main stopped at lib/counter.st:21 in Counter.BUMP (instance Main.a), step"
    assert variables(cell)["by"]["value"] == 3
    over = cell.ok("debug", "step", "Main").strip()
    assert over.startswith("Main stopped at lib/counter.st:22 in Counter.BUMP"), over
    out = cell.ok("debug", "step", "Main", "--out").strip()
    assert out == "Main stopped at main.st:7 in Main, step"
    cell.ok("debug", "continue", "Main")


def test_a_breakpoint_in_a_function_and_the_end_of_the_cycle(cell: Cell) -> None:
    cell.ok("debug", "set", "lib/counter.st:11", "--program", "Main")  # Twice := tmp;
    stopped = cell.json("debug", "wait", "--timeout", "60")
    where = stopped["paused"]
    assert (where["program"], where["file"], where["line"]) == ("Main", "lib/counter.st", 11)
    assert stopped["frames"] == cell.json("debug", "stack", "Main")["frames"]
    frames = stopped["frames"]
    assert [(f["kind"], f["name"]) for f in frames] == [
        ("function", "Twice"),
        ("function block", "Counter"),
        ("program", "Main"),
    ]
    local = variables(cell)
    assert local["tmp"]["value"] == 2 * local["x"]["value"] and local["tmp"]["path"] is None
    # frame 2 is Main's: its instances are expanded by path
    main = variables(cell, "--frame", "2")
    assert main["a"]["value"] is None and main["a"]["children"]
    members = variables(cell, "a", "--frame", "2")
    assert members["total"]["path"] == "Main.a.total"
    shown = cell.ok("debug", "vars", "Main", "--frame", "2").splitlines()
    assert shown[0].split() == ["name", "type", "value", "path"]
    assert any(line.split()[:3] == ["a", "Counter", "{...}"] for line in shown), shown
    end = cell.ok("debug", "step", "Main", "--cycle").strip()
    assert end == "Main stopped at the end of its program cycle"
    cell.ok("debug", "continue", "Main")


def test_writes_and_forcing_at_a_break(cell: Cell) -> None:
    cell.ok("debug", "set", "main.st:7")  # FOR i := 1 TO 3 DO
    cell.ok("debug", "wait", "--timeout", "60")
    assert cell.ok("write", "Main.n", "1000").strip() == "Main.n := 1000"
    assert variables(cell)["n"]["value"] == 1000
    cell.ok("force", "set", "Main.i", "40")
    cell.ok("force", "start", "--program", "Main")
    try:
        until(lambda: variables(cell)["i"]["value"] == 40)
    finally:
        cell.ok("force", "stop", "--program", "Main")
        cell.ok("force", "clear", "Main.i")
    cell.ok("debug", "clear")  # the program in BKPT continues
    until(lambda: cell.program("Main")["state"] == "RUN")


def test_a_logpoint_records_without_stopping(cell: Cell) -> None:
    logged = cell.ok("debug", "set", "main.st:8", "--log", "i", "n * 2").strip()
    assert logged.endswith("at main.st:8 logs i, n * 2"), logged

    def log_events() -> list[str]:
        shown = cell.ok("events", "--json", user="viewer").splitlines()
        found = [json.loads(line) for line in shown]
        return [e["message"] for e in found if e["kind"] == "log"]

    messages = until(log_events)
    assert messages[0].startswith("main.st:8 in Main: i = 1, n * 2 = "), messages
    assert cell.program("Main")["state"] == "RUN"


def test_files_named_from_elsewhere(cell: Cell) -> None:
    elsewhere = cell.project.parent  # no padt.toml here
    given = ["debug", "set", "lib/counter.st:11", "--program", "Other"]
    armed = cell.ok(*given, "--project", str(cell.project), cwd=elsewhere).strip()
    assert armed.endswith("at lib/counter.st:11 for Other"), armed  # Other calls no Twice
    # the name the project gives the file, from anywhere
    cleared = cell.ok("debug", "clear", "lib/counter.st", cwd=elsewhere).strip()
    assert cleared == "breakpoints of lib/counter.st cleared"
    assert cell.json("debug", "list")["breakpoints"] == []


def test_a_bad_file_line_or_condition_is_told(cell: Cell) -> None:
    wrong = cell.padt("debug", "set", "main.st")
    assert wrong.returncode == 2 and "'main.st' is not FILE:LINE" in wrong.stderr
    below = cell.padt("debug", "timeout", "2")
    assert below.returncode == 2 and "5 to 3600" in below.stderr
    nowhere = cell.padt("debug", "set", "main.st:500")
    assert nowhere.returncode == 1, nowhere.stderr
    assert "not armed: no statement at or after line 500 of main.st" in nowhere.stderr
    broken = cell.padt("debug", "set", "main.st:8", "--condition", "n >")
    assert broken.returncode == 1 and "'n >': more expected" in broken.stderr
    listed = cell.ok("debug", "list").splitlines()
    assert listed[0].split()[:3] == ["id", "at", "for"]
    assert any("not armed: no statement" in line for line in listed), listed
    gone = cell.padt("debug", "clear", "main.st:400")
    assert gone.returncode == 1 and "no breakpoint at main.st:400" in gone.stderr
    assert cell.ok("debug", "clear", "main.st").strip() == "breakpoints of main.st cleared"
    outside = cell.padt("debug", "set", "/etc/hostname:1")
    assert outside.returncode == 2 and "is not in the project" in outside.stderr
    standing = cell.padt("debug", "step", "Main")
    assert standing.returncode == 1 and "refused (state): program Main is not in BKPT" in (
        standing.stderr
    )


def test_refused_below_read_write(cell: Cell) -> None:
    refused = cell.padt("debug", "set", "main.st:3", user="op")
    assert refused.returncode == 1 and "refused (forbidden)" in refused.stderr
    assert cell.padt("debug", "clear", user="op").returncode == 1
    assert cell.padt("debug", "timeout", "60", user="viewer").returncode == 1
    # reading is for every level
    assert cell.json("debug", "list", user="viewer")["breakpoints"] == []


def test_a_silent_client_lets_the_program_continue(cell: Cell) -> None:
    assert "after 5 s" in cell.ok("debug", "timeout", "5")
    try:
        cell.ok("debug", "set", "main.st:3")
        cell.ok("debug", "wait", "--timeout", "60")
        # no debug command any more: only the status and the event log are read
        until(lambda: cell.program("Main")["state"] == "RUN")
        shown = cell.ok("events", "--json", user="viewer").splitlines()
        messages = [json.loads(line)["message"] for line in shown]
        assert "no debug command for 5 s: breakpoints cleared, the program continues" in messages
        assert cell.json("debug", "list", user="viewer")["breakpoints"] == []
    finally:
        cell.ok("debug", "timeout", "120")


def test_an_online_change_waits_and_a_stop_ends_the_break(cell: Cell, tmp_path: Path) -> None:
    changed = write_project(tmp_path / "changed")
    (changed / "main.st").write_text(MAIN_ST.replace("ticks + 1", "ticks + 2"))
    cell.ok("debug", "set", "main.st:3")
    cell.ok("debug", "wait", "--timeout", "60")
    backups = ["--backup-dir", str(tmp_path / "backups")]
    reload = cell.padt("reload", str(changed), "--yes", *backups)
    assert reload.returncode == 1, reload.stdout + reload.stderr
    assert "refused (state): program Main stands at a breakpoint" in reload.stderr
    # a stop: Main leaves BKPT for STOP; its breakpoint stays armed for the next start
    assert cell.ok("stop", "--program", "Main").strip() == "program Main: STOP"
    state = cell.json("debug", "list")
    assert state["paused"] is None and [b["line"] for b in state["breakpoints"]] == [3]
    cell.ok("start", "--program", "Main")
    stopped = cell.ok("debug", "wait", "--timeout", "60")
    assert stopped.startswith("Main stopped at main.st:3 in Main, breakpoint")


def test_refused_in_safety_operation(cell: Cell, tmp_path: Path) -> None:
    """Last: the cell is loaded with safety operation on."""
    safe = write_project(tmp_path / "safe", safety=True)
    cell.ok("stop")
    cell.ok("load", str(safe), "--backup-dir", str(tmp_path / "backups"))
    refused = cell.padt("debug", "set", "main.st:3")
    assert refused.returncode == 1 and "refused (safety_operation)" in refused.stderr
