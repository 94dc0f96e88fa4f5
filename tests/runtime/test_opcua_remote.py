"""A remote OPC UA server as remote I/O (runtime/field_io/opcua/remote.py): a plain asyncua
server on its own event loop thread, with Basic256Sha256 endpoints and a user manager, and a
`RemoteServer` on another (as on the runtime's I/O thread) read from the test's thread (as
the cycle reads it). Values arrive subscribed and read, outputs are written, a wrong
password and a password file others may read are refused, and a server that stops is lost
(safe values, marked bad) until it runs again on the same port."""

from __future__ import annotations

import asyncio
import os
import socket
import threading
import time
from collections.abc import Callable, Coroutine, Iterator
from concurrent.futures import Future
from dataclasses import replace
from pathlib import Path
from typing import Any, TypeVar

import pytest
from asyncua import ua
from asyncua.crypto.cert_gen import setup_self_signed_certificate
from asyncua.crypto.permission_rules import User, UserRole
from asyncua.server.server import Server
from cryptography.x509.oid import ExtendedKeyUsageOID

from runtime.contract.opcua import OpcuaDevice, OpcuaPoint
from runtime.field_io.opcua.remote import (
    CERTIFICATE,
    PRIVATE_KEY,
    Refused,
    RemoteServer,
    client_certificate,
    read_password,
)
from tests.support.ports import free_port

T = TypeVar("T")
USER, PASSWORD = "operator", "s3cret pass"
URI = "urn:padt:test:remote-server"
NS = "urn:padt:test:plant"

# node, variant type, initial value
NODES: dict[str, tuple[ua.VariantType, Any]] = {
    "level": (ua.VariantType.Int16, 42),
    "flow": (ua.VariantType.Float, 2.5),
    "ready": (ua.VariantType.Boolean, True),
    "label": (ua.VariantType.String, "tank 1"),
    "delay": (ua.VariantType.Double, 1500.0),  # a Duration, in ms
    "huge": (ua.VariantType.Int32, 100_000),  # more than an INT holds
    "speed": (ua.VariantType.Int16, 0),
    "pump": (ua.VariantType.Boolean, False),
    "setpoint": (ua.VariantType.Float, 0.0),
}
INPUTS = (
    OpcuaPoint("level", "%IW0", "INT", "ns=2;s=level", safe_value=-1),
    OpcuaPoint("flow", "%ID1", "REAL", "ns=2;s=flow", safe_value=0.0),
    OpcuaPoint("ready", "%IX0.0", "BOOL", "ns=2;s=ready", safe_value=False),
    OpcuaPoint("label", "%ID2", "STRING", "ns=2;s=label", safe_value="lost"),
    OpcuaPoint("delay", "%ID3", "TIME", "ns=2;s=delay", safe_value=0),
)
OUTPUTS = (
    OpcuaPoint("speed", "%QW0", "INT", "ns=2;s=speed"),
    OpcuaPoint("pump", "%QX0.0", "BOOL", "ns=2;s=pump"),
    OpcuaPoint("setpoint", "%QD1", "REAL", "ns=2;s=setpoint"),
)
ARRIVED = {"level": 42, "flow": 2.5, "ready": True, "label": "tank 1", "delay": 1_500_000_000}
SAFE = {"level": -1, "flow": 0.0, "ready": False, "label": "lost", "delay": 0}


class Users:
    """One user with a password; anonymous sessions may read and write too."""

    def get_user(
        self, iserver: Any, username: str | None = None, password: str | None = None,
        certificate: Any = None,
    ) -> User | None:  # fmt: skip
        if username is None or (username, password) == (USER, PASSWORD):
            return User(role=UserRole.User, name=username)
        return None


class Loop:
    """An event loop on a thread of its own."""

    def __init__(self) -> None:
        self.loop = asyncio.new_event_loop()
        self._thread = threading.Thread(target=self.loop.run_forever, daemon=True)
        self._thread.start()

    def call(self, coroutine: Coroutine[Any, Any, T], timeout_s: float = 30) -> T:
        return asyncio.run_coroutine_threadsafe(coroutine, self.loop).result(timeout_s)

    def close(self) -> None:
        """Cancel what still runs on it (asyncua's servers leave tasks behind), and stop."""
        self.call(_cancel_all())
        self.loop.call_soon_threadsafe(self.loop.stop)
        self._thread.join(10)
        self.loop.close()


