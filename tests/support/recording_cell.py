"""A resource to record from, for the recording tests: a router, a real runtime process
that powers up running (cold start) a program whose values change every cycle in ways a
test can check, with PES accounts of each level."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

from backend.engineering.project import compile_project, load_project, user_entry
from backend.engineering.resource_client import ResourceClient
from runtime.contract.accounts import hash_password
from runtime.contract.artifact import UserAccount
from tests.support.runtime_process import running_resource, store_artifact

RESOURCE = "Cell"
PASSWORDS = {"viewer": "Look-1", "op": "Turn-2", "engineer": "Change-3", "admin": "Manage-4"}
LEVELS = {
    "viewer": "read",
    "op": "operator",
    "engineer": "read-write",
    "admin": "administrator",
}

PADT_TOML = """\
[project]
name = "Recording cell"

[resource]
name = "Cell"
target_cycle_ms = 20
safety_operation = false
autostart = "cold"

[[resource.program]]
name = "Main"
pou = "Main"
id = 1
"""

# `count` goes up by one every cycle, so a recording that lost or doubled a cycle shows
# it; `alarm` is TRUE one cycle in every 25 (a trigger fires twice a second)
MAIN_ST = """\
PROGRAM Main
VAR
  count : DINT := 0;
  level : REAL := 0.0;
  alarm : BOOL := FALSE;
  label : STRING[16] := 'cell';
  elapsed : TIME := T#0s;
END_VAR
count := count + 1;
level := DINT_TO_REAL(count MOD 100) / 2.0;
alarm := (count MOD 25) = 0;
elapsed := elapsed + T#20ms;
END_PROGRAM
"""


@dataclass
class Cell:
    project: Path
    state_dir: Path
    endpoint: str
    client: ResourceClient  # not logged in

    def logged_in(self, user: str) -> ResourceClient:
        client = ResourceClient(self.client.session, RESOURCE)
        client.login(user, PASSWORDS[user])
        return client


def write_project(folder: Path) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    accounts = "".join(
        "\n" + user_entry(UserAccount(name, LEVELS[name], hash_password(password)))
        for name, password in sorted(PASSWORDS.items())
    )
    (folder / "padt.toml").write_text(PADT_TOML + accounts)
    (folder / "main.st").write_text(MAIN_ST)
    return folder


@contextmanager
def recording_cell(base: Path, endpoint: str) -> Iterator[Cell]:
    project = write_project(base / "project")
    result = compile_project(load_project([project]))
    assert result.artifact is not None, result.diagnostics
    state_dir = base / "state"
    store_artifact(state_dir, result.artifact)
    with running_resource(RESOURCE, state_dir, endpoint) as (_, client):
        yield Cell(project, state_dir, endpoint, client)
