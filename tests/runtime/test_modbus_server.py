"""A runtime process serves its process image over Modbus TCP (OpenPLC's map), read and
written by real pymodbus clients on 127.0.0.1: every table and encoding, the configured
writable points only, safe values in STOP, exception responses for what is wrong, and
malformed frames that leave the cycle untouched."""

from __future__ import annotations

import contextlib
import json
import os
import re
import shutil
import socket
import struct
import subprocess
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any, NamedTuple

import pytest
from pymodbus.client import ModbusTcpClient

from backend.compiler.pipeline import compile_sources
from backend.compiler.source import SourceFile
from backend.engineering.project import compile_project, load_project
from backend.engineering.resource_client import ResourceClient
from runtime.clock import RealClock, VirtualClock
from runtime.contract.artifact import Artifact, ResourceConfig
from runtime.contract.protocol import GetEvents, GetIo, GetStatus, GetValues, ResourceState, Stop
from runtime.contract.protocol import Write as WriteValue
from runtime.field_io import FieldIo
from runtime.resource import Resource
from tests.conftest import free_port, padt
from tests.support.modbus_device import modbus_client
from tests.support.resource_harness import OPEN_RESOURCE, Harness
from tests.support.runtime_process import running_resource, store_artifact

SOURCE = """VAR_GLOBAL
  run AT %IX0.1 : BOOL;
  lamp AT %QX0.2 : BOOL;
  level AT %IW0 : INT;
  speed AT %QW1 : INT;
  setpoint AT %MW0 : INT;
  gain AT %MD0 : REAL;
  total AT %MD1 : DINT;
  word AT %MW2 : WORD;
END_VAR
PROGRAM Main
lamp := run;
speed := setpoint * 2;
total := 70000 + setpoint;
END_PROGRAM
"""

SETTINGS = """[resource]
name = "Mb1"
target_cycle_ms = 10
autostart = "cold"
safety_operation = false

[modbus]
writable = ["%MW0", "%MD0", "%MW2", "%QX0.2"]
word_order = "{word_order}"
"""


def wait_for(check: Callable[[], Any], timeout_s: float = 10.0) -> Any:
    deadline = time.monotonic() + timeout_s
    while True:
        result = check()
        if result:
            return result
        if time.monotonic() > deadline:
            raise AssertionError(f"not within {timeout_s} s: {check}")
        time.sleep(0.02)


def listening_port(client: ResourceClient) -> int:
    def port() -> int:
        io = client.ask(GetStatus()).status.io
        return io.server.port if io is not None and io.server is not None else 0

    result: int = wait_for(port)
    return result


class Served(NamedTuple):
    client: ResourceClient
    modbus: ModbusTcpClient
    word_order: str
    endpoint: str  # the Zenoh router's


@pytest.fixture(params=["big", "little"])
def served(request: pytest.FixtureRequest, tmp_path: Path) -> Iterator[Served]:
    folder = tmp_path / "project"
    folder.mkdir()
    (folder / "padt.toml").write_text(SETTINGS.format(word_order=request.param))
    (folder / "main.st").write_text(SOURCE)
    result = compile_project(load_project([folder]))
    assert result.artifact is not None, result.diagnostics
    state = tmp_path / "state"
    store_artifact(state, result.artifact)
    port = free_port()
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    with running_resource("Mb1", state, endpoint, "--modbus-port", str(port)) as (_, client):
        assert listening_port(client) == port
        with modbus_client(port) as modbus:
            yield Served(client, modbus, request.param, endpoint)


def value(client: ResourceClient, name: str) -> Any:
    return client.ask(GetValues()).values[name]


