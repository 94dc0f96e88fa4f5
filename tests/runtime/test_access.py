"""Access control enforced by the runtime itself (spec section 13): accounts from the
configuration, login to a session token, the level each command needs, expiry, forged
tokens, locking after failed logins, and no password anywhere but as a salted hash."""

from __future__ import annotations

import base64
import hashlib
import json
import os
import signal
import subprocess
import sys
from pathlib import Path
from typing import Any

import httpx

from backend.compiler.pipeline import compile_sources
from backend.compiler.source import SourceFile
from backend.engineering.resource_client import ResourceClient
from runtime.commands import execute
from runtime.contract import scram
from runtime.contract.accounts import SESSION_NS, hash_password, verify_password
from runtime.contract.artifact import ResourceConfig, UserAccount
from runtime.contract.keyspace import command_key
from runtime.contract.session import open_client
from tests.conftest import REPO, free_port, padt
from tests.support.resource_harness import Harness, compiled, harness
from tests.support.runtime_process import running_resource, store_artifact, wait_until_answering

TEXT = "PROGRAM P VAR n : INT; END_VAR n := n + 1; END_PROGRAM"
PASSWORDS = {"viewer": "Look-1", "op": "Turn-2", "engineer": "Change-3", "admin": "Manage-4"}
LEVELS = {"viewer": "read", "op": "operator", "engineer": "read-write", "admin": "administrator"}


def users() -> list[UserAccount]:
    return [UserAccount(n, LEVELS[n], hash_password(PASSWORDS[n])) for n in sorted(PASSWORDS)]


def login(h: Harness, name: str) -> str:
    return h.login(name, PASSWORDS[name])


def test_every_command_needs_a_session_of_the_right_level() -> None:
    h = harness(TEXT, users=users())
    assert h.refused("status") == "unauthenticated"
    assert h.refused("stop", token="forged-" + "x" * 40) == "unauthenticated"
    viewer, op, engineer = login(h, "viewer"), login(h, "op"), login(h, "engineer")
    assert h.ok("status", token=viewer)["status"]["access"] == "users"
    assert h.refused("stop", token=viewer) == "forbidden"
    assert h.ok("stop", token=op)["status"]["state"] == "STOP/VALID CONFIGURATION"
    assert h.refused("step", token=op) == "forbidden"  # single step needs Read+Write
    assert h.ok("step", token=engineer)["ok"]
    assert h.refused("write", token=op, variable="P.n", value=5) == "forbidden"
    h.ok("write", token=engineer, variable="P.n", value=5)
    admin_only = {"name": "allow_online_settings", "value": False}
    assert h.refused("set_parameter", token=engineer, **admin_only) == "forbidden"
    h.ok("set_parameter", token=login(h, "admin"), **admin_only)
    write = [e for e in h.ok("events", token=viewer)["events"] if e["kind"] == "write"]
    assert write[0]["user"] == "engineer"  # who did it is in the event


def test_sessions_expire_and_logout_ends_them() -> None:
    h = harness(TEXT, users=users())
    token = login(h, "op")
    h.clock.advance(SESSION_NS)
    assert h.refused("status", token=token) == "unauthenticated"
    token = login(h, "op")
    h.ok("logout", token=token)
    assert h.refused("status", token=token) == "unauthenticated"


def test_failed_logins_are_events_and_lock_the_name_for_a_while() -> None:
    h = harness(TEXT, users=users())
    for _ in range(11):  # ten lock nothing; the eleventh locks the name for 1 s
        assert h.failed_login("op", "Guess-0") == "login_failed"
    assert h.failed_login("op", PASSWORDS["op"]) == "locked"
    h.clock.advance(2 * 10**9)
    assert h.failed_login("op", "Guess-0") == "login_failed"  # now for 2 s
    assert h.failed_login("op", PASSWORDS["op"]) == "locked"
    h.clock.advance(3 * 10**9)
    token = login(h, "op")
    events = h.ok("events", token=token)["events"]
    refused = [e for e in events if e["kind"] == "login" and "refused" in e["message"]]
    # all fourteen refusals are accounted for, in two events: the first, and the count of
    # the others reported with the next login of that name (failed logins are aggregated)
    assert len(refused) == 2
    assert "13 more refused" in refused[1]["message"]
    assert "Guess-0" not in json.dumps(events)  # no password in any event


def test_new_accounts_take_effect_with_a_reload() -> None:
    h = harness(TEXT, users=users())
    op, admin = login(h, "op"), login(h, "admin")
    fewer = [u for u in users() if u.name != "op"]
    h.token = admin
    h.send(compiled(TEXT.replace("n + 1", "n + 2"), users=fewer))
    h.ok("reload")
    h.token = None
    assert h.refused("status", token=op) == "unauthenticated"  # the account is gone
    assert h.failed_login("op", PASSWORDS["op"]) == "login_failed"
    assert h.ok("status", token=admin)["ok"]


