"""A runtime process serves its variables over OPC UA, reached by asyncua clients on
127.0.0.1: the address space mirrors the configuration, values follow the cycle, writes
are online writes with the user's level checked and the event naming the user, and who
may not get in does not: a session on a channel without security (even with the right
password), an unknown client certificate (until it is trusted), a wrong password.

node-opcua, a client nobody here wrote, checks the same server in test_opcua_interop.py.
"""

from __future__ import annotations

import asyncio
import hashlib
import shutil
import socket
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any

import pytest
from asyncua import ua
from asyncua.client.client import Client
from asyncua.crypto.cert_gen import setup_self_signed_certificate
from asyncua.ua.attribute_ids import AttributeIds
from asyncua.ua.uaerrors import UaStatusCodeError
from cryptography.x509.oid import ExtendedKeyUsageOID

from backend.engineering.project import compile_project, load_project, user_entry
from backend.engineering.resource_client import ResourceClient
from runtime.contract.accounts import hash_password
from runtime.contract.artifact import UserAccount
from runtime.contract.protocol import GetEvents, GetIo, GetValues
from tests.conftest import free_port, padt
from tests.support.runtime_process import running_resource, store_artifact, wait_for

PASSWORD = "opc-ua-test"
SOURCE = """TYPE Point : STRUCT
  x : REAL;  (* across *)
  y : REAL;
END_STRUCT END_TYPE

PROGRAM Main
VAR
  count : DINT;            (* cycles counted *)
  setpoint : INT := 10;    (* operators set this *)
  limit : INT := 100;
  label : STRING[16] := 'idle';
  history : ARRAY[1..3] OF INT := [1, 2, 3];
  delay : TON;
  origin : Point;
  corners : ARRAY[1..2] OF Point;
END_VAR
count := count + 1;
delay(IN := TRUE, PT := T#1h);
END_PROGRAM

VAR_GLOBAL
  gLevel : REAL := 1.5;
  gHidden : INT;
END_VAR
"""

SETTINGS = """[resource]
name = "Ua1"
target_cycle_ms = 10
autostart = "cold"
safety_operation = false

[opcua]
expose = ["Main", "gLevel"]
writable = ["Main.setpoint", "Main.label", "Main.history"]
"""


@dataclass(frozen=True)
class Served:
    url: str
    client: ResourceClient  # over Zenoh, logged in as the administrator
    pki: Path  # the server's trust list
    certificate: Path  # a client certificate the server trusts
    key: Path
    project: Path  # its project folder
    zenoh: str  # the router's endpoint
    port: int  # the OPC UA server's
    pid: int  # the runtime's process


def client_certificate(folder: Path, name: str) -> tuple[Path, Path]:
    cert, key = folder / f"{name}.der", folder / f"{name}.pem"
    asyncio.run(
        setup_self_signed_certificate(
            key,
            cert,
            f"urn:padt-test:{name}",
            socket.gethostname(),
            [ExtendedKeyUsageOID.CLIENT_AUTH],
            {"commonName": name},
        )
    )
    return cert, key


def thumbprint(cert: Path) -> str:
    return hashlib.sha1(cert.read_bytes()).hexdigest().upper()


@pytest.fixture(scope="module")
def served(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Served]:
    with serving(tmp_path_factory.mktemp("opcua")) as server:
        yield server


