"""A fleet on one router: three real runtime processes, `padt fleet status` (signed
statuses only, the host of each), `padt fleet load` and `padt fleet reload` (one project,
each resource its own compile, stopping at the first refusal), and `padt status` naming
the host."""

from __future__ import annotations

import json
import socket
import zipfile
from collections.abc import Iterator
from contextlib import ExitStack
from pathlib import Path
from typing import Any

import pytest

from backend.engineering.project import compile_project, for_resource, load_project, user_entry
from backend.engineering.resource_client import ResourceClient
from runtime.contract.accounts import hash_password
from runtime.contract.artifact import UserAccount
from tests.conftest import padt
from tests.support.runtime_process import (
    KNOWN_SETUP_SECRET,
    client_session,
    know_setup_secret,
    router,
    runtime_process,
    store_artifact,
    wait_until_answering,
)

FLEET = ("LineA", "LineB", "LineC")
PASSWORD = "Admin-1"

PADT_TOML = """\
[project]
name = "Fleet test"

[resource]
name = "Line1"
target_cycle_ms = 20
safety_operation = false

[[resource.program]]
name = "Main"
pou = "Main"
id = 1
"""

MAIN_ST = """\
PROGRAM Main
VAR
  counter : DINT := {start};
END_VAR
counter := counter + 1;
END_PROGRAM
"""


def write_project(folder: Path, start: int = 0) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    admin = user_entry(UserAccount("admin", "administrator", hash_password(PASSWORD)))
    (folder / "padt.toml").write_text(PADT_TOML + "\n" + admin)
    (folder / "main.st").write_text(MAIN_ST.format(start=start))
    return folder


@pytest.fixture
def fleet(tmp_path: Path, zenoh_endpoint: str) -> Iterator[dict[str, ResourceClient]]:
    """Three runtimes without a configuration on one router (a setup secret the test
    knows), and a client of each."""
    with ExitStack() as stack:
        stack.enter_context(router(zenoh_endpoint))
        for name in FLEET:
            state = tmp_path / "state" / name
            know_setup_secret(state)
            stack.enter_context(runtime_process(name, state, zenoh_endpoint, "--no-native-code"))
        session = stack.enter_context(client_session(zenoh_endpoint))
        clients = {name: ResourceClient(session, name) for name in FLEET}
        for client in clients.values():
            wait_until_answering(client)
        yield clients


def fleet_status(endpoint: str, *extra: str, env: dict[str, str] | None = None) -> Any:
    shown = padt("fleet", "status", "--zenoh", endpoint, "--json", *extra, env=env)
    return shown.returncode, json.loads(shown.stdout)


def by_name(entries: list[dict[str, Any]]) -> dict[str, dict[str, Any]]:
    return {entry["resource"]: entry for entry in entries}


def state(client: ResourceClient) -> dict[str, Any]:
    reply = client.command("status")
    assert reply["ok"], reply
    result: dict[str, Any] = reply["status"]
    return result


