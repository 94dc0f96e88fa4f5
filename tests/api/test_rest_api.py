"""The REST API against a real runtime process over Zenoh, served on a real HTTP port:
PADT accounts and their levels, the resource's own levels behind them, every operation,
live values over a WebSocket, structured errors, and no password anywhere."""

from __future__ import annotations

import json
import logging
import os
import socket
import stat
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from websockets.sync.client import connect

from backend.engineering.event_chain import check_chain
from backend.engineering.padt_accounts import PadtAccounts, read_accounts
from backend.engineering.project import compile_project, load_project
from runtime.contract import protocol as p
from runtime.contract.accounts import LEVELS, SESSION_NS
from runtime.contract.protocol import COMMAND_LEVELS
from runtime.contract.refusal import Refusal
from tests.conftest import REPO, free_port, padt
from tests.support.rest_plant import (
    PADT_PASSWORDS,
    PES_LEVELS,
    PES_PASSWORDS,
    Plant,
    padt_accounts_file,
    plant,
    write_project,
)
from tests.support.runtime_process import router, runtime_process, store_artifact

R = "/api/resources/Plant"


@pytest.fixture(scope="module")
def site(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Plant]:
    with plant(tmp_path_factory.mktemp("rest")) as found:
        yield found


def state(site: Plant, token: str) -> str:
    reply = site.call("GET", f"{R}/status", token)
    assert reply.status_code == 200, reply.text
    return str(reply.json()["state"])


def error(reply: Any, status: int, code: str) -> str:
    """The message of a structured error reply with this status and code."""
    assert reply.status_code == status, reply.text
    body = reply.json()
    assert set(body) == {"error"} and body["error"]["code"] == code, body
    message: str = body["error"]["message"]
    assert "Traceback" not in message
    return message


# (method, path, body, PES level it needs); every one needs Read+Write on the PADT side
RESOURCE_ROUTES: list[tuple[str, str, dict[str, Any] | None, str]] = [
    ("POST", f"{R}/start", None, "operator"),
    ("POST", f"{R}/stop", None, "operator"),
    ("POST", f"{R}/statistics/reset", None, "operator"),
    ("POST", f"{R}/programs/P/start", None, "operator"),
    ("POST", f"{R}/programs/P/stop", None, "operator"),
    ("POST", f"{R}/forcing/start", {}, "operator"),
    ("POST", f"{R}/forcing/stop", {}, "operator"),
    ("PUT", f"{R}/forces/P.n", {"value": 5}, "operator"),
    ("DELETE", f"{R}/forces/P.n", None, "operator"),
    ("POST", f"{R}/recordings", {"variables": ["P.n"], "cycles": 5}, "operator"),
    ("POST", f"{R}/recordings/r1/stop", None, "operator"),
    ("DELETE", f"{R}/recordings/r1", None, "operator"),
    ("POST", f"{R}/init", None, "read-write"),
    ("POST", f"{R}/cold-start", None, "read-write"),
    ("POST", f"{R}/step", None, "read-write"),
    ("POST", f"{R}/programs/P/freeze", None, "read-write"),
    ("POST", f"{R}/programs/P/unfreeze", None, "read-write"),
    ("POST", f"{R}/programs/P/step", None, "read-write"),
    ("PUT", f"{R}/values/P.n", {"value": 1}, "read-write"),
    ("PUT", f"{R}/parameters/watchdog_ms", {"value": 150}, "read-write"),
    ("PUT", f"{R}/parameters/allow_online_settings", {"value": True}, "administrator"),
    ("POST", f"{R}/load", {"project": "plant"}, "read-write"),
    ("POST", f"{R}/reload/preview", {"project": "plant_v2"}, "read-write"),
    ("POST", f"{R}/reload", {"project": "plant_v2", "expected_crc": "00000000"}, "read-write"),
]
SECURITY = "security-administrator"
PADT_ONLY_ROUTES: list[tuple[str, str, dict[str, Any] | None, str]] = [
    ("POST", "/api/projects/plant/compile", None, "read-write"),
    ("POST", "/api/projects/plant/check-twice", None, "read-write"),
    ("GET", "/api/accounts", None, SECURITY),
    ("PUT", "/api/accounts/intruder", {"level": SECURITY, "password": "Pw-1"}, SECURITY),
    ("DELETE", "/api/accounts/keeper", None, SECURITY),
]
BELOW = {"operator": "viewer", "read-write": "op", "administrator": "engineer"}