def test_every_table_and_encoding(served: Served) -> None:
    client, modbus, word_order, _ = served
    client.ask(WriteValue("run", True))
    client.ask(WriteValue("level", -7))
    # %IX0.1 is discrete input 1, %QX0.2 coil 2 (bit reads come padded to a byte)
    wait_for(lambda: modbus.read_discrete_inputs(0, count=2).bits[:2] == [False, True])
    wait_for(lambda: modbus.read_coils(2, count=1).bits[0] is True)
    # %IW0 is input register 0, as a signed 16-bit value
    wait_for(lambda: modbus.read_input_registers(0, count=1).registers == [0x10000 - 7])
    # %MW0 is holding register 1024, writable: the program doubles it into %QW1
    assert not modbus.write_register(1024, 21).isError()
    wait_for(lambda: modbus.read_holding_registers(1, count=1).registers == [42])
    assert modbus.read_holding_registers(1024, count=1).registers == [21]
    assert value(client, "setpoint") == 21
    # %MD0 (REAL) is holding registers 2048-2049, in the configured word order
    high, low = struct.unpack(">HH", struct.pack(">f", 2.5))
    words = [high, low] if word_order == "big" else [low, high]
    assert not modbus.write_registers(2048, words).isError()
    wait_for(lambda: value(client, "gain") == 2.5)
    assert modbus.read_holding_registers(2048, count=2).registers == words
    # %MD1 (DINT) is holding registers 2050-2051
    high, low = divmod(70021, 0x10000)
    expected = [high, low] if word_order == "big" else [low, high]
    wait_for(lambda: modbus.read_holding_registers(2050, count=2).registers == expected)
    # a WORD takes the whole 16 bits; a coil write reaches its output variable
    assert not modbus.write_register(1026, 0xBEEF).isError()
    wait_for(lambda: value(client, "word") == 0xBEEF)
    assert not modbus.write_coil(2, False).isError()
    assert modbus.read_holding_registers(1026, count=1).registers == [0xBEEF]


def test_what_may_not_be_done_gets_exception_responses(
    served: Served,
) -> None:
    client, modbus, _, _ = served
    cycle = client.ask(GetStatus()).status.cycle
    refused = [
        modbus.write_register(1, 5),  # %QW1 is not writable
        modbus.write_register(3, 5),  # no variable at holding register 3
        modbus.write_coil(0, True),  # nor at coil 0
        modbus.write_registers(1025, [1, 2]),  # 1025 is a gap, 1026 writable: none written
        modbus.read_input_registers(1, count=1),  # beyond the last input register
        modbus.read_holding_registers(2048, count=10),  # past %MD1
        modbus.read_coils(3, count=1),
    ]
    assert [getattr(r, "exception_code", None) for r in refused] == [2] * len(refused)
    assert value(client, "word") == 0 and value(client, "speed") == 0
    # a register between two mapped ones reads 0 rather than failing the whole read
    assert modbus.read_holding_registers(0, count=2).registers == [0, 0]
    io = client.ask(GetIo())
    assert io.io is not None and io.io.server is not None
    assert io.io.server.exceptions == len(refused)
    assert io.io.server.requests >= len(refused) + 1 and io.io.server.writes == 0
    wait_for(lambda: client.ask(GetStatus()).status.cycle > cycle)  # the cycle went on


def _frame(transaction: int, pdu: bytes, unit: int = 1, protocol: int = 0) -> bytes:
    return struct.pack(">HHHB", transaction, protocol, len(pdu) + 1, unit) + pdu


def _answer(sock: socket.socket) -> bytes:
    header = sock.recv(7)
    assert len(header) == 7, header
    length = struct.unpack(">H", header[4:6])[0]
    return header + sock.recv(length - 1)


def test_malformed_frames_and_unknown_function_codes(
    served: Served,
) -> None:
    client, modbus, _, _ = served
    port = modbus.comm_params.port
    with socket.create_connection(("127.0.0.1", port), timeout=3) as sock:
        sock.sendall(_frame(1, bytes([0x41, 0, 0])))  # an unknown function code
        answer = _answer(sock)
        assert answer[7] == 0xC1 and answer[8] == 1  # ILLEGAL FUNCTION
        sock.sendall(_frame(2, bytes([0x03, 0x04, 0x00, 0x00, 0x01])))  # read HR 1024
        answer = _answer(sock)
        assert answer[7:9] == bytes([0x03, 2])  # the connection still works
    garbage = [
        b"\xff" * 300,  # nothing like a frame
        _frame(3, b"\x03\x00", protocol=7),  # another protocol, truncated PDU
        struct.pack(">HHHB", 4, 0, 2000, 1) + b"\x03",  # a length beyond any PDU
        b"\x00\x01",  # a header cut short, then the connection closed
    ]
    for junk in garbage:
        with socket.create_connection(("127.0.0.1", port), timeout=3) as sock:
            sock.sendall(junk)
            sock.settimeout(0.5)
            with contextlib.suppress(TimeoutError, ConnectionResetError):
                sock.recv(512)
    cycle = client.ask(GetStatus()).status.cycle
    wait_for(lambda: client.ask(GetStatus()).status.cycle > cycle + 5)
    assert client.ask(GetStatus()).status.state == ResourceState.RUN
    with modbus_client(port) as again:
        assert again.read_holding_registers(1024, count=1).registers == [0]