def test_fleet_status_and_load(
    fleet: dict[str, ResourceClient], tmp_path: Path, zenoh_endpoint: str
) -> None:
    host = socket.gethostname()
    # nobody logged in to them yet: online, their statuses not trusted
    code, entries = fleet_status(zenoh_endpoint)
    assert code == 1
    assert sorted(by_name(entries)) == list(FLEET)
    for entry in entries:
        assert entry["verified"] is False and entry["note"] == "not yet verified"
        assert entry["state"] is None and entry["host"] is None
    table = padt("fleet", "status", "--zenoh", zenoh_endpoint)
    assert table.returncode == 1
    assert table.stdout.splitlines()[0].split() == [
        "resource", "host", "state", "crc", "project", "target", "mean"
    ]  # fmt: skip
    assert (
        table.stdout.splitlines()[2].split() == ["LineB", "-", "not", "yet", "verified"] + ["-"] * 4
    )

    # one project into all three, each compiled for it: its own CRC, its own backup
    project = write_project(tmp_path / "project")
    backups = tmp_path / "backups"
    common = ["--zenoh", zenoh_endpoint, "--backup-dir", str(backups)]
    targets = [word for name in FLEET for word in ("--resource", name)]
    env = {"PADT_SETUP_SECRET": KNOWN_SETUP_SECRET}
    loaded = padt("fleet", "load", str(project), *targets, *common, env=env)
    assert loaded.returncode == 0, loaded.stderr
    lines = loaded.stdout.splitlines()
    assert [line.split(":")[0] for line in lines] == list(FLEET)
    assert all(": done, configuration CRC " in line for line in lines), lines
    for client in fleet.values():  # the accounts of the project now
        client.login("admin", PASSWORD)
    crcs = {name: state(client)["crc"] for name, client in fleet.items()}
    assert len(set(crcs.values())) == 3  # the name is part of the configuration
    for name, client in fleet.items():
        shown = state(client)
        assert (shown["resource"], shown["state"]) == (name, "STOP/VALID CONFIGURATION")
        assert shown["host"] == host
    manifests = []
    for archive in backups.glob("*.zip"):
        with zipfile.ZipFile(archive) as opened:
            manifests.append(json.loads(opened.read("MANIFEST.json")))
    assert sorted((m["resource"], m["crc"]["configuration"]) for m in manifests) == sorted(
        crcs.items()
    )

    # LineA runs: a changed project goes into LineB, LineA refuses, LineC is not tried
    admin = {"PADT_PASSWORD": PASSWORD}
    assert fleet["LineA"].command("start")["ok"]
    changed = write_project(tmp_path / "changed", start=100)
    order = ["--resource", "LineB", "--resource", "LineA", "--resource", "LineC"]
    again = padt(
        "fleet", "load", str(changed), *order, *common, "--user", "admin", "--json", env=admin
    )
    assert again.returncode == 1, again.stderr
    report = json.loads(again.stdout)
    assert report["done"] is False
    outcomes = [(r["resource"], r["outcome"], r["code"]) for r in report["resources"]]
    assert outcomes == [
        ("LineB", "done", None),
        ("LineA", "refused", "state"),
        ("LineC", "not tried", None),
    ]
    assert state(fleet["LineB"])["crc"] != crcs["LineB"]
    assert state(fleet["LineA"])["crc"] == crcs["LineA"]
    assert state(fleet["LineC"])["crc"] == crcs["LineC"]

    # an online change of LineA with the fleet's project: compiled for LineA, or refused
    reload = ["reload", str(changed), "--resource", "LineA", "--zenoh", zenoh_endpoint]
    reload += ["--backup-dir", str(backups), "--user", "admin", "--yes"]
    refused = padt(*reload, env=admin)
    assert refused.returncode == 1 and "(needs_download)" in refused.stderr
    assert "the resource identity changes (LineA -> Line1)" in refused.stderr
    reloaded = padt(*reload, "--compile-for-resource", env=admin)
    assert reloaded.returncode == 0, reloaded.stderr
    assert "source diff against backup Fleet_test_" + crcs["LineA"] in reloaded.stdout
    crcs["LineA"] = state(fleet["LineA"])["crc"]
    assert state(fleet["LineA"])["state"] == "RUN"

    # the keys are known now (the logins pinned them): signed statuses, with the host
    code, entries = fleet_status(zenoh_endpoint)
    shown = by_name(entries)
    assert code == 1  # LineB and LineC are in STOP
    assert shown["LineA"]["state"] == "RUN" and shown["LineA"]["host"] == host
    assert shown["LineB"]["state"] == "STOP/VALID CONFIGURATION"
    assert shown["LineA"]["verified"] and shown["LineA"]["crc"] == crcs["LineA"]
    assert shown["LineA"]["project"] == "Fleet test" and shown["LineA"]["cycle_ms"] == 20
    for name in ("LineB", "LineC"):
        assert fleet[name].command("start")["ok"]
    table = padt("fleet", "status", "--zenoh", zenoh_endpoint)
    assert table.returncode == 0, table.stdout + table.stderr
    rows = [line.split() for line in table.stdout.splitlines()[1:]]
    assert [row[:3] for row in rows] == [[name, host, "RUN"] for name in FLEET]

    # another account's known resources: not verified until --user logs in to each
    elsewhere = {"PADT_KNOWN_RESOURCES": str(tmp_path / "elsewhere")}
    code, entries = fleet_status(zenoh_endpoint, env=elsewhere)
    assert code == 1 and not any(entry["verified"] for entry in entries)
    code, entries = fleet_status(zenoh_endpoint, "--user", "admin", env={**elsewhere, **admin})
    assert code == 0 and all(entry["state"] == "RUN" for entry in entries)

    # a login refused: said, and still not verified
    stranger = {"PADT_KNOWN_RESOURCES": str(tmp_path / "stranger"), "PADT_PASSWORD": "wrong"}
    code, entries = fleet_status(zenoh_endpoint, "--user", "nobody", env=stranger)
    assert code == 1
    assert all(e["note"].startswith("not yet verified: login refused (") for e in entries)

    # `padt status` names the host and the runtime's Zenoh session
    single = padt(
        "status", "--resource", "LineA", "--zenoh", zenoh_endpoint, "--user", "admin", env=admin
    )
    assert single.returncode == 0, single.stderr
    assert single.stdout.splitlines()[1].startswith(f"host {host}, Zenoh session ")


def test_bad_fleet_options(tmp_path: Path, zenoh_endpoint: str) -> None:
    project = write_project(tmp_path / "project")
    twice = padt("fleet", "load", str(project), "--resource", "A", "--resource", "A")
    assert twice.returncode == 2 and "resource A is named twice" in twice.stderr
    missing = padt("fleet", "load", str(tmp_path / "nowhere"), "--resource", "A")
    assert missing.returncode == 2, missing.stderr
    assert padt("fleet", "status", "--wait", "0").returncode == 2
    with router(zenoh_endpoint):
        empty = padt("fleet", "status", "--zenoh", zenoh_endpoint)
    assert empty.returncode == 1 and "no resource is online" in empty.stderr