def test_no_token_a_forged_one_or_a_wrong_password_is_refused(site: Plant) -> None:
    error(site.call("GET", "/api/resources"), 401, "unauthenticated")
    error(site.call("GET", "/api/resources", "forged-" + "x" * 40), 401, "unauthenticated")
    wrong = site.http.post(f"{site.url}/api/login", json={"user": "builder", "password": "No-0"})
    assert "unknown user or wrong password" in error(wrong, 401, "login_failed")
    unknown = site.http.post(f"{site.url}/api/login", json={"user": "nobody", "password": "No-0"})
    assert error(unknown, 401, "login_failed") == "unknown user or wrong password"
    token = site.token("reader")
    assert site.call("GET", "/api/session", token).json()["level"] == "read-only"
    assert site.call("POST", "/api/logout", token).status_code == 204
    error(site.call("GET", "/api/session", token), 401, "unauthenticated")


def test_a_session_expires_and_an_account_change_ends_it(tmp_path: Path) -> None:
    now = [0]
    accounts = PadtAccounts(padt_accounts_file(tmp_path / "a.json"), lambda: now[0])
    token, _ = accounts.login("builder", PADT_PASSWORDS["builder"], "127.0.0.1")
    assert accounts.check(token, "read-write").user == "builder"
    now[0] += SESSION_NS
    with pytest.raises(Refusal, match="expired"):
        accounts.check(token, "read-only")
    token, _ = accounts.login("builder", PADT_PASSWORDS["builder"], "127.0.0.1")
    accounts.put("builder", "read-only", None)  # lowered: its sessions end
    with pytest.raises(Refusal, match="log in first"):
        accounts.check(token, "read-only")


def test_every_state_changing_route_is_refused_below_its_padt_level(site: Plant) -> None:
    reader = site.session("reader", "admin")  # the resource would allow it; the PADT not
    builder = site.session("builder", "admin")
    before = state(site, reader)
    for method, path, body, _ in RESOURCE_ROUTES + PADT_ONLY_ROUTES:
        message = error(site.call(method, path, reader, json=body), 403, "forbidden")
        assert "reader (read-only)" in message, (path, message)
    for method, path, body, needed in PADT_ONLY_ROUTES:
        if needed == "security-administrator":
            message = error(site.call(method, path, builder, json=body), 403, "forbidden")
            assert "builder (read-write)" in message
    assert state(site, reader) == before
    assert sorted(a.name for a in read_accounts(site.accounts_file)) == sorted(PADT_PASSWORDS)


def test_every_state_changing_route_is_refused_by_the_resource_below_its_pes_level(
    site: Plant,
) -> None:
    viewer = site.session("builder", "viewer")
    before = site.call("GET", f"{R}/status", viewer).json()
    last = site.call("GET", f"{R}/events", viewer, params={"limit": 1000}).json()[-1]["seq"]
    tokens = {pes: site.session("builder", pes) for pes in ("viewer", "op", "engineer")}
    for method, path, body, needed in RESOURCE_ROUTES:
        below = BELOW[needed]
        reply = site.call(method, path, tokens[below], json=body)
        message = error(reply, 403, "forbidden")
        assert f"{below} ({PES_LEVELS[below]})" in message and needed in message, path
    after = site.call("GET", f"{R}/status", viewer).json()
    assert (after["state"], after["crc"]) == (before["state"], before["crc"])
    assert after["cycle"] > before["cycle"]  # it kept running all along
    events = site.call("GET", f"{R}/events", viewer, params={"after": last}).json()
    # nothing else happened; the native tier's report comes when its build ends, which
    # under load may be during the requests
    assert {e["kind"] for e in events} - {"native"} == {"login"}