def test_accounts_are_checked_at_compile_time() -> None:
    def messages(accounts: list[UserAccount]) -> list[str]:
        result = compile_sources([SourceFile("t.st", TEXT)], users=accounts)
        return [d.message for d in result.diagnostics]

    operator = UserAccount("op", "operator", hash_password("Turn-2"))
    assert messages([operator]) == ["the users include no administrator"]
    assert messages([operator, UserAccount("op", "administrator", operator.password_hash)]) == [
        "user 'op' is defined twice"
    ]
    bad = UserAccount("bad name", "boss", "Turn-2")
    assert messages([bad, UserAccount("a", "administrator", operator.password_hash)]) == sorted(
        [
            "user name 'bad name' must be 1 to 32 of A-Z a-z 0-9 _ -",
            "level of 'bad name' must be one of read, operator, read-write, administrator",
            "password of 'bad name' is not a verifier from `padt passwd`",
        ]
    )


def test_hashes_are_salted_and_slow() -> None:
    first, second = hash_password("Same-1"), hash_password("Same-1")
    assert first != second  # another salt each time
    assert verify_password("Same-1", first) and not verify_password("Same-2", first)
    assert first.startswith("scram$16384$8$1$")  # scrypt cost, the SCRAM verifier form


def test_passwd_prints_an_account_and_never_the_password() -> None:
    result = padt("passwd", "admin", "--level", "administrator", env={"PADT_PASSWORD": "Ab-12"})
    assert result.returncode == 0, result.stderr
    assert "Ab-12" not in result.stdout + result.stderr
    line = next(x for x in result.stdout.splitlines() if x.startswith("password_hash"))
    assert verify_password("Ab-12", line.split('"')[1])


def test_the_runtime_refuses_whoever_sends_the_command(tmp_path: Path, zenoh_endpoint: str) -> None:
    """Straight over Zenoh (bypassing the PADT) and through the command line alike."""
    config = ResourceConfig(name="Guarded", autostart="cold", target_cycle_ms=20)
    result = compile_sources([SourceFile("p.st", TEXT)], resource=config, users=users())
    assert result.artifact is not None
    store_artifact(tmp_path, result.artifact)
    assert "Manage-4" not in result.artifact.to_json()
    with running_resource("Guarded", tmp_path, zenoh_endpoint) as (_, client):
        raw: list[dict[str, Any]] = [
            json.loads(r.ok.payload.to_bytes())
            for r in client.session.get(
                command_key("Guarded"), payload=json.dumps({"cmd": "stop"}), timeout=5
            )
            if r.ok is not None
        ]
        assert raw[0]["error"]["code"] == "unauthenticated"
        endpoint = ["--resource", "Guarded", "--zenoh", zenoh_endpoint]
        refused = padt("stop", *endpoint)
        assert refused.returncode == 1 and "unauthenticated" in refused.stderr
        env = {"PADT_PASSWORD": PASSWORDS["viewer"]}
        forbidden = padt("stop", *endpoint, "--user", "viewer", env=env)
        assert forbidden.returncode == 1 and "forbidden" in forbidden.stderr
        env = {"PADT_PASSWORD": PASSWORDS["op"]}
        stopped = padt("stop", *endpoint, "--user", "op", env=env)
        assert stopped.returncode == 0, stopped.stderr
        op = ResourceClient(client.session, "Guarded")
        assert op.login("op", PASSWORDS["op"]).level == "operator"
        assert op.command("status")["status"]["state"] == "STOP/VALID CONFIGURATION"
    logs = [p.read_text(errors="replace") for p in tmp_path.rglob("*") if p.is_file()]
    assert not any(password in text for text in logs for password in PASSWORDS.values())
    assert os.environ.get("PADT_PASSWORD") is None


def start_demo(state_dir: Path, zenoh_port: int) -> tuple[subprocess.Popen[str], list[str]]:
    command = [sys.executable, "-m", "padt.cli", "demo", "--state-dir", str(state_dir)]
    command += ["--port", str(free_port()), "--zenoh-port", str(zenoh_port), "--api-port", "0"]
    command += ["--no-opcua"]
    process = subprocess.Popen(command, cwd=REPO, stdout=subprocess.PIPE, text=True)
    assert process.stdout is not None
    lines = []
    for line in process.stdout:
        lines.append(line)
        if "padt demo: open" in line:
            break
    return process, lines


def stop_demo(process: subprocess.Popen[str]) -> None:
    process.send_signal(signal.SIGINT)
    assert process.wait(timeout=15) == 0