@pytest.fixture
def running_fleet(tmp_path: Path, zenoh_endpoint: str) -> Iterator[dict[str, ResourceClient]]:
    """The three runtimes in RUN from their stored configurations: the fleet's project
    compiled for each, LineB's with another safety time (not changed online); a client of
    each, logged in as admin."""
    project = write_project(tmp_path / "project")
    other = write_project(tmp_path / "other")
    toml = other / "padt.toml"
    toml.write_text(
        toml.read_text().replace("safety_operation", "safety_time_ms = 700\nsafety_operation")
    )
    with ExitStack() as stack:
        stack.enter_context(router(zenoh_endpoint))
        for name in FLEET:
            folder = other if name == "LineB" else project
            compiled = compile_project(for_resource(load_project([folder]), name))
            assert compiled.artifact is not None
            state_dir = tmp_path / "state" / name
            store_artifact(state_dir, compiled.artifact)
            stack.enter_context(
                runtime_process(name, state_dir, zenoh_endpoint, "--no-native-code")
            )
        session = stack.enter_context(client_session(zenoh_endpoint))
        clients = {name: ResourceClient(session, name) for name in FLEET}
        for client in clients.values():
            wait_until_answering(client)
            client.login("admin", PASSWORD)
            if state(client)["state"] != "RUN":
                assert client.command("start")["ok"]
        yield clients


def test_fleet_reload(
    running_fleet: dict[str, ResourceClient], tmp_path: Path, zenoh_endpoint: str
) -> None:
    """`padt fleet reload`: the plans previewed change nothing, nor do they without --yes;
    confirmed, LineA is changed online, LineB's plan needs a download (its safety time
    differs) and ends the run, LineC is not tried."""
    fleet = running_fleet
    crcs = {name: state(client)["crc"] for name, client in fleet.items()}
    backups = tmp_path / "backups"
    changed = write_project(tmp_path / "changed", start=100)
    targets = [word for name in FLEET for word in ("--resource", name)]
    command = ["fleet", "reload", str(changed), "--zenoh", zenoh_endpoint]
    command += ["--backup-dir", str(backups), "--user", "admin"]
    admin = {"PADT_PASSWORD": PASSWORD}

    # the plans only: each compiled for its resource, LineB's not possible
    preview = padt(*command, *targets, "--preview", "--json", env=admin)
    assert preview.returncode == 1, preview.stderr
    report = json.loads(preview.stdout)
    assert (report["done"], report["possible"]) == (False, False)
    plans = [(r["resource"], r["outcome"], r["possible"]) for r in report["resources"]]
    assert plans == [
        ("LineA", "previewed", True),
        ("LineB", "previewed", False),
        ("LineC", "previewed", True),
    ]
    assert report["resources"][0]["plan"]["old_crc"] == crcs["LineA"]
    assert "safety_time_ms changes from 700 to" in report["resources"][1]["why_not_online"][0]

    # without --yes: the plan, and nothing changed either
    unconfirmed = padt(*command, "--resource", "LineA", env=admin)
    assert unconfirmed.returncode == 1
    assert unconfirmed.stderr.strip().endswith("nothing changed; confirm with --yes")
    lines = unconfirmed.stdout.splitlines()
    assert lines[0].startswith(f"LineA: reload preview: configuration CRC {crcs['LineA']} -> ")
    assert "  summary: " in unconfirmed.stdout
    assert {name: state(client)["crc"] for name, client in fleet.items()} == crcs
    assert not backups.exists()

    # confirmed: LineA done, LineB refused (its plan), LineC not tried
    confirmed = padt(*command, *targets, "--yes", env=admin)
    assert confirmed.returncode == 1, confirmed.stderr
    outcomes = [line for line in confirmed.stdout.splitlines() if not line.startswith(" ")]
    assert outcomes[0].startswith("LineA: reload preview: ")
    assert outcomes[1].startswith(f"LineA: done, configuration CRC {crcs['LineA']} -> ")
    assert ", RUN, backup " in outcomes[1]
    assert outcomes[2].startswith("LineB: reload preview: ")
    assert outcomes[3].startswith("LineB: refused (needs_download): needs STOP and download: ")
    assert outcomes[4:] == ["LineC: not tried"]
    after = {name: state(client) for name, client in fleet.items()}
    assert after["LineA"]["crc"] != crcs["LineA"] and after["LineA"]["state"] == "RUN"
    assert (after["LineB"]["crc"], after["LineC"]["crc"]) == (crcs["LineB"], crcs["LineC"])
    (archive,) = backups.glob("*.zip")
    with zipfile.ZipFile(archive) as opened:
        manifest = json.loads(opened.read("MANIFEST.json"))
    assert manifest["resource"] == "LineA"
    assert manifest["crc"]["configuration"] == after["LineA"]["crc"]
    assert manifest["command"].startswith("padt fleet reload ")