def test_the_long_term_log_comes_with_its_chain_which_a_client_can_check(site: Plant) -> None:
    viewer = site.session("builder", "viewer")
    entries = site.call("GET", f"{R}/events", viewer, params={"log": "long", "limit": 1000}).json()
    assert any(e["kind"] == "login" and e["user"] == "viewer" for e in entries)
    names = ("seq", "time_ns", "kind", "message", "user", "details")
    events = [p.Event(*(e[name] for name in names)) for e in entries]
    chain = check_chain(events, [e["prev"] for e in entries])
    assert chain.ok and chain.entries == len(entries), chain.describe()
    short = site.call("GET", f"{R}/events", viewer, params={"limit": 1000}).json()
    assert "prev" not in short[-1]
    refused = site.call("GET", f"{R}/events", viewer, params={"log": "all"})
    assert "log" in error(refused, 400, "bad_request")


WELL_FORMED: dict[str, dict[str, Any]] = {
    "watch": {"id": "w1", "variables": ["P.n"]},
    "unwatch": {"id": "w1"},
    **{
        name: {"program": "P"}
        for name in ("start_program", "stop_program", "freeze", "unfreeze", "step_program")
    },
    "force": {"variable": "P.n", "value": 1},
    "unforce": {"variable": "P.n"},
    "write": {"variable": "P.n", "value": 1},
    "set_parameter": {"name": "watchdog_ms", "value": 100},
    "transfer_begin": {"size": 10, "crc": "0000ABCD"},
    "transfer_chunk": {"offset": 0, "data": "x"},
    "record_start": {"variables": ["P.n"]},
    "record_stop": {"id": "r1"},
    "record_read": {"file": "r1-1.mcap"},
    "record_delete": {"id": "r1"},
    "debug_set": {"file": "p.st", "breakpoints": [{"line": 3}]},
    **{name: {"program": "P"} for name in ("debug_continue", "debug_step", "debug_stack")},
    "debug_variables": {"program": "P"},
    "debug_run_to": {"program": "P", "file": "p.st", "line": 3},
    "debug_options": {"silent_s": 60},
}


def test_the_same_commands_sent_directly_over_zenoh_get_the_same_refusals(site: Plant) -> None:
    """A client that bypasses the PADT meets the resource's own check."""
    client = site.zenoh_client
    logins = {
        name: client.login(name, PES_PASSWORDS[name]) for name in ("viewer", "op", "engineer")
    }
    client.logged_in = None
    refused = []
    for command, needed in sorted(COMMAND_LEVELS.items()):
        # well-formed requests: a malformed one is refused by the decoder before the
        # access check sees it
        arguments = WELL_FORMED.get(command, {})
        assert client.command(command, **arguments)["error"]["code"] == "unauthenticated", command
        if needed == "read":
            continue
        below = LEVELS[LEVELS.index(needed) - 1]
        name = next(n for n, level in PES_LEVELS.items() if level == below)
        client.logged_in = logins[name]
        reply = client.command(command, **arguments)
        client.logged_in = None
        assert reply["error"]["code"] == "forbidden", (command, reply)
        refused.append(command)
    admin_only: dict[str, Any] = {"name": "allow_online_settings", "value": True}
    client.logged_in = logins["engineer"]
    assert client.command("set_parameter", **admin_only)["error"]["code"] == "forbidden"
    client.logged_in = None
    assert len(refused) >= 20