def test_the_demo_makes_its_administrator_once_and_keeps_only_the_hash(tmp_path: Path) -> None:
    zenoh_port = free_port()
    process, lines = start_demo(tmp_path, zenoh_port)
    try:
        line = next(x for x in lines if "administrator 'admin', password" in x)
        password = line.split("password ")[1].split(" ")[0]
        session = open_client(f"tcp/127.0.0.1:{zenoh_port}")
        try:
            anonymous = ResourceClient(session, "Tank1")
            wait_until_answering(anonymous)
            assert anonymous.command("stop")["error"]["code"] == "unauthenticated"
            admin = ResourceClient(session, "Tank1")
            assert admin.login("admin", password).level == "administrator"
            assert admin.command("stop")["ok"]
            # the same administrator is the REST API's Security Administrator
            api = next(x for x in lines if "REST API" in x).split()[4].removesuffix("/docs")
            login = httpx.post(f"{api}/api/login", json={"user": "admin", "password": password})
            assert login.json()["level"] == "security-administrator"
            headers = {"Authorization": f"Bearer {login.json()['token']}"}
            listed = httpx.get(f"{api}/api/resources", headers=headers).json()
            assert [entry["resource"] for entry in listed] == ["Tank1"]
            # a load of the served demo project keeps the demo's accounts
            account = {"user": "admin", "password": password}
            httpx.post(f"{api}/api/resources/Tank1/login", headers=headers, json=account)
            loaded = httpx.post(
                f"{api}/api/resources/Tank1/load", headers=headers, json={"project": "demo"},
                timeout=120,
            )  # fmt: skip
            assert loaded.status_code == 200, loaded.text
            assert anonymous.command("status")["error"]["code"] == "unauthenticated"
        finally:
            session.close()
    finally:
        stop_demo(process)
    stored = [p.read_text(errors="replace") for p in tmp_path.rglob("*") if p.is_file()]
    assert not any(password in text for text in stored)
    # the files that hold verifiers or keys are the owner's alone
    secret = [
        p for p in tmp_path.rglob("*") if p.is_file() and "scram$" in p.read_text(errors="replace")
    ]
    secret += [tmp_path / "identity.key"]
    assert {p.name for p in secret} >= {"artifact.json", "padt.toml", "demo-administrator.json"}
    assert all(p.stat().st_mode & 0o077 == 0 for p in secret), [
        oct(p.stat().st_mode) for p in secret
    ]
    again, lines = start_demo(tmp_path, free_port())
    stop_demo(again)
    assert not any(password in line for line in lines)
    assert any("shown at the first start" in line for line in lines)


def test_a_token_alone_is_worth_nothing() -> None:
    h = harness(TEXT, users=users())
    token = login(h, "op")
    assert h.ok("status", token=token)["ok"]  # signed with the session key, as clients do
    key, numbers = h.logins[token]
    bare = json.dumps({"cmd": "status", "token": token, "seq": next(numbers)}).encode()
    refused = json.loads(execute(h.resource, bare))  # the token as a listener saw it
    assert refused["error"]["code"] == "unauthenticated"
    signed = json.dumps({"cmd": "stop", "token": token, "seq": next(numbers)}).encode()
    mac = scram.request_mac(key, signed)
    assert json.loads(execute(h.resource, signed, mac))["ok"]
    replayed = json.loads(execute(h.resource, signed, mac))  # the same request again
    assert replayed["error"]["code"] == "unauthenticated"
    wrong_key = scram.request_mac(b"k" * 32, signed.replace(b'"stop"', b'"start"'))
    forged = json.loads(execute(h.resource, signed.replace(b'"stop"', b'"start"'), wrong_key))
    assert forged["error"]["code"] == "unauthenticated"


def test_an_unknown_name_gets_a_challenge_like_any_other() -> None:
    h = harness(TEXT, users=users())
    known = h.ok("login_begin", user="op", nonce=scram.new_nonce())
    ghost = h.ok("login_begin", user="ghost", nonce=scram.new_nonce())
    again = h.ok("login_begin", user="ghost", nonce=scram.new_nonce())
    assert sorted(known) == sorted(ghost) and ghost["salt"] == again["salt"]
    assert (ghost["n"], ghost["r"], ghost["p"]) == (known["n"], known["r"], known["p"])
    assert h.failed_login("ghost", "Anything-1") == "login_failed"


def test_verifiers_of_the_older_form_still_log_in() -> None:
    salt = b"0123456789abcdef"
    salted = hashlib.scrypt(b"Turn-2", salt=salt, n=2**14, r=8, p=1, dklen=32)
    encoded = (base64.b64encode(part).decode() for part in (salt, salted))
    older = "scrypt$16384$8$1$" + "$".join(encoded)
    accounts = [UserAccount("op", "operator", older), *(u for u in users() if u.name != "op")]
    h = harness(TEXT, users=accounts)
    assert h.ok("status", token=h.login("op", "Turn-2"))["ok"]