async def _cancel_all() -> None:
    tasks = [t for t in asyncio.all_tasks() if t is not asyncio.current_task()]
    for task in tasks:
        task.cancel()
    await asyncio.gather(*tasks, return_exceptions=True)


class PlantServer:
    """A plain asyncua server on 127.0.0.1:`port` holding NODES in namespace 2."""

    def __init__(self, loop: Loop, pki: Path, port: int) -> None:
        self._loop, self.port = loop, port
        self.server = Server(user_manager=Users())  # type: ignore[arg-type]
        loop.call(self._start(pki))

    async def _start(self, pki: Path) -> None:
        server = self.server
        await server.init()
        server.set_endpoint(f"opc.tcp://127.0.0.1:{self.port}")
        await server.set_application_uri(URI)
        server.set_security_policy(
            [
                ua.SecurityPolicyType.NoSecurity,
                ua.SecurityPolicyType.Basic256Sha256_Sign,
                ua.SecurityPolicyType.Basic256Sha256_SignAndEncrypt,
            ]
        )
        server.set_identity_tokens([ua.AnonymousIdentityToken, ua.UserNameIdentityToken])
        await server.load_certificate(pki / "server.der")
        await server.load_private_key(pki / "server.pem")
        namespace = await server.register_namespace(NS)
        assert namespace == 2
        for name, (kind, value) in NODES.items():
            node = await server.nodes.objects.add_variable(
                ua.NodeId(ua.String(name), ua.Int16(namespace)), name, ua.Variant(value, kind)
            )
            await node.set_writable()
        await server.start()

    def read(self, name: str) -> Any:
        return self._loop.call(self.server.get_node(f"ns=2;s={name}").read_value())

    def write(self, name: str, value: Any) -> None:
        variant = ua.Variant(value, NODES[name][0])
        self._loop.call(self.server.get_node(f"ns=2;s={name}").write_value(variant))

    def reset(self) -> None:
        for name, (_kind, value) in NODES.items():
            self.write(name, value)

    def stop(self) -> None:
        self._loop.call(self.server.stop())


class Running:
    """A RemoteServer running on a loop of its own, until `stop`."""

    def __init__(self, device: OpcuaDevice, pki: Path) -> None:
        self.outputs: dict[str, Any] = {}
        self.remote = RemoteServer(device, lambda: self.outputs, pki)
        self._loop = Loop()
        self._task: Future[None] = asyncio.run_coroutine_threadsafe(
            self.remote.run(), self._loop.loop
        )

    def stop(self) -> None:
        """Cancelled as the driver stops it: run() ends, with its client closed."""
        self._loop.close()
        assert self._task.cancelled()


def until(check: Callable[[], Any], what: str, timeout_s: float = 15.0) -> Any:
    deadline = time.monotonic() + timeout_s
    while True:
        found = check()
        if found:
            return found
        if time.monotonic() > deadline:
            raise AssertionError(f"not within {timeout_s} s: {what}")
        time.sleep(0.02)