@contextmanager
def serving(tmp: Path, log: IO[bytes] | None = None) -> Iterator[Served]:
    """The runtime of SOURCE serving OPC UA, with its files in `tmp` and its log to `log`."""
    accounts = [
        UserAccount("admin", "administrator", hash_password(PASSWORD)),
        UserAccount("op", "operator", hash_password(PASSWORD)),
        UserAccount("viewer", "read", hash_password(PASSWORD)),
    ]
    folder = tmp / "project"
    folder.mkdir()
    users = "".join("\n" + user_entry(a) for a in accounts)
    (folder / "padt.toml").write_text(SETTINGS + users)
    (folder / "main.st").write_text(SOURCE)
    result = compile_project(load_project([folder]))
    assert result.artifact is not None, result.diagnostics
    state = tmp / "state"
    store_artifact(state, result.artifact)
    cert, key = client_certificate(tmp, "trusted")
    trusted = state / "opcua" / "pki" / "trusted"
    trusted.mkdir(parents=True)
    shutil.copy(cert, trusted / f"{thumbprint(cert)}.der")
    port = free_port()
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    opcua = ("--opcua-port", str(port))
    with running_resource("Ua1", state, endpoint, *opcua, log=log) as (process, client):
        client.login("admin", PASSWORD)
        url = f"opc.tcp://127.0.0.1:{port}/"
        wait_for("the server listens", lambda: listening(client))
        yield Served(
            url, client, state / "opcua" / "pki", cert, key, folder, endpoint, port, process.pid
        )


def listening(client: ResourceClient) -> bool:
    io = client.ask(GetIo()).io
    return io is not None and any(s.protocol == "opcua" and s.listening for s in io.servers)


async def connected(
    served: Served, user: str | None, cert: Path | None = None, key: Path | None = None
) -> Client:
    client = Client(served.url, timeout=10)
    name = (cert or served.certificate).stem
    client.application_uri = f"urn:padt-test:{name}"
    chain = f"{cert or served.certificate},{key or served.key}"
    await client.set_security_string(f"Basic256Sha256,SignAndEncrypt,{chain}")
    if user is not None:
        client.set_user(user)
        client.set_password(PASSWORD)
    await client.connect()
    return client


def run(work: Callable[[], Any]) -> Any:
    return asyncio.run(work())


def node(path: str) -> str:
    return f"ns=2;s=Ua1.{path}"


def events(served: Served) -> list[tuple[str, str, str | None]]:
    return [(e.kind, e.message, e.user) for e in served.client.ask(GetEvents(limit=500)).events]


def test_the_address_space_mirrors_the_configuration(served: Served) -> None:
    async def browse() -> dict[str, Any]:
        client = await connected(served, "viewer")
        try:
            main = client.get_node(node("Main"))
            seen: dict[str, Any] = {}
            for child in await main.get_children():
                name = (await child.read_browse_name()).Name
                if await child.read_node_class() == ua.NodeClass.Object:
                    members = [
                        (await m.read_browse_name()).Name for m in await child.get_children()
                    ]
                    seen[name] = sorted(members)
                else:
                    seen[name] = await child.read_data_value()
            seen["gLevel"] = await client.get_node(node("gLevel")).read_data_value()
            corner = client.get_node(node("Main.corners[2].x"))
            seen["corner"] = ((await corner.read_description()).Text, await corner.read_value())
            seen["description"] = (
                await client.get_node(node("Main.setpoint")).read_description()
            ).Text
            resource = [
                (await c.read_browse_name()).Name
                for c in await client.get_node("ns=2;s=Ua1").get_children()
            ]
            seen["resource"] = sorted(resource)
            return seen
        finally:
            await client.disconnect()

    seen = run(browse)
    assert seen["resource"] == ["Main", "gLevel"]  # gHidden is not exposed
    assert {"ET", "IN", "PT", "Q"} <= set(seen["delay"])  # a function block: an object
    assert seen["origin"] == ["x", "y"]
    assert seen["description"] == "operators set this"
    assert seen["corners"] == ["[1]", "[2]"]  # an array of structures: an object per element
    assert seen["corner"] == ("across", 0.0)  # described as the structure's member is
    label, history = seen["label"].Value, seen["history"].Value
    assert (label.Value, label.VariantType) == ("idle", ua.VariantType.String)
    assert (history.Value, history.VariantType) == ([1, 2, 3], ua.VariantType.Int16)
    assert seen["setpoint"].Value.VariantType == ua.VariantType.Int16
    assert seen["count"].Value.VariantType == ua.VariantType.Int32
    assert seen["count"].SourceTimestamp is not None
    assert seen["gLevel"].Value.Value == 1.5