def test_operate_a_resource_through_the_api(site: Plant) -> None:
    op = site.session("builder", "op")
    engineer = site.session("builder", "engineer")
    assert error(
        site.call("GET", f"{R}/status", site.token("builder")), 401, "resource_login_required"
    )
    assert site.call("POST", f"{R}/stop", op).json()["status"]["state"].startswith("STOP")
    assert site.call("POST", f"{R}/start", op).json()["status"]["state"] == "RUN"
    programs = site.call("GET", f"{R}/programs", op).json()
    assert [(p["name"], p["state"]) for p in programs] == [("P", "RUN")]
    # single step: frozen, one program cycle per step
    site.call("POST", f"{R}/programs/P/freeze", engineer).raise_for_status()
    before = site.call("GET", f"{R}/values", engineer).json()["values"]["P.n"]
    site.call("POST", f"{R}/programs/P/step", engineer).raise_for_status()
    after = site.call("GET", f"{R}/values", engineer).json()["values"]["P.n"]
    assert after == before + 1
    site.call("POST", f"{R}/programs/P/unfreeze", engineer).raise_for_status()
    # a write, and forcing with its switch
    site.call("PUT", f"{R}/values/P.limit", engineer, json={"value": 50}).raise_for_status()
    site.call("PUT", f"{R}/forces/P.flag", op, json={"value": True}).raise_for_status()
    site.call("POST", f"{R}/forcing/start", op, json={"program": "P"}).raise_for_status()
    forcing = site.call("GET", f"{R}/forcing", op).json()
    assert "P.flag" in json.dumps(forcing)
    site.call("POST", f"{R}/forcing/stop", op, json={"program": "P"}).raise_for_status()
    site.call("DELETE", f"{R}/forces/P.flag", op).raise_for_status()
    # parameters and statistics
    params = site.call("PUT", f"{R}/parameters/watchdog_ms", engineer, json={"value": 150})
    assert params.status_code == 200, params.text
    assert site.call("GET", f"{R}/parameters", op).json()["resource"]["watchdog_ms"] == 150
    bad = site.call("PUT", f"{R}/parameters/watchdog_ms", engineer, json={"value": 1})
    assert "watchdog_ms" in error(bad, 400, "bad_value")
    stats = site.call("GET", f"{R}/statistics", op).json()
    assert stats["cycle"] > 0 and stats["programs"]["P"]["cycles"] > 0
    assert site.call("POST", f"{R}/statistics/reset", op).status_code == 200
    # refusals of the resource's state keep their code, with 409
    assert "STOP" in error(site.call("POST", f"{R}/step", engineer), 409, "state")
    events = site.call("GET", f"{R}/events", op, params={"limit": 1000}).json()
    kinds = {e["kind"] for e in events}
    assert {"write", "force", "parameter"} <= kinds
    assert any(e.get("user") == "engineer" for e in events if e["kind"] == "write")


def test_compile_check_twice_load_preview_and_reload(site: Plant, tmp_path: Path) -> None:
    builder = site.session("builder", "engineer")
    compiled = site.call("POST", "/api/projects/plant_v2/compile", builder).json()
    assert compiled["ok"] and len(compiled["crc"]["configuration"]) == 8
    twice = site.call("POST", "/api/projects/plant/check-twice", builder).json()
    assert twice["ok"] and twice["mismatches"] == []
    first = twice["runs"][0]["configuration"]
    # a load needs STOP: its preview says so, in words, and the load is refused
    plan = site.call("POST", f"{R}/load/preview", builder, json={"project": "plant"}).json()
    assert not plan["possible"] and "needs it in STOP" in plan["refusals"][0], plan
    assert plan["new_crc"] == first and plan["check_crcs"] == [first, first]
    refused = site.call("POST", f"{R}/load", builder, json={"project": "plant"})
    assert "STOP" in error(refused, 409, "state")
    site.call("POST", f"{R}/stop", builder).raise_for_status()
    plan = site.call("POST", f"{R}/load/preview", builder, json={"project": "plant"}).json()
    assert plan["possible"] and plan["refusals"] == [], plan
    assert any("initial value" in effect for effect in plan["effects"])
    loaded = site.call("POST", f"{R}/load", builder, json={"project": "plant"})
    assert loaded.status_code == 200, loaded.text
    assert loaded.json()["status"]["crc"] == first
    assert (site.backups / loaded.json()["backup"]).is_file()
    site.call("POST", f"{R}/start", builder).raise_for_status()
    # the preview names what the reload would do; the reload needs the CRC it was made for
    preview = site.call("POST", f"{R}/reload/preview", builder, json={"project": "plant_v2"})
    assert preview.status_code == 200, preview.text
    plan = preview.json()["plan"]
    assert plan["old_crc"] == first
    added = [c for c in plan["changes"] if c["action"] == "new"]
    assert [c["path"] for c in added] == ["P.m"]
    # with what changed in the sources since the loaded configuration (its backup)
    shown = preview.json()
    assert shown["why_not_online"] == [] and shown["parameter_resets"] == []
    assert shown["running_sources"].startswith("backup Plant_")
    changed = [line for diff in shown["source_diff"] for line in diff["lines"]]
    assert any(line.startswith("+") and "m" in line for line in changed), shown["source_diff"]
    stale = {"project": "plant_v2", "expected_crc": "0BADC0DE"}
    assert error(site.call("POST", f"{R}/reload", builder, json=stale), 409, "changed")
    confirmed = {"project": "plant_v2", "expected_crc": plan["old_crc"]}
    done = site.call("POST", f"{R}/reload", builder, json=confirmed)
    assert done.status_code == 200, done.text
    assert done.json()["reload"]["new_crc"] == plan["new_crc"]
    values = site.call("GET", f"{R}/values", builder).json()["values"]
    assert values["P.m"] == 7 and values["P.n"] > 0  # n carried over, m new
    # a project that does not compile: the diagnostics with file:line:col
    broken = site.projects / "plant"
    (broken / "plant.st").write_text("PROGRAM P\nVAR n : DINT; END_VAR\nn := ;\nEND_PROGRAM\n")
    report = site.call("POST", "/api/projects/plant/compile", builder).json()
    errors = [d for d in report["diagnostics"] if d["severity"] == "error"]
    assert not report["ok"], report
    assert ("plant.st", 3, 6) in [(e["file"], e["line"], e["col"]) for e in errors], report
    refused = site.call("POST", f"{R}/reload/preview", builder, json={"project": "plant"})
    message = error(refused, 422, "compile")
    assert "does not compile" in message and refused.json()["error"]["diagnostics"]