def test_stop_serves_the_safe_values(served: Served) -> None:
    client, modbus, _, _ = served
    client.ask(WriteValue("run", True))
    assert not modbus.write_register(1024, 5).isError()
    wait_for(lambda: modbus.read_holding_registers(1, count=1).registers == [10])
    wait_for(lambda: modbus.read_coils(2, count=1).bits[0] is True)
    client.ask(Stop())
    # the outputs are served safe, though the program left them set; memory stays served
    wait_for(lambda: modbus.read_holding_registers(1, count=1).registers == [0])
    assert modbus.read_coils(2, count=1).bits[0] is False
    assert value(client, "speed") == 10
    assert modbus.read_holding_registers(1024, count=1).registers == [5]
    points = {p.variable: p for p in client.ask(GetIo()).points}
    assert (points["speed"].value, points["speed"].quality) == (0, "safe")
    assert (points["setpoint"].value, points["setpoint"].quality) == (5, "good")
    events = [e.message for e in client.ask(GetEvents(limit=1000)).events]
    assert any(m.startswith("Modbus server listening on 127.0.0.1:") for m in events)


def mbpoll(port: int, *args: str, write: str | None = None) -> subprocess.CompletedProcess[str]:
    """Debian's mbpoll (libmodbus), once, zero-based addresses; `write`: a value to write."""
    if shutil.which("mbpoll") is None:
        if os.environ.get("CI") == "true":
            pytest.fail("mbpoll is missing: scripts/install-mbpoll.sh installs it")
        pytest.skip("mbpoll is not installed (scripts/install-mbpoll.sh)")
    command = ["mbpoll", "-m", "tcp", "-p", str(port), "-a", "1", "-0", "-1", *args, "127.0.0.1"]
    command += [write] if write is not None else []
    return subprocess.run(command, capture_output=True, text=True, timeout=30)


def polled(run: subprocess.CompletedProcess[str]) -> dict[int, str]:
    """mbpoll's `[address]: value` lines."""
    assert run.returncode == 0, run.stdout + run.stderr
    found = re.findall(r"^\[(\d+)\]:\s+(.+)$", run.stdout, re.MULTILINE)
    return {int(address): text.strip() for address, text in found}


def test_mbpoll_reads_and_writes_the_image(
    served: Served,
) -> None:
    client, modbus, word_order, _ = served
    port = modbus.comm_params.port
    client.ask(WriteValue("run", True))
    client.ask(WriteValue("level", -7))
    wait_for(lambda: modbus.read_input_registers(0, count=1).registers == [0x10000 - 7])
    wait_for(lambda: modbus.read_coils(2, count=1).bits[0] is True)
    assert polled(mbpoll(port, "-t", "3", "-r", "0", "-c", "1")) == {0: "65529 (-7)"}
    assert polled(mbpoll(port, "-t", "1", "-r", "1", "-c", "1")) == {1: "1"}
    assert polled(mbpoll(port, "-t", "0", "-r", "2", "-c", "1")) == {2: "1"}
    written = mbpoll(port, "-t", "4", "-r", "1024", write="21")
    assert written.returncode == 0 and "Written 1 references" in written.stdout
    wait_for(lambda: modbus.read_holding_registers(1, count=1).registers == [42])
    assert polled(mbpoll(port, "-t", "4", "-r", "1", "-c", "1")) == {1: "42"}
    order = ["-B"] if word_order == "big" else []
    floated = mbpoll(port, "-t", "4:float", *order, "-r", "2048", write="3.75")
    assert floated.returncode == 0, floated.stdout
    wait_for(lambda: client.ask(GetValues()).values["gain"] == 3.75)
    assert polled(mbpoll(port, "-t", "4:float", *order, "-r", "2048", "-c", "1")) == {2048: "3.75"}
    refused = mbpoll(port, "-t", "4", "-r", "1", write="99")  # %QW1 is not writable
    assert refused.returncode != 0 and "Illegal data address" in refused.stdout + refused.stderr