def test_a_subscription_sees_the_count_move(served: Served) -> None:
    async def watch() -> list[int]:
        client = await connected(served, "viewer")
        seen: list[int] = []

        class Handler:
            def datachange_notification(self, node: Any, value: int, data: Any) -> None:
                seen.append(value)

        try:
            subscription = await client.create_subscription(50, Handler())
            await subscription.subscribe_data_change(client.get_node(node("Main.count")))
            for _ in range(100):
                if len(seen) >= 3:
                    break
                await asyncio.sleep(0.1)
            return seen
        finally:
            await client.disconnect()

    seen = run(watch)
    assert len(seen) >= 3 and seen == sorted(seen) and seen[0] < seen[-1]


def test_an_operator_writes_what_is_writable_and_the_event_names_them(served: Served) -> None:
    async def write(user: str, path: str, value: Any, kind: ua.VariantType) -> str:
        client = await connected(served, user)
        try:
            target = client.get_node(node(path))
            variant = ua.Variant(value, kind)
            status = (
                await client.uaclient.write_attributes([target.nodeid], [ua.DataValue(variant)])
            )[0]
            return status.name
        finally:
            await client.disconnect()

    async def user_access(user: str, path: str) -> int:
        client = await connected(served, user)
        try:
            found = await client.get_node(node(path)).read_attribute(AttributeIds.UserAccessLevel)
            return int(found.Value.Value) if found.Value is not None else -1
        finally:
            await client.disconnect()

    Int16, String = ua.VariantType.Int16, ua.VariantType.String
    assert run(lambda: write("op", "Main.setpoint", 42, Int16)) == "Good"
    assert run(lambda: write("op", "Main.label", "running", String)) == "Good"
    # named writable, but an online write takes elementary values: arrays are read-only
    assert run(lambda: write("op", "Main.history", [7, 8, 9], Int16)) == "BadNotWritable"
    assert run(lambda: write("viewer", "Main.setpoint", 1, Int16)) == "BadUserAccessDenied"
    assert run(lambda: write("op", "Main.limit", 1, Int16)) == "BadNotWritable"
    assert run(lambda: write("op", "Main.setpoint", "x", String)) == "BadTypeMismatch"
    assert run(lambda: write("op", "Main.label", "x" * 17, String)) == "BadOutOfRange"
    assert run(lambda: user_access("op", "Main.setpoint")) == 3  # CurrentRead | CurrentWrite
    assert run(lambda: user_access("viewer", "Main.setpoint")) == 1  # CurrentRead
    written = [e for e in events(served) if e[0] == "write"]
    assert ("write", "Main.setpoint written: 10 -> 42", "op") in written
    assert ("write", "Main.label written: 'idle' -> 'running'", "op") in written
    assert not any(e[2] == "viewer" for e in written)
    values = served.client.ask(GetValues()).values
    assert (values["Main.setpoint"], values["Main.history"]) == (42, [1, 2, 3])


def test_a_session_without_security_is_refused_even_with_the_right_password(
    served: Served,
) -> None:
    """asyncua opens a channel without security for discovery; a session on it would carry
    the password in clear, so the server refuses it whatever the password."""

    async def probe() -> tuple[str, str]:
        client = Client(served.url, timeout=10)
        await client.connect_socket()
        try:
            await client.send_hello()
            await client.open_secure_channel()  # security None: what discovery uses
            session = ua.CreateSessionParameters()
            session.ClientDescription = ua.ApplicationDescription()
            session.ClientNonce = b"n" * 32
            session.EndpointUrl = served.url
            session.SessionName = "probe"
            session.RequestedSessionTimeout = 60_000
            await client.uaclient.create_session(session)
            token = ua.UserNameIdentityToken()
            token.UserName, token.Password = "op", PASSWORD.encode()  # in clear
            token.PolicyId = "username"
            activation = ua.ActivateSessionParameters()
            activation.UserIdentityToken = token
            try:
                await client.uaclient.activate_session(activation)
                activated = "Good"
            except UaStatusCodeError as exc:
                activated = type(exc).__name__
            try:
                await client.get_node(node("Main.setpoint")).read_value()
                read = "Good"
            except UaStatusCodeError as exc:
                read = type(exc).__name__
            return activated, read
        finally:
            client.disconnect_socket()

    activated, read = run(probe)
    assert activated == "BadUserAccessDenied"
    assert read == "BadSessionNotActivated"