def test_live_values_arrive_over_a_websocket_with_their_quality(site: Plant) -> None:
    token = site.session("builder", "op")
    ws_url = site.url.replace("http://", "ws://") + f"{R}/live"
    site.call("PUT", f"{R}/forces/P.flag", token, json={"value": False}).raise_for_status()
    site.call("POST", f"{R}/forcing/start", token, json={"program": "P"}).raise_for_status()
    try:
        with connect(ws_url) as ws:
            ws.send(json.dumps({"token": token, "variables": ["p.n", "P.flag"], "period_ms": 50}))
            assert json.loads(ws.recv(timeout=10)) == {"variables": ["P.n", "P.flag"]}
            messages = [json.loads(ws.recv(timeout=10)) for _ in range(5)]
            cycles = [m["cycle"] for m in messages]
            assert cycles == sorted(cycles) and len(set(cycles)) == 5
            forced = {"value": False, "literal": "FALSE", "quality": "forced"}
            assert messages[-1]["values"]["P.flag"] == forced
            assert messages[-1]["values"]["P.n"]["quality"] == "live"
            watches = site.zenoh_client.command("watches", token=None)
            assert watches.get("error", {}).get("code") == "unauthenticated"
        # the set ends with the WebSocket (the runtime is told by liveliness)
        viewer = site.zenoh_client
        viewer.login("viewer", PES_PASSWORDS["viewer"])
        deadline = time.monotonic() + 10
        while viewer.command("watches")["watches"] and time.monotonic() < deadline:
            time.sleep(0.05)
        assert viewer.command("watches")["watches"] == []
        viewer.logged_in = None
    finally:
        site.call("POST", f"{R}/forcing/stop", token, json={"program": "P"}).raise_for_status()
        site.call("DELETE", f"{R}/forces/P.flag", token)
    with connect(ws_url) as ws:
        ws.send(json.dumps({"token": "forged", "variables": ["P.n"]}))
        assert json.loads(ws.recv(timeout=10))["error"]["code"] == "unauthenticated"
    with connect(ws_url) as ws:
        ws.send(json.dumps({"token": token, "variables": ["P.nothing"]}))
        assert json.loads(ws.recv(timeout=10))["error"]["code"] == "watch_refused"