@pytest.mark.parametrize("served", ["big"], indirect=True)  # it shows no word order
def test_padt_status_shows_the_server_and_every_point(served: Served) -> None:
    port = served.modbus.comm_params.port
    base = ["status", "--resource", "Mb1", "--zenoh", served.endpoint]
    shown = padt(*base, "--io")
    assert shown.returncode == 0, shown.stderr
    assert f"Modbus server 127.0.0.1:{port}: " in shown.stdout
    rows = [line.split() for line in shown.stdout.splitlines() if line.startswith("server ")]
    assert [
        "server",
        "setpoint",
        "%MW0",
        "INT",
        "holding_register",
        "1024",
        "yes",
        "0",
        "good",
    ] in rows
    as_json = json.loads(padt(*base, "--io", "--json").stdout)
    assert as_json["io"]["server"]["port"] == port
    assert {p["variable"] for p in as_json["points"]} >= {"run", "lamp", "gain", "total"}


def test_a_busy_port_is_an_event_and_the_resource_runs_on(tmp_path: Path) -> None:
    folder = tmp_path / "project"
    folder.mkdir()
    (folder / "padt.toml").write_text(SETTINGS.format(word_order="big"))
    (folder / "main.st").write_text(SOURCE)
    result = compile_project(load_project([folder]))
    assert result.artifact is not None
    resource = Resource("Mb1", RealClock())
    resource.load(result.artifact)
    resource.start()
    with socket.create_server(("127.0.0.1", 0)) as taken:
        port = taken.getsockname()[1]
        field_io = FieldIo(
            lambda: resource.artifact, resource.variables, resource.io, resource.recorder,
            resource.running, port,
        )  # fmt: skip
        resource.field_io = field_io

        def cycle_until_reported() -> bool:
            field_io.before_cycle()
            resource.cycle()
            field_io.after_cycle()
            return any(e.kind == "io" for e in resource.events.recent(0))

        try:
            wait_for(cycle_until_reported)
        finally:
            field_io.close()
    (event,) = [e for e in resource.events.recent(0) if e.kind == "io"]
    assert event.message.startswith(f"Modbus server: cannot listen on 127.0.0.1:{port}")
    io = resource.status().io
    assert io is not None and io.server is not None
    assert not io.server.listening and io.server.error is not None
    assert resource.state == ResourceState.RUN and resource.cycle_count > 0


def test_a_reload_keeps_serving_and_takes_new_settings() -> None:
    """An online change that changes the Modbus settings restarts the server with them;
    the values carried over are served on."""

    def artifact(writable: list[str], program: str) -> Artifact:
        source = SOURCE.replace("speed := setpoint * 2;", program)
        config = ResourceConfig(name="R", **{**OPEN_RESOURCE, "target_cycle_ms": 10})
        result = compile_sources(
            [SourceFile("main.st", source)], resource=config, modbus={"writable": writable}
        )
        assert result.artifact is not None, result.diagnostics
        return result.artifact

    clock = VirtualClock()
    resource = Resource("R", clock)
    resource.load(artifact(["%MW0"], "speed := setpoint * 2;"))
    resource.start()
    h = Harness(resource, clock, 10_000_000)
    port = free_port()
    field_io = FieldIo(
        lambda: resource.artifact, resource.variables, resource.io, resource.recorder,
        resource.running, port,
    )  # fmt: skip

    def cycled() -> bool:
        field_io.before_cycle()
        h.cycle()
        field_io.after_cycle()
        return True

    def served(check: Callable[[], bool]) -> None:
        wait_for(lambda: cycled() and check())

    try:
        served(lambda: field_io.server is not None and field_io.server.port == port)
        with modbus_client(port) as modbus:
            assert not modbus.write_register(1024, 7).isError()
            served(lambda: modbus.read_holding_registers(1, count=1).registers == [14])
            assert modbus.write_register(1026, 1).exception_code == 2  # %MW2: not writable
        h.send(artifact(["%MW0", "%MW2"], "speed := setpoint * 3;"))
        assert h.cmd("reload")["ok"]
        served(lambda: field_io.server is not None and field_io.server.port == port)
        with modbus_client(port) as modbus:
            served(lambda: modbus.read_holding_registers(1, count=1).registers == [21])
            assert modbus.read_holding_registers(1024, count=1).registers == [7]  # carried
            assert not modbus.write_register(1026, 5).isError()  # writable now
            served(lambda: resource.variables.value("word") == 5)
    finally:
        field_io.close()
