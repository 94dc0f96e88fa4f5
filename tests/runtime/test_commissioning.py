"""A runtime without a configuration is not open to anyone on the bus (issue 30, item 2):
the first download proves knowledge of the setup secret the runtime made at its first
start, by logging in as the commissioning account `setup` with it; once a configuration
with accounts is loaded, the secret works no more. A runtime process over a real Zenoh
router, the command line as a user runs it."""

from __future__ import annotations

import json
import stat
from pathlib import Path

import pytest

from backend.compiler.pipeline import compile_sources
from backend.compiler.source import SourceFile
from backend.engineering.download import download
from backend.engineering.project import user_entry
from backend.engineering.resource_client import ResourceClient
from runtime.contract.accounts import hash_password
from runtime.contract.artifact import Artifact, ResourceConfig, UserAccount
from runtime.contract.protocol import GetStatus
from runtime.contract.refusal import Refusal
from runtime.contract.state_folder import setup_secret_path
from tests.conftest import padt
from tests.support.rest_plant import plant
from tests.support.runtime_process import running_resource, setup_secret

RESOURCE = "Fresh"
TEXT = "PROGRAM P VAR n : INT; END_VAR n := n + 1; END_PROGRAM"
ADMIN = UserAccount("boss", "administrator", hash_password("Boss-pw1"))


def configuration() -> Artifact:
    config = ResourceConfig(name=RESOURCE, target_cycle_ms=20)
    result = compile_sources([SourceFile("p.st", TEXT)], resource=config, users=[ADMIN])
    assert result.artifact is not None
    return result.artifact


def test_a_fresh_runtime_takes_its_first_configuration_only_with_the_setup_secret(
    tmp_path: Path, zenoh_endpoint: str
) -> None:
    with running_resource(RESOURCE, tmp_path, zenoh_endpoint) as (_, anonymous):
        status = anonymous.ask(GetStatus()).status  # a fresh runtime still says what it is
        assert status.state.value == "STOP/INVALID CONFIGURATION" and status.access == "setup"
        secret_file = setup_secret_path(tmp_path)
        assert stat.S_IMODE(secret_file.stat().st_mode) == 0o600
        for reply in [
            anonymous.command("transfer_begin", size=10, crc="00000000"),
            anonymous.command("load"),
            anonymous.command("events"),
        ]:
            assert reply["error"]["code"] == "unauthenticated", reply
            assert "setup secret" in reply["error"]["message"]
        with pytest.raises(Refusal) as refused:
            download(anonymous, configuration())
        assert refused.value.code == "unauthenticated"

        with pytest.raises(Refusal):  # a guess is no secret
            ResourceClient(anonymous.session, RESOURCE).login("setup", "Guessed-secret-1")
        commissioner = ResourceClient(anonymous.session, RESOURCE)
        secret = setup_secret(tmp_path)
        commissioner.login("setup", secret)
        assert download(commissioner, configuration()).state.value == "STOP/VALID CONFIGURATION"

        # the configuration's accounts rule from now on: the secret works no more
        assert not secret_file.exists()
        with pytest.raises(Refusal) as spent:
            ResourceClient(anonymous.session, RESOURCE).login("setup", secret)
        assert spent.value.code == "login_failed"
        assert anonymous.command("transfer_begin", size=10, crc="00000000")["error"]["code"] == (
            "unauthenticated"
        )
        assert anonymous.command("status")["error"]["code"] == "unauthenticated"
        ResourceClient(anonymous.session, RESOURCE).login("boss", "Boss-pw1")


def write_project(folder: Path) -> Path:
    folder.mkdir()
    (folder / "padt.toml").write_text(
        f'[project]\nname = "Fresh"\nversion = "1"\n\n[resource]\nname = "{RESOURCE}"\n'
        'target_cycle_ms = 20\n\n[[resource.program]]\nname = "P"\npou = "P"\nid = 1\n'
        + user_entry(ADMIN)
    )
    (folder / "p.st").write_text(TEXT)
    return folder


def test_padt_load_commissions_with_the_setup_secret_file(
    tmp_path: Path, zenoh_endpoint: str
) -> None:
    project = write_project(tmp_path / "project")
    state = tmp_path / "state"
    online = ["--resource", RESOURCE, "--zenoh", zenoh_endpoint]
    backups = ["--backup-dir", str(tmp_path / "backups")]
    with running_resource(RESOURCE, state, zenoh_endpoint):
        refused = padt("load", str(project), *online, *backups)
        assert refused.returncode == 1 and "setup secret" in refused.stderr
        secret_file = setup_secret_path(state)
        loaded = padt(
            "load", str(project), *online, *backups, "--setup-secret-file", str(secret_file)
        )
        assert loaded.returncode == 0, loaded.stderr
        status = padt(
            "status", *online, "--user", "boss", "--json", env={"PADT_PASSWORD": "Boss-pw1"}
        )
        assert json.loads(status.stdout)["state"] == "STOP/VALID CONFIGURATION"


def test_the_setup_secret_may_come_from_a_file_given_to_the_runtime(
    tmp_path: Path, zenoh_endpoint: str
) -> None:
    given = tmp_path / "secret.txt"
    given.write_text("Chosen-by-the-integrator-42\n")
    state = tmp_path / "state"
    with running_resource(RESOURCE, state, zenoh_endpoint, "--setup-secret-file", str(given)) as (
        _,
        client,
    ):
        assert not setup_secret_path(state).exists()  # none made: the given one counts
        client.login("setup", "Chosen-by-the-integrator-42")
        download(client, configuration())
        assert given.exists()  # the integrator's own file is left alone


def test_the_rest_api_commissions_by_logging_in_as_setup(tmp_path: Path) -> None:
    with plant(tmp_path, fresh=True) as site:
        builder = site.token("builder")
        url = "/api/resources/Plant"
        refused = site.call("POST", f"{url}/load", builder, json={"project": "plant"})
        assert refused.status_code == 401  # no login to the resource
        secret = {"user": "setup", "password": setup_secret(site.state_dir)}
        assert site.call("POST", f"{url}/login", builder, json=secret).status_code == 200
        loaded = site.call("POST", f"{url}/load", builder, json={"project": "plant"})
        assert loaded.status_code == 200, loaded.text
        again = site.call("POST", f"{url}/login", site.token("builder"), json=secret)
        assert again.status_code != 200  # spent
        assert site.session("builder", "engineer")  # the project's accounts rule now