def test_errors_are_json_with_a_code_never_a_traceback(site: Plant) -> None:
    token = site.session("builder", "engineer")
    error(site.call("GET", "/api/nothing", token), 404, "not_found")
    error(site.call("DELETE", "/api/login", token), 405, "method_not_allowed")
    error(site.call("GET", "/api/resources/Elsewhere/status", token), 404, "unknown_resource")
    unknown = site.call("POST", f"{R}/load", token, json={"project": "none"})
    error(unknown, 404, "unknown_project")
    upward = site.call("POST", "/api/projects/..%2F..%2Fetc/compile", token)
    assert upward.status_code == 404 and "etc" in upward.json()["error"]["message"]
    bad = site.call("POST", f"{R}/reload", token, content=b"{not json")
    error(bad, 400, "bad_request")
    missing = site.call("POST", f"{R}/reload", token, json={"project": "plant_v2"})
    assert "expected_crc" in error(missing, 400, "bad_request")
    one = {"value": 1}
    error(site.call("PUT", f"{R}/values/P.nothing", token, json=one), 404, "unknown_variable")
    error(site.call("POST", f"{R}/programs/Q/start", token), 404, "unknown_program")
    error(site.call("PUT", f"{R}/parameters/colour", token, json=one), 404, "unknown_parameter")
    huge = site.call("PUT", f"{R}/values/P.n", token, json={"value": 10**40})
    error(huge, 400, "bad_value")
    oversized = {"value": "x" * (2 * 1024 * 1024)}
    too_large = site.call("PUT", f"{R}/values/P.n", token, json=oversized)
    assert "body larger" in error(too_large, 413, "too_large")

    def chunks() -> Iterator[bytes]:
        yield b'{"value": "'
        for _ in range(40):
            yield b"x" * 65536
        yield b'"}'

    chunked = site.call("PUT", f"{R}/values/P.n", token, content=chunks())
    assert "body larger" in error(chunked, 413, "too_large")
    openapi = site.http.get(f"{site.url}/openapi.json").json()
    assert f"{R.replace('Plant', '{resource}')}/reload/preview" in openapi["paths"]
    assert site.http.get(f"{site.url}/docs").status_code == 200


def test_the_security_administrator_manages_the_padt_accounts(site: Plant) -> None:
    keeper = site.token("keeper")
    new = {"level": "read-only", "password": "Fresh-8"}
    assert site.call("PUT", "/api/accounts/visitor", keeper, json=new).status_code == 200
    listed = site.call("GET", "/api/accounts", keeper).json()
    assert {"name": "visitor", "level": "read-only"} in listed
    assert "password" not in json.dumps(listed) and "scrypt" not in json.dumps(listed)
    login = site.http.post(f"{site.url}/api/login", json={"user": "visitor", "password": "Fresh-8"})
    assert login.status_code == 200
    assert site.call("DELETE", "/api/accounts/visitor", keeper).status_code == 204
    again = site.http.post(f"{site.url}/api/login", json={"user": "visitor", "password": "Fresh-8"})
    error(again, 401, "login_failed")
    last = site.call("DELETE", "/api/accounts/keeper", keeper)
    assert "security-administrator" in error(last, 422, "accounts")
    weak = {"level": "read-only", "password": "a b"}
    weak_reply = site.call("PUT", "/api/accounts/x", keeper, json=weak)
    error(weak_reply, 422, "accounts")
    assert stat.S_IMODE(site.accounts_file.stat().st_mode) == 0o600


def test_no_password_in_any_file_or_log(
    site: Plant, caplog: pytest.LogCaptureFixture, tmp_path: Path
) -> None:
    caplog.set_level(logging.DEBUG)
    site.session("builder", "op")
    site.http.post(f"{site.url}/api/login", json={"user": "builder", "password": "Wrong-9"})
    everything = [PADT_PASSWORDS, PES_PASSWORDS]
    files = [p for p in (site.state_dir.parent).rglob("*") if p.is_file()]
    texts = [p.read_bytes().decode(errors="replace") for p in files]
    texts.append(caplog.text)
    for passwords in everything:
        for password in passwords.values():
            assert not any(password in text for text in texts), password
    assert "Wrong-9" not in caplog.text and "builder" in caplog.text