@pytest.fixture(scope="module")
def pki(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("pki")
    asyncio.run(
        setup_self_signed_certificate(
            folder / "server.pem", folder / "server.der", URI, socket.gethostname(),
            [ExtendedKeyUsageOID.SERVER_AUTH, ExtendedKeyUsageOID.CLIENT_AUTH], {},
        )
    )  # fmt: skip
    return folder


@pytest.fixture(scope="module")
def server_loop() -> Iterator[Loop]:
    loop = Loop()
    yield loop
    loop.close()


@pytest.fixture(scope="module")
def shared_plant(server_loop: Loop, pki: Path) -> Iterator[PlantServer]:
    server = PlantServer(server_loop, pki, free_port())
    yield server
    server.stop()


@pytest.fixture
def plant(shared_plant: PlantServer) -> PlantServer:
    shared_plant.reset()
    return shared_plant


@pytest.fixture
def password_file(tmp_path: Path) -> Path:
    path = tmp_path / "password"
    path.write_text(PASSWORD + "\n")
    path.chmod(0o600)
    return path


@pytest.fixture
def running() -> Iterator[Callable[[OpcuaDevice, Path], Running]]:
    started: list[Running] = []

    def start(device: OpcuaDevice, pki: Path) -> Running:
        started.append(Running(device, pki))
        return started[-1]

    yield start
    for one in started:
        one.stop()


def device(port: int, **changes: Any) -> OpcuaDevice:
    made = OpcuaDevice(
        "plant", f"opc.tcp://127.0.0.1:{port}", period_ms=50, timeout_ms=1000,
        points=INPUTS + OUTPUTS,
    )  # fmt: skip
    return replace(made, **changes)


def test_subscribed_values_arrive_and_outputs_are_written(
    plant: PlantServer, pki: Path, password_file: Path,
    running: Callable[[OpcuaDevice, Path], Running],
) -> None:  # fmt: skip
    config = device(
        plant.port, security="sign_encrypt", user=USER, password_file=str(password_file)
    )
    run = running(config, pki / "client")
    remote = run.remote
    until(lambda: remote.state == "connected", "connected")
    assert remote.delivery.good and remote.delivery.values == ARRIVED
    assert remote.last_error is None
    # the client's certificate: made once, its key owner-only
    assert (pki / "client" / "client-private-key.pem").stat().st_mode & 0o777 == 0o600

    plant.write("level", 43)
    plant.write("label", "tank 2")
    until(lambda: remote.delivery.values["level"] == 43, "a data change delivered")
    until(lambda: remote.delivery.values["label"] == "tank 2", "a string delivered")
    assert remote.delivery.good and remote.delivery.values["flow"] == 2.5

    run.outputs = {"speed": 120, "pump": True, "setpoint": 1.5}
    until(lambda: remote.sent == {"speed": 120, "pump": True, "setpoint": 1.5}, "written")
    assert (plant.read("speed"), plant.read("pump"), plant.read("setpoint")) == (120, True, 1.5)
    run.outputs = {"speed": -7, "pump": True, "setpoint": 1.5}  # one changed: it goes again
    until(lambda: plant.read("speed") == -7, "a changed output written")
    # the server applies a write before it answers; the client notes it on the answer
    until(lambda: remote.sent["speed"] == -7, "the write's answer taken")
    assert remote.sent["speed"] == -7
    assert remote.requests > 0 and remote.round_trip_ms > 0 and remote.failures == 0


def test_read_values_arrive_and_bad_nodes_take_safe_values(
    plant: PlantServer, pki: Path, running: Callable[[OpcuaDevice, Path], Running]
) -> None:
    extra = (
        OpcuaPoint("missing", "%IW8", "INT", "ns=2;s=missing", safe_value=7),
        OpcuaPoint("huge", "%IW9", "INT", "ns=2;s=huge", safe_value=8),
    )
    config = device(plant.port, security="sign", mode="read", points=INPUTS + OUTPUTS + extra)
    run = running(config, pki / "client")
    remote = run.remote
    until(lambda: remote.state == "connected", "connected")
    assert remote.delivery.good
    assert remote.delivery.values == {**ARRIVED, "missing": 7, "huge": 8}
    # either node named, the other counted
    assert remote.last_error is not None
    assert "ns=2;s=huge" in remote.last_error and "(and 1 more)" in remote.last_error

    plant.write("ready", False)
    plant.write("delay", 250.0)
    until(lambda: not remote.delivery.values["ready"], "a polled change delivered")
    until(lambda: remote.delivery.values["delay"] == 250_000_000, "a duration delivered")

    run.outputs = {"speed": 3, "pump": False, "setpoint": -2.25}
    until(lambda: plant.read("setpoint") == -2.25, "written")
    assert remote.sent == {"speed": 3, "pump": False, "setpoint": -2.25}


def test_a_wrong_password_is_refused(
    plant: PlantServer, pki: Path, tmp_path: Path,
    running: Callable[[OpcuaDevice, Path], Running],
) -> None:  # fmt: skip
    wrong = tmp_path / "wrong"
    wrong.write_text("not the password\n")
    wrong.chmod(0o600)
    config = device(plant.port, security="sign_encrypt", user=USER, password_file=str(wrong))
    remote = running(config, pki / "client").remote
    until(lambda: remote.state == "lost", "lost")
    assert remote.last_error is not None
    assert f"refused user '{USER}'" in remote.last_error
    assert "BadUserAccessDenied" in remote.last_error
    assert not remote.delivery.good and remote.delivery.values == SAFE
    assert remote.sent == {}


def test_a_password_file_others_may_read_is_refused(
    plant: PlantServer, pki: Path, password_file: Path,
    running: Callable[[OpcuaDevice, Path], Running],
) -> None:  # fmt: skip
    password_file.chmod(0o644)
    config = device(plant.port, security="none", user=USER, password_file=str(password_file))
    remote = running(config, pki / "client").remote
    until(lambda: remote.state == "lost", "lost")
    assert remote.last_error is not None
    assert str(password_file) in remote.last_error and "0644" in remote.last_error
    assert remote.requests == 0  # the server was never asked
    password_file.chmod(0o600)  # taken at the next attempt, without a restart
    until(lambda: remote.state == "connected", "connected")
    assert remote.delivery.values == ARRIVED


def test_a_stopped_server_is_lost_until_it_runs_again(
    server_loop: Loop, pki: Path, password_file: Path,
    running: Callable[[OpcuaDevice, Path], Running],
) -> None:  # fmt: skip
    port = free_port()
    first = PlantServer(server_loop, pki, port)
    config = device(port, security="sign_encrypt", user=USER, password_file=str(password_file))
    run = running(config, pki / "client")
    remote = run.remote
    run.outputs = {"speed": 5, "pump": True, "setpoint": 0.5}
    until(lambda: remote.state == "connected" and remote.sent.get("speed") == 5, "connected")
    assert remote.delivery.good and remote.delivery.values == ARRIVED

    first.stop()
    until(lambda: remote.state == "lost", "lost")
    assert not remote.delivery.good and remote.delivery.values == SAFE
    assert remote.failures >= 1 and remote.last_error
    assert remote.sent == {}

    second = PlantServer(server_loop, pki, port)
    try:
        second.write("level", 99)
        until(lambda: remote.state == "connected", "connected again", timeout_s=20)
        until(lambda: remote.delivery.values["level"] == 99, "values again")
        assert remote.delivery.good
        until(lambda: second.read("speed") == 5, "the outputs written again")
    finally:
        second.stop()


def test_what_makes_a_password_file_usable(tmp_path: Path) -> None:
    def password(data: bytes | None, mode: int = 0o600) -> str:
        path = tmp_path / "password"
        if data is not None:
            path.write_bytes(data)
            path.chmod(mode)
        return read_password(device(1, user=USER, password_file=str(path)))

    assert password(b"secret\n") == "secret"
    assert password(b"secret\r\n") == "secret"
    assert password(b"secret\n\n") == "secret\n"  # one newline only
    assert password(b"secret", 0o400) == "secret"
    assert password(b"x" * 1024) == "x" * 1024
    for data, mode, said in [
        (b"x" * 1025, 0o600, "larger than 1024 bytes"),
        (b"secret", 0o640, "mode 0640"),
        (b"secret", 0o700, "mode 0700"),
        (b"\xff", 0o600, "not UTF-8"),
    ]:
        with pytest.raises(Refused, match=said):
            password(data, mode)
    (tmp_path / "password").unlink()
    with pytest.raises(Refused, match="No such file"):
        password(None)
    os.mkfifo(tmp_path / "password", 0o600)  # never blocks: refused at once
    with pytest.raises(Refused, match="not a regular file"):
        password(None)
    with pytest.raises(Refused, match="no password file"):
        read_password(device(1, user=USER))


def test_the_client_certificate_is_made_once(tmp_path: Path) -> None:
    from cryptography import x509

    certificate, key = client_certificate(tmp_path / "pki", "urn:padt:a:client", "a")
    assert (certificate.name, key.name) == (CERTIFICATE, PRIVATE_KEY)
    assert key.stat().st_mode & 0o777 == 0o600
    made = certificate.read_bytes()
    found = x509.load_der_x509_certificate(made)
    names = found.extensions.get_extension_for_class(x509.SubjectAlternativeName).value
    assert names.get_values_for_type(x509.UniformResourceIdentifier) == ["urn:padt:a:client"]
    usage = found.extensions.get_extension_for_class(x509.ExtendedKeyUsage).value
    assert list(usage) == [x509.oid.ExtendedKeyUsageOID.CLIENT_AUTH]
    assert client_certificate(tmp_path / "pki", "urn:padt:a:client", "a")[0].read_bytes() == made
    # another application URI (the host was renamed): a new one
    client_certificate(tmp_path / "pki", "urn:padt:b:client", "b")
    assert certificate.read_bytes() != made