def test_anonymous_and_a_wrong_password_are_refused(served: Served) -> None:
    async def attempt(user: str | None, password: str) -> str:
        client = Client(served.url, timeout=10)
        client.application_uri = "urn:padt-test:trusted"
        await client.set_security_string(
            f"Basic256Sha256,SignAndEncrypt,{served.certificate},{served.key}"
        )
        if user is not None:
            client.set_user(user)
            client.set_password(password)
        try:
            await client.connect()
        except UaStatusCodeError as exc:
            return type(exc).__name__
        await client.disconnect()
        return "Good"

    assert run(lambda: attempt(None, "")) == "BadIdentityTokenRejected"
    assert run(lambda: attempt("op", "wrong")) == "BadUserAccessDenied"
    assert run(lambda: attempt("nobody", PASSWORD)) == "BadUserAccessDenied"
    # recorded by the cycle thread at its next cycle
    wait_for(
        "the refusal is an event",
        lambda: any("OPC UA login of 'op' refused" in e[1] for e in events(served)),
    )


def test_an_unknown_certificate_is_refused_until_it_is_trusted(
    served: Served, tmp_path: Path
) -> None:
    cert, key = client_certificate(tmp_path, "newcomer")
    name = f"{thumbprint(cert)}.der"

    async def attempt() -> str:
        try:
            client = await connected(served, "viewer", cert, key)
        except UaStatusCodeError as exc:
            return type(exc).__name__
        await client.disconnect()
        return "Good"

    assert run(attempt) == "BadSecurityChecksFailed"
    rejected = served.pki / "rejected" / name
    assert rejected.is_file()
    wait_for(
        "the refusal is an event",
        lambda: any(thumbprint(cert) in e[1] and "refused" in e[1] for e in events(served)),
    )
    rejected.rename(served.pki / "trusted" / name)  # what an engineer does to trust it
    assert run(attempt) == "Good"


def test_an_online_change_adds_nodes_and_keeps_the_subscriptions(served: Served) -> None:
    """Last in the module: it changes the served configuration."""

    async def across_the_reload() -> tuple[list[int], Any]:
        client = await connected(served, "viewer")
        seen: list[int] = []

        class Handler:
            def datachange_notification(self, node: Any, value: int, data: Any) -> None:
                seen.append(value)

        try:
            subscription = await client.create_subscription(50, Handler())
            await subscription.subscribe_data_change(client.get_node(node("Main.count")))
            source = (served.project / "main.st").read_text()
            changed = source.replace(
                "  limit : INT := 100;", "  limit : INT := 100;\n  added : INT := 5;"
            )
            (served.project / "main.st").write_text(changed)
            online = ["--resource", "Ua1", "--zenoh", served.zenoh, "--user", "admin"]
            reload = await asyncio.to_thread(
                padt, "reload", str(served.project), *online, "--yes",
                env={"PADT_PASSWORD": PASSWORD},
            )  # fmt: skip
            assert reload.returncode == 0, reload.stdout + reload.stderr
            before = len(seen)
            for _ in range(100):  # the subscription goes on after the switch-over
                if len(seen) >= before + 3:
                    break
                await asyncio.sleep(0.1)
            added = None
            for _ in range(100):  # the new variable's node, built after the switch-over
                try:
                    added = await client.get_node(node("Main.added")).read_value()
                    if added is not None:
                        break
                except UaStatusCodeError:
                    pass
                await asyncio.sleep(0.1)
            return seen[before:], added
        finally:
            await client.disconnect()

    after, added = run(across_the_reload)
    assert len(after) >= 3 and after == sorted(after), (  # a warm change: the count goes on
        after,
        served.client.ask(GetValues()).values["Main.count"],
        events(served)[-8:],
    )
    assert added == 5
