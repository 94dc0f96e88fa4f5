"""References in the online test as a person at a terminal sees them: `padt values` shows a
reference as the path it refers to or NULL, and `padt write` / `padt force` refuse one with a
message that says why. Real processes: a runtime over real Zenoh, `padt` as a user runs it."""

from __future__ import annotations

import json
import time
from pathlib import Path

import pytest

import tests.cli.test_online_commands as online
from tests.cli.test_online_commands import as_user

MAIN_ST = """\
PROGRAM Main
VAR counter : DINT; target : REF_TO DINT; spare : REF_TO DINT; END_VAR
counter := counter + 1;
target := REF(counter);
END_PROGRAM
"""


def test_values_show_references_and_writes_and_forcing_refuse_them(
    tmp_path: Path, zenoh_endpoint: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(online, "MAIN_ST", MAIN_ST)  # the cell of the online commands
    with online.loaded_cell(tmp_path, zenoh_endpoint):
        deadline = time.monotonic() + 20
        while True:  # until the program has run its first cycle
            shown = as_user("viewer", "values", zenoh_endpoint)
            assert shown.returncode == 0, shown.stderr
            rows = {line.split()[0]: line.split()[1:] for line in shown.stdout.splitlines()[1:]}
            if rows["Main.counter"] != ["DINT", "0"] or time.monotonic() > deadline:
                break
        assert rows["Main.target"] == ["REF_TO", "DINT", "Main.counter"]
        assert rows["Main.spare"] == ["REF_TO", "DINT", "NULL"]
        as_json = as_user("viewer", "values", zenoh_endpoint, "Main.target", "--json")
        assert json.loads(as_json.stdout)["values"] == {"Main.target": "Main.counter"}

        written = as_user("engineer", "write", zenoh_endpoint, "Main.spare", "NULL")
        assert written.returncode != 0
        assert "a reference (REF_TO DINT) is set by the program only" in written.stderr
        forced = as_user("engineer", "force", zenoh_endpoint, "set", "Main.target", "NULL")
        assert forced.returncode != 0
        assert "cannot be written or forced" in forced.stderr, forced.stderr
