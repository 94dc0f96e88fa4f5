"""Editing projects over the REST API, on a real HTTP port: a new project from a template,
its tree, a file read and saved (409 with the current hash when it changed meanwhile),
POUs added, renamed and deleted, padt.toml's settings checked and written; Read-only may
look and not change; hostile paths are refused with a reason."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from collections.abc import Iterator
from contextlib import ExitStack
from dataclasses import dataclass
from pathlib import Path
from typing import Any
from urllib.parse import quote

import httpx
import pytest

from backend.api.server import ApiServer
from backend.api.service import PadtService
from backend.engineering.padt_accounts import PadtAccounts
from backend.engineering.project_shelf import shelf_of
from backend.engineering.resource_directory import ResourceDirectory
from runtime.contract.session import open_client
from tests.conftest import REPO, free_port
from tests.support.rest_plant import PADT_PASSWORDS, padt_accounts_file
from tests.support.runtime_process import router


@dataclass
class Api:
    url: str
    http: httpx.Client
    projects: Path
    audit: Path

    def token(self, user: str) -> str:
        body = {"user": user, "password": PADT_PASSWORDS[user]}
        reply = self.http.post(f"{self.url}/api/login", json=body)
        assert reply.status_code == 200, reply.text
        return str(reply.json()["token"])

    def call(self, method: str, path: str, user: str, **kwargs: Any) -> httpx.Response:
        headers = {"Authorization": f"Bearer {self.token(user)}"}
        return self.http.request(method, f"{self.url}{path}", headers=headers, **kwargs)


@pytest.fixture(scope="module")
def api(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Api]:
    base = tmp_path_factory.mktemp("rest-editing")
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    with ExitStack() as stack:
        stack.enter_context(router(endpoint))
        session = open_client(endpoint)
        stack.callback(session.close)
        accounts = PadtAccounts(padt_accounts_file(base / "accounts.json"), time.monotonic_ns)
        shelf = shelf_of({}, base / "projects", base / "audit.jsonl")
        service = PadtService(ResourceDirectory(session), accounts, shelf, base / "backups")
        stack.callback(service.close)
        server = ApiServer(service)
        stack.callback(server.close)
        http = stack.enter_context(httpx.Client(timeout=60))
        yield Api(server.url, http, base / "projects", base / "audit.jsonl")


def error(reply: httpx.Response) -> dict[str, Any]:
    found: dict[str, Any] = reply.json()["error"]
    return found


def test_a_new_project_from_a_template_with_its_tree(api: Api) -> None:
    templates = api.call("GET", "/api/projects/templates", "reader").json()
    assert [t["name"] for t in templates] == ["empty", "tank", "sequence", "conveyor"]
    made = api.call(
        "POST", "/api/projects", "builder", json={"name": "seq", "template": "sequence"}
    )
    assert made.status_code == 201, made.text
    assert {"name": "seq"} in api.call("GET", "/api/projects", "reader").json()
    tree = api.call("GET", "/api/projects/seq/tree", "reader").json()
    assert [(p["kind"], p["name"]) for p in tree["pous"]] == [("PROGRAM", "Batch")]
    assert tree["resource"]["programs"][0]["pou"] == "Batch"
    assert [g["name"] for g in tree["globals"]] == ["Globals"]
    again = api.call("POST", "/api/projects", "builder", json={"name": "seq", "template": "empty"})
    assert again.status_code == 409 and error(again)["code"] == "exists"
    bad = api.call("POST", "/api/projects", "builder", json={"name": "a/x", "template": "empty"})
    assert bad.status_code == 400 and "must not hold '/'" in error(bad)["message"]
    reader = api.call("POST", "/api/projects", "reader", json={"name": "r", "template": "empty"})
    assert reader.status_code == 403


def test_two_clients_saving_one_file_get_a_conflict(api: Api) -> None:
    api.call("POST", "/api/projects", "builder", json={"name": "two", "template": "empty"})
    first = api.call("GET", "/api/projects/two/files/Main.st", "builder").json()
    second = api.call("GET", "/api/projects/two/files/Main.st", "keeper").json()
    body = {"text": first["text"] + "(* one *)\n", "base_hash": first["hash"]}
    saved = api.call("PUT", "/api/projects/two/files/Main.st", "builder", json=body)
    assert saved.status_code == 200, saved.text
    body = {"text": second["text"] + "(* two *)\n", "base_hash": second["hash"]}
    late = api.call("PUT", "/api/projects/two/files/Main.st", "keeper", json=body)
    assert late.status_code == 409
    assert error(late)["code"] == "conflict"
    assert error(late)["current_hash"] == saved.json()["hash"]
    state = api.call(
        "GET",
        "/api/projects/two/changed",
        "reader",
        params={"path": "Main.st", "known_hash": second["hash"]},
    ).json()
    assert state == {"path": "Main.st", "changed": True, "hash": saved.json()["hash"]}
    text = api.call("GET", "/api/projects/two/files/Main.st", "reader").json()["text"]
    assert "(* one *)" in text and "(* two *)" not in text


def test_read_only_reads_and_cannot_save(api: Api) -> None:
    api.call("POST", "/api/projects", "builder", json={"name": "ro", "template": "empty"})
    opened = api.call("GET", "/api/projects/ro/files/Main.st", "reader").json()
    body = {"text": "", "base_hash": opened["hash"]}
    refused = api.call("PUT", "/api/projects/ro/files/Main.st", "reader", json=body)
    assert refused.status_code == 403
    assert api.call("GET", "/api/projects/ro/files/Main.st", "reader").json() == opened


@pytest.mark.parametrize(
    "path", ["..%2F..%2Fetc%2Fpasswd", "%2Fetc%2Fpasswd", "notes.txt", ".hidden.st", "a%5Cb.st"]
)
def test_hostile_paths_are_refused_with_a_reason(api: Api, path: str) -> None:
    api.call("POST", "/api/projects", "builder", json={"name": "paths", "template": "empty"})
    reply = api.call("GET", f"/api/projects/paths/files/{path}", "builder")
    assert reply.status_code in (400, 404), reply.text
    assert error(reply)["code"] in ("path", "not_found") and error(reply)["message"]
    put = api.call("PUT", f"/api/projects/paths/files/{path}", "builder", json={"text": "x"})
    assert put.status_code in (400, 404) and error(put)["message"]


def test_declarations_added_renamed_and_deleted(api: Api) -> None:
    api.call("POST", "/api/projects", "builder", json={"name": "decl", "template": "empty"})
    route = "/api/projects/decl/declarations"
    made = api.call("POST", route, "builder", json={"kind": "FUNCTION_BLOCK", "name": "Motor"})
    assert made.status_code == 201 and made.json()["path"] == "Motor.st"
    renamed = api.call("POST", f"{route}/Motor/rename", "builder", json={"new_name": "Drive"})
    assert [s["path"] for s in renamed.json()] == ["Motor.st", "Drive.st"]
    running = api.call("DELETE", f"{route}/Main", "builder")
    assert running.status_code == 409 and error(running)["code"] == "in_use"
    assert api.call("DELETE", f"{route}/Drive", "builder").status_code == 200
    tree = api.call("GET", "/api/projects/decl/tree", "reader").json()
    assert [p["name"] for p in tree["pous"]] == ["Main"]
    actions = [line for line in api.audit.read_text().splitlines() if '"decl"' in line]
    assert len(actions) == 5  # new project, create, save + rename, delete
    drive = api.call("GET", "/api/projects/decl/history", "reader", params={"file": "Drive.st"})
    assert [(e["user"], e["action"]) for e in drive.json()] == [
        ("builder", "delete"),
        ("builder", "rename"),
    ]


def test_settings_checked_and_written(api: Api) -> None:
    api.call("POST", "/api/projects", "builder", json={"name": "set", "template": "tank"})
    read = api.call("GET", "/api/projects/set/settings", "reader").json()
    draft = read["settings"]
    draft["parameters"]["watchdog_ms"] = 2
    problems = api.call("POST", "/api/projects/set/settings/check", "reader", json=draft).json()
    assert problems == [
        {
            "field": "resource.watchdog_ms",
            "message": "watchdog_ms must be from 6 to 7500",
            "code": "",
            "severity": "error",
        }
    ]
    body = {"settings": draft, "base_hash": read["hash"]}
    refused = api.call("PUT", "/api/projects/set/settings", "builder", json=body)
    assert refused.status_code == 422 and error(refused)["problems"][0]["field"] == (
        "resource.watchdog_ms"
    )
    draft["parameters"]["watchdog_ms"] = 300
    written = api.call("PUT", "/api/projects/set/settings", "builder", json=body)
    assert written.status_code == 200, written.text
    config = (api.projects / "set" / "padt.toml").read_text()
    assert "watchdog_ms = 300" in config and "# Field I/O over Modbus TCP" in config
    stale = api.call("PUT", "/api/projects/set/settings", "builder", json=body)
    assert stale.status_code == 409


def test_an_unknown_project_is_404(api: Api) -> None:
    reply = api.call("GET", f"/api/projects/{quote('nope')}/tree", "reader")
    assert reply.status_code == 404 and error(reply)["code"] == "unknown_project"


def test_padt_api_makes_new_projects_in_its_projects_dir_and_audits_them(tmp_path: Path) -> None:
    accounts = padt_accounts_file(tmp_path / "accounts.json")
    port, endpoint = free_port(), f"tcp/127.0.0.1:{free_port()}"
    (tmp_path / "shelf" / "by_hand").mkdir(parents=True)
    (tmp_path / "shelf" / "by_hand" / "a.st").write_text("PROGRAM A END_PROGRAM\n")
    command = [sys.executable, "-m", "padt.cli", "api", "--accounts", str(accounts)]
    command += ["--port", str(port), "--zenoh", endpoint]
    command += ["--projects-dir", str(tmp_path / "shelf"), "--audit-log", str(tmp_path / "a.log")]
    with (
        router(endpoint),
        subprocess.Popen(
            command, cwd=REPO, stdout=subprocess.PIPE, text=True, env=dict(os.environ)
        ) as process,
    ):
        try:
            assert process.stdout is not None
            assert f"http://127.0.0.1:{port}" in process.stdout.readline()
            url = f"http://127.0.0.1:{port}"
            login = {"user": "builder", "password": PADT_PASSWORDS["builder"]}
            token = httpx.post(f"{url}/api/login", json=login).json()["token"]
            headers = {"Authorization": f"Bearer {token}"}
            body = {"name": "line", "template": "empty", "resource": "Line1"}
            made = httpx.post(f"{url}/api/projects", json=body, headers=headers)
            assert made.status_code == 201, made.text
            listed = httpx.get(f"{url}/api/projects", headers=headers).json()
            assert listed == [{"name": "by_hand"}, {"name": "line"}]
        finally:
            process.terminate()
            assert process.wait(timeout=15) == 0
    assert (tmp_path / "shelf" / "line" / "Main.st").is_file()
    [entry] = [json.loads(line) for line in (tmp_path / "a.log").read_text().splitlines()]
    assert (entry["user"], entry["project"], entry["action"]) == ("builder", "line", "new-project")
