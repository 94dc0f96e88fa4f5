"""Transport security by configuration: TLS with a private CA, and user/password
authentication. A runtime process and the `padt` command line connect with the right
settings; a client without them does not get in at all."""

from __future__ import annotations

import json
import subprocess
import time
from pathlib import Path

import pytest

from backend.engineering.resource_client import ResourceClient
from runtime.contract.keyspace import command_key, status_key
from runtime.contract.session import open_client, open_router
from runtime.contract.session_options import RouterUnreachable
from tests.conftest import REPO, free_port, padt
from tests.support.runtime_process import runtime_process, wait_until_answering, write_demo_artifact


def openssl(*args: str) -> None:
    subprocess.run(["openssl", *args], check=True, capture_output=True)


def certificates(folder: Path) -> dict[str, Path]:
    """A private CA and a server certificate for 127.0.0.1, made with the openssl CLI."""
    ca, ca_key = folder / "ca.pem", folder / "ca.key"
    server, server_key, request = folder / "server.pem", folder / "server.key", folder / "s.csr"
    extensions = folder / "ext.cnf"
    openssl("req", "-x509", "-newkey", "rsa:2048", "-nodes", "-keyout", str(ca_key),
            "-out", str(ca), "-days", "2", "-subj", "/CN=padt test CA",
            "-addext", "basicConstraints=critical,CA:TRUE",
            "-addext", "keyUsage=critical,keyCertSign,cRLSign")  # fmt: skip
    openssl("req", "-newkey", "rsa:2048", "-nodes", "-keyout", str(server_key),
            "-out", str(request), "-subj", "/CN=localhost")  # fmt: skip
    extensions.write_text(
        "subjectAltName=IP:127.0.0.1,DNS:localhost\nbasicConstraints=CA:FALSE\n"
        "extendedKeyUsage=serverAuth\n"
    )
    openssl("x509", "-req", "-in", str(request), "-CA", str(ca), "-CAkey", str(ca_key),
            "-CAcreateserial", "-out", str(server), "-days", "2",
            "-extfile", str(extensions))  # fmt: skip
    return {"ca": ca, "cert": server, "key": server_key}


def config(path: Path, text: str) -> Path:
    path.write_text(text)
    return path


def refused(endpoint: str, config_file: Path | None) -> None:
    with pytest.raises(RouterUnreachable):
        open_client(endpoint, config_file).close()


def check_runtime_and_cli(tmp_path: Path, endpoint: str, client_config: Path) -> None:
    write_demo_artifact(tmp_path / "state")
    extra = ("--zenoh-config", str(client_config))
    with runtime_process("Tank1", tmp_path / "state", endpoint, *extra):
        session = open_client(endpoint, client_config)
        try:
            client = ResourceClient(session, "Tank1")
            wait_until_answering(client)
            assert client.command("status")["status"]["state"] == "RUN"
        finally:
            session.close()
        shown = padt("status", "--resource", "Tank1", "--zenoh", endpoint, *extra)
        assert shown.returncode == 0, shown.stderr
        assert "resource Tank1: RUN" in shown.stdout


def test_tls_with_a_private_ca(tmp_path: Path) -> None:
    files = certificates(tmp_path)
    endpoint = f"tls/127.0.0.1:{free_port()}"
    router_config = config(
        tmp_path / "router.json5",
        f'{{transport: {{link: {{tls: {{listen_certificate: "{files["cert"]}", '
        f'listen_private_key: "{files["key"]}"}}}}}}}}',
    )
    client_config = config(
        tmp_path / "client.json5",
        f'{{transport: {{link: {{tls: {{root_ca_certificate: "{files["ca"]}"}}}}}}}}',
    )
    untrusted = config(tmp_path / "plain.json5", "{connect: {timeout_ms: 1500}}")
    router = open_router(endpoint, router_config)
    try:
        check_runtime_and_cli(tmp_path, endpoint, client_config)
        refused(endpoint, untrusted)  # no CA to trust the router's certificate
    finally:
        router.close()