def test_padt_api_needs_an_account_and_padt_api_user_makes_one(tmp_path: Path) -> None:
    accounts = tmp_path / "accounts.json"
    port = free_port()
    options = ["--accounts", str(accounts), "--port", str(port)]
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    options += ["--zenoh", endpoint]
    refused = padt("api", *options)
    assert refused.returncode == 2 and "padt api-user" in refused.stderr
    made = padt("api-user", "chief", "--level", "security-administrator", "--accounts",
                str(accounts), env={"PADT_PASSWORD": "Chief-1"})  # fmt: skip
    assert made.returncode == 0, made.stderr
    assert "Chief-1" not in accounts.read_text()
    assert stat.S_IMODE(accounts.stat().st_mode) == 0o600
    last = padt("api-user", "chief", "--delete", "--accounts", str(accounts))
    assert last.returncode == 2 and "security-administrator" in last.stderr
    command = [sys.executable, "-m", "padt.cli", "api", *options]
    with (
        router(endpoint),
        subprocess.Popen(
            command, cwd=REPO, stdout=subprocess.PIPE, text=True, env=dict(os.environ)
        ) as process,
    ):
        try:
            assert process.stdout is not None
            line = process.stdout.readline()
            assert f"http://127.0.0.1:{port}" in line and "/docs" in line
            import httpx

            reply = httpx.post(
                f"http://127.0.0.1:{port}/api/login", json={"user": "chief", "password": "Chief-1"}
            )
            assert reply.status_code == 200 and reply.json()["level"] == "security-administrator"
        finally:
            process.terminate()
            assert process.wait(timeout=15) == 0


