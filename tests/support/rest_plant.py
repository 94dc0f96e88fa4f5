"""A plant for the REST API tests: a Zenoh router, one runtime process for resource
`Plant` with PES accounts, two project folders the API serves, and the API server itself
on a real HTTP port, with PADT accounts of each level."""

from __future__ import annotations

import subprocess
import time
from collections.abc import Iterator
from contextlib import ExitStack, contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import httpx

from backend.api.server import ApiServer
from backend.api.service import PadtService
from backend.engineering.padt_accounts import PadtAccounts, with_account, write_accounts
from backend.engineering.project import compile_project, load_project
from backend.engineering.resource_client import ResourceClient
from backend.engineering.resource_directory import ResourceDirectory
from runtime.contract.accounts import hash_password
from runtime.contract.session import open_client
from tests.conftest import free_port
from tests.support.runtime_process import router, runtime_process, store_artifact

# PES accounts of the resource (its own levels) and PADT accounts of the API
PES_PASSWORDS = {"viewer": "Look-1", "op": "Turn-2", "engineer": "Change-3", "admin": "Manage-4"}
PES_LEVELS = {
    "viewer": "read",
    "op": "operator",
    "engineer": "read-write",
    "admin": "administrator",
}
PADT_PASSWORDS = {"reader": "Read-5", "builder": "Build-6", "keeper": "Keep-7"}
PADT_LEVELS = {"reader": "read-only", "builder": "read-write", "keeper": "security-administrator"}

PROGRAM = """PROGRAM P
VAR n : DINT; limit : DINT := 1000000; flag : BOOL; {extra} END_VAR
n := n + 1;
IF n > limit THEN n := 0; END_IF;
flag := n > 10;
END_PROGRAM
"""


def write_project(folder: Path, extra: str = "", resource: str = "Plant") -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    users = "".join(
        f'[[resource.user]]\nname = "{name}"\nlevel = "{PES_LEVELS[name]}"\n'
        f'password_hash = "{hash_password(password)}"\n\n'
        for name, password in sorted(PES_PASSWORDS.items())
    )
    (folder / "padt.toml").write_text(
        '[project]\nname = "Plant"\nversion = "1"\n\n'
        f'[resource]\nname = "{resource}"\ntarget_cycle_ms = 20\nsafety_operation = false\n'
        'global_forcing_allowed = true\nautostart = "cold"\n\n'
        '[[resource.program]]\nname = "P"\npou = "P"\nid = 1\nlocal_forcing_allowed = true\n\n'
        + users
    )
    (folder / "plant.st").write_text(PROGRAM.format(extra=extra))
    return folder


@dataclass
class Plant:
    url: str
    endpoint: str
    projects: Path
    backups: Path
    accounts_file: Path
    state_dir: Path
    http: httpx.Client
    zenoh_client: ResourceClient
    runtime: subprocess.Popen[bytes]

    def token(self, padt_user: str) -> str:
        reply = self.http.post(
            f"{self.url}/api/login",
            json={"user": padt_user, "password": PADT_PASSWORDS[padt_user]},
        )
        assert reply.status_code == 200, reply.text
        token: str = reply.json()["token"]
        return token

    def call(
        self, method: str, path: str, token: str | None = None, **kwargs: Any
    ) -> httpx.Response:
        headers = {"Authorization": f"Bearer {token}"} if token is not None else {}
        return self.http.request(method, f"{self.url}{path}", headers=headers, **kwargs)

    def session(self, padt_user: str, pes_user: str | None = None) -> str:
        """An API token of `padt_user`, logged in to the resource as `pes_user`."""
        token = self.token(padt_user)
        if pes_user is not None:
            body = {"user": pes_user, "password": PES_PASSWORDS[pes_user]}
            reply = self.call("POST", "/api/resources/Plant/login", token, json=body)
            assert reply.status_code == 200, reply.text
        return token


def padt_accounts_file(path: Path) -> Path:
    accounts: tuple[Any, ...] = ()
    # the security administrator first: every state of the file keeps one
    for name in sorted(PADT_PASSWORDS, key=lambda n: PADT_LEVELS[n] != "security-administrator"):
        accounts = with_account(accounts, name, PADT_LEVELS[name], PADT_PASSWORDS[name])
    write_accounts(path, accounts)
    return path


@contextmanager
def plant(base: Path, fresh: bool = False, extra: str = "") -> Iterator[Plant]:
    """`fresh`: the runtime starts without a configuration (else with project `plant`)."""
    projects = base / "projects"
    write_project(projects / "plant", extra=extra)  # `extra`: more variables of P
    write_project(projects / "plant_v2", extra="m : INT := 7;")
    state_dir = base / "state"
    artifact = compile_project(load_project([projects / "plant"])).artifact
    assert artifact is not None
    if not fresh:
        store_artifact(state_dir, artifact)
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    accounts_file = padt_accounts_file(base / "padt-accounts.json")
    with ExitStack() as stack:
        stack.enter_context(router(endpoint))
        runtime = stack.enter_context(runtime_process("Plant", state_dir, endpoint))
        session = open_client(endpoint)
        stack.callback(session.close)
        accounts = PadtAccounts(accounts_file, time.monotonic_ns)
        folders = {"plant": projects / "plant", "plant_v2": projects / "plant_v2"}
        service = PadtService(ResourceDirectory(session), accounts, folders, base / "backups")
        stack.callback(service.close)
        server = ApiServer(service)
        stack.callback(server.close)
        http = stack.enter_context(httpx.Client(timeout=60))
        zenoh_client = ResourceClient(session, "Plant")
        zenoh_client.wait_until_answering()
        found = Plant(
            server.url,
            endpoint,
            projects,
            base / "backups",
            accounts_file,
            state_dir,
            http,
            zenoh_client,
            runtime,
        )
        _wait_until_listed(found)
        yield found


def _wait_until_listed(plant: Plant) -> None:
    token = plant.token("reader")
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline:
        listed = plant.call("GET", "/api/resources", token).json()
        if [entry["resource"] for entry in listed] == ["Plant"]:
            return
        time.sleep(0.05)
    raise AssertionError("the API did not see resource Plant come online")