def test_user_and_password(tmp_path: Path) -> None:
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    users = tmp_path / "users.txt"
    users.write_text("plant:Sesame-42\n")
    router_config = config(
        tmp_path / "router.json5",
        f'{{transport: {{auth: {{usrpwd: {{dictionary_file: "{users}"}}}}}}}}',
    )
    good = config(
        tmp_path / "client.json5",
        '{transport: {auth: {usrpwd: {user: "plant", password: "Sesame-42"}}}}',
    )
    wrong = config(
        tmp_path / "wrong.json5",
        '{connect: {timeout_ms: 1500}, transport: {auth: {usrpwd: {user: "plant", '
        'password: "guess"}}}}',
    )
    anonymous = config(tmp_path / "anonymous.json5", "{connect: {timeout_ms: 1500}}")
    router = open_router(endpoint, router_config)
    try:
        check_runtime_and_cli(tmp_path, endpoint, good)
        refused(endpoint, wrong)
        refused(endpoint, anonymous)
    finally:
        router.close()


def test_only_the_resource_serves_and_publishes_its_keys(tmp_path: Path) -> None:
    """The shipped access-control configuration (docs/examples/zenoh-router-acl.json5):
    a PADT user on the bus cannot answer for the resource or publish as it; a user of no
    subject gets nothing through at all; the resource and the PADT work as ever."""
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    users = tmp_path / "users.txt"
    users.write_text("Tank1:Res-secret-1\nengineer:Eng-secret-2\nintruder:Bad-secret-3\n")
    shipped = (REPO / "docs" / "examples" / "zenoh-router-acl.json5").read_text()
    router_config = config(
        tmp_path / "router.json5", shipped.replace("/etc/padt/zenoh-users.txt", str(users))
    )
    credentials = {
        name: config(
            tmp_path / f"{name}.json5",
            f'{{transport: {{auth: {{usrpwd: {{user: "{name}", password: "{secret}"}}}}}}}}',
        )
        for name, secret in (("Tank1", "Res-secret-1"), ("engineer", "Eng-secret-2"))
    }
    intruder = config(
        tmp_path / "intruder.json5",
        '{transport: {auth: {usrpwd: {user: "intruder", password: "Bad-secret-3"}}}}',
    )
    write_demo_artifact(tmp_path / "state")
    router = open_router(endpoint, router_config)
    try:
        with runtime_process(
            "Tank1", tmp_path / "state", endpoint, "--zenoh-config", str(credentials["Tank1"])
        ):
            rogue = open_client(endpoint, credentials["engineer"])
            stranger = open_client(endpoint, intruder)
            victim = open_client(endpoint, credentials["engineer"])
            try:
                answered: list[str] = []
                rogue.declare_queryable(command_key("Tank1"), lambda q: answered.append("rogue"))
                client = ResourceClient(victim, "Tank1")
                wait_until_answering(client)
                seen: list[str] = []
                client.on_status(lambda status: seen.append(status.state))
                for forger in (rogue, stranger):
                    forger.put(status_key("Tank1"), json.dumps({"state": "FORGED"}))
                shown = padt(
                    "status", "--resource", "Tank1", "--zenoh", endpoint,
                    "--zenoh-config", str(credentials["engineer"]),
                )  # fmt: skip
                assert shown.returncode == 0, shown.stderr
                assert "resource Tank1: RUN" in shown.stdout
                time.sleep(1.5)  # a status a second from the resource
                assert answered == [], "a PADT user answered for the resource"
                assert seen and set(seen) == {"RUN"}
                # a user of no subject reaches nothing
                replies = list(stranger.get(command_key("Tank1"), payload=b"{}", timeout=1))
                assert not [r for r in replies if r.ok is not None]
            finally:
                for session in (rogue, stranger, victim):
                    session.close()
    finally:
        router.close()