def test_two_resources_on_one_router_and_a_killed_one_leaves_the_list(tmp_path: Path) -> None:
    second = write_project(tmp_path / "line2", resource="Line2")
    artifact = compile_project(load_project([second])).artifact
    assert artifact is not None
    store_artifact(tmp_path / "line2-state", artifact)
    with (
        plant(tmp_path / "plant") as site,
        runtime_process("Line2", tmp_path / "line2-state", site.endpoint),
    ):
        token = site.session("builder", "viewer")
        deadline = time.monotonic() + 20
        listed: list[str] = []
        while listed != ["Line2", "Plant"] and time.monotonic() < deadline:
            listed = [e["resource"] for e in site.call("GET", "/api/resources", token).json()]
        assert listed == ["Line2", "Plant"]
        line2 = {"user": "op", "password": PES_PASSWORDS["op"]}
        assert site.call("POST", "/api/resources/Line2/login", token, json=line2).status_code == 200
        status = site.call("GET", "/api/resources/Line2/status", token).json()
        assert (status["resource"], status["state"]) == ("Line2", "RUN")
        # the list names the host each runs on, once its status is verified
        deadline = time.monotonic() + 20
        hosts: dict[str, Any] = {}
        while None in (hosts.get("Line2"), hosts.get("Plant")) and time.monotonic() < deadline:
            listed_now = site.call("GET", "/api/resources", token).json()
            hosts = {e["resource"]: e["host"] for e in listed_now}
        assert hosts == {"Line2": socket.gethostname(), "Plant": socket.gethostname()}

        # a fleet load: Line2 (stopped) takes plant_v2 compiled for it, Plant refuses (it
        # runs), Ghost is not tried
        engineer = site.session("builder", "engineer")
        body = {"user": "engineer", "password": PES_PASSWORDS["engineer"]}
        assert (
            site.call("POST", "/api/resources/Line2/login", engineer, json=body).status_code == 200
        )
        assert site.call("POST", "/api/resources/Line2/stop", engineer).status_code == 200
        fleet = {"project": "plant_v2", "resources": ["Line2", "Plant", "Ghost"]}
        reply = site.call("POST", "/api/resources/load", engineer, json=fleet)
        assert reply.status_code == 200, reply.text
        report = reply.json()
        assert report["done"] is False
        outcomes = [(r["resource"], r["outcome"], r["code"]) for r in report["resources"]]
        assert outcomes == [
            ("Line2", "done", None),
            ("Plant", "refused", "state"),
            ("Ghost", "not tried", None),
        ]
        line2_crc = report["resources"][0]["crc"]
        status = site.call("GET", "/api/resources/Line2/status", engineer).json()
        assert (status["crc"], status["state"]) == (line2_crc, "STOP/VALID CONFIGURATION")
        assert report["resources"][0]["backup"].startswith("Plant_" + line2_crc)
        # only a reader of the PADT: refused before anything; a bad list: 400, no traceback
        reader = site.session("reader")
        assert site.call("POST", "/api/resources/load", reader, json=fleet).status_code == 403
        twice = {"project": "plant_v2", "resources": ["Line2", "Line2"]}
        error(site.call("POST", "/api/resources/load", engineer, json=twice), 400, "bad_request")
        none = {"project": "plant_v2", "resources": []}
        error(site.call("POST", "/api/resources/load", engineer, json=none), 400, "bad_request")

        # a fleet reload: the plans first (nothing changes), then each provided it still
        # runs the configuration of the plan confirmed; a stale one ends it
        plants = {"project": "plant_v2", "resources": ["Plant", "Ghost"]}
        reply = site.call("POST", "/api/resources/reload/preview", engineer, json=plants)
        assert reply.status_code == 200, reply.text
        previews = reply.json()["resources"]
        assert [(r["outcome"], r["possible"]) for r in previews] == [
            ("previewed", True),
            ("refused", False),
        ]
        plant_crc = previews[0]["plan"]["old_crc"]
        for path in ("/api/resources/reload/preview", "/api/resources/reload"):
            error(site.call("POST", path, reader, json=plants), 403, "forbidden")
        assert site.call("GET", f"{R}/status", engineer).json()["crc"] == plant_crc
        stale = {**plants, "expected_crcs": {"Plant": "0BADC0DE", "Ghost": "00000000"}}
        report = site.call("POST", "/api/resources/reload", engineer, json=stale).json()
        assert [(r["outcome"], r["code"]) for r in report["resources"]] == [
            ("refused", "changed"),
            ("not tried", None),
        ]
        missing = {**plants, "expected_crcs": {"Plant": plant_crc}}
        error(
            site.call("POST", "/api/resources/reload", engineer, json=missing), 400, "bad_request"
        )
        confirmed = {**plants, "resources": ["Plant"], "expected_crcs": {"Plant": plant_crc}}
        report = site.call("POST", "/api/resources/reload", engineer, json=confirmed).json()
        assert report["done"] is True, report
        (done,) = report["resources"]
        assert (done["outcome"], done["old_crc"], done["state"]) == ("done", plant_crc, "RUN")
        assert site.call("GET", f"{R}/status", engineer).json()["crc"] == done["new_crc"]
        assert done["backup"].startswith("Plant_" + done["new_crc"])
        ws_url = site.url.replace("http://", "ws://") + f"{R}/live"
        with connect(ws_url) as ws:
            ws.send(json.dumps({"token": token, "variables": ["P.n"], "period_ms": 50}))
            assert json.loads(ws.recv(timeout=10)) == {"variables": ["P.n"]}
            assert "P.n" in json.loads(ws.recv(timeout=10))["values"]
            site.runtime.kill()
            deadline = time.monotonic() + 20
            message: dict[str, Any] = {}
            while "error" not in message and time.monotonic() < deadline:
                message = json.loads(ws.recv(timeout=20))
            assert message["error"]["code"] == "unreachable"
        listed = [e["resource"] for e in site.call("GET", "/api/resources", token).json()]
        assert listed == ["Line2"]
        error(site.call("GET", f"{R}/status", token), 404, "unknown_resource")


def test_building_the_command_line_loads_neither_the_api_server_nor_zenoh() -> None:
    """Every padt command (the runtime's start, each check-twice compile) pays for what
    its parser imports: FastAPI alone took 0.6 s."""
    probe = (
        "import sys; from padt.cli import build_parser; build_parser(); "
        "print(sorted(m for m in ('fastapi', 'uvicorn', 'zenoh') if m in sys.modules))"
    )
    loaded = subprocess.run(
        [sys.executable, "-c", probe], cwd=REPO, capture_output=True, text=True, check=True
    )
    assert loaded.stdout.strip() == "[]"
