"""A runtime process polls a remote I/O device (a plain pymodbus server in its own process)
as a Modbus TCP client: every table and encoding in both directions; a device killed or
silent is lost (its inputs take their safe values, quality bad, an event says so) and
comes back by itself when it answers again."""

from __future__ import annotations

import json
import socket
import struct
import subprocess
import sys
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import pytest

from backend.engineering.project import compile_project, load_project
from backend.engineering.resource_client import ResourceClient
from runtime.contract.protocol import (
    DeviceStatus,
    GetEvents,
    GetIo,
    GetStatus,
    GetValues,
    ResourceState,
)
from tests.conftest import REPO, free_port
from tests.runtime.test_modbus_server import wait_for
from tests.support.modbus_device import modbus_client, reachable
from tests.support.runtime_process import running_resource, store_artifact

SOURCE = """VAR_GLOBAL
  level AT %IW0 : INT;
  temp AT %IW1 : UINT;
  flow AT %ID1 : REAL;
  count AT %ID2 : DINT;
  ready AT %IX0.0 : BOOL;
  feedback AT %IX0.1 : BOOL;
  pump AT %QX0.0 : BOOL;
  speed AT %QW0 : INT;
  reference AT %QD1 : REAL;
END_VAR
PROGRAM Main
pump := ready AND level > 3;
speed := level * 10;
reference := flow * 2.0;
END_PROGRAM
"""

SETTINGS = """[resource]
name = "Poller"
target_cycle_ms = 10
autostart = "cold"

[modbus]
serve = false

[[modbus.device]]
name = "rack"
host = "127.0.0.1"
port = {port}
period_ms = 50
timeout_ms = 300

[[modbus.device.point]]
variable = "level"
area = "input_register"
address = 0
safe_value = -1

[[modbus.device.point]]
variable = "flow"
area = "input_register"
address = 2
word_order = "little"

[[modbus.device.point]]
variable = "count"
area = "holding_register"
address = 10

[[modbus.device.point]]
variable = "temp"
area = "holding_register"
address = 12
byte_order = "little"

[[modbus.device.point]]
variable = "ready"
area = "discrete_input"
address = 3
safe_value = false

[[modbus.device.point]]
variable = "feedback"
area = "coil"
address = 7

[[modbus.device.point]]
variable = "pump"
area = "coil"
address = 5

[[modbus.device.point]]
variable = "speed"
area = "holding_register"
address = 20

[[modbus.device.point]]
variable = "reference"
area = "holding_register"
address = 21
"""

FLOW = struct.unpack(">HH", struct.pack(">f", 1.25))
INITIAL = {
    "input_register": {"0": 5, "2": FLOW[1], "3": FLOW[0]},  # flow: low word first
    "discrete_input": {"3": True},
}


@contextmanager
def device_process(port: int) -> Iterator[subprocess.Popen[bytes]]:
    command = [sys.executable, "-m", "tests.support.modbus_device", str(port), json.dumps(INITIAL)]
    process = subprocess.Popen(command, cwd=REPO)
    try:
        wait_for(lambda: reachable(port), 20)
        yield process
    finally:
        process.kill()
        process.wait()


@pytest.fixture
def polling(tmp_path: Path) -> Iterator[tuple[ResourceClient, int]]:
    port = free_port()
    folder = tmp_path / "project"
    folder.mkdir()
    (folder / "padt.toml").write_text(SETTINGS.format(port=port))
    (folder / "main.st").write_text(SOURCE)
    result = compile_project(load_project([folder]))
    assert result.artifact is not None, result.diagnostics
    state = tmp_path / "state"
    store_artifact(state, result.artifact)
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    with running_resource("Poller", state, endpoint) as (_, client):
        yield client, port


def values(client: ResourceClient) -> dict[str, Any]:
    return client.ask(GetValues()).values


def device(client: ResourceClient) -> DeviceStatus:
    io = client.ask(GetStatus()).status.io
    assert io is not None and io.server is None
    return io.devices[0]


def events(client: ResourceClient) -> list[str]:
    return [e.message for e in client.ask(GetEvents(limit=1000)).events if e.kind == "io"]


def test_a_device_not_reached_gives_safe_values_of_the_variables_types(
    polling: tuple[ResourceClient, int],
) -> None:
    """Before its device first answers, a REAL input without a configured safe value holds
    0.0, not the integer 0: the program's bodies run as C (the runtime's default), which
    checks the type of every value they read, and keep running."""
    client, _ = polling  # nothing listens on the device's port

    def native_in_place() -> bool:
        found = client.ask(GetEvents(limit=1000)).events
        return any(e.kind == "native" and "in place" in e.message for e in found)

    wait_for(native_in_place, 60)
    before = client.ask(GetStatus()).status.cycle
    wait_for(lambda: client.ask(GetStatus()).status.cycle > before + 20)
    status = client.ask(GetStatus()).status
    assert status.state == ResourceState.RUN, status.error
    now = values(client)
    assert now["flow"] == 0.0 and isinstance(now["flow"], float)
    assert now["reference"] == 0.0 and now["ready"] is False and now["level"] == -1


def test_polling_every_table_and_encoding(polling: tuple[ResourceClient, int]) -> None:
    client, port = polling
    with device_process(port):
        wait_for(lambda: device(client).state == "connected")
        wait_for(lambda: values(client)["level"] == 5)
        assert values(client)["flow"] == 1.25 and values(client)["ready"] is True
        with modbus_client(port) as rig:
            rig.write_registers(10, [0x0001, 0x1170])  # DINT 70000, high word first
            rig.write_register(12, 0x3412)  # UINT 0x1234, bytes swapped
            rig.write_coil(7, True)
            # each table is polled by its own request: the three arrive in any order
            wait_for(lambda: values(client)["count"] == 70000)
            wait_for(lambda: values(client)["temp"] == 0x1234)
            wait_for(lambda: values(client)["feedback"] is True)
            # the outputs the program computed reach the device
            reference = list(struct.unpack(">HH", struct.pack(">f", 2.5)))
            registers = [50, *reference]
            wait_for(lambda: rig.read_holding_registers(20, count=3).registers == registers)
            assert rig.read_coils(5, count=1).bits[0] is True
        status = device(client)
        assert status.requests > 0 and status.last_error is None
        points = {p.variable: p for p in client.ask(GetIo()).points}
        assert (points["count"].value, points["count"].quality) == (70000, "good")
        assert (points["speed"].source, points["speed"].value) == ("rack", 50)


def test_a_killed_device_is_lost_and_comes_back(polling: tuple[ResourceClient, int]) -> None:
    client, port = polling
    with device_process(port):
        wait_for(lambda: values(client)["level"] == 5)
    # killed: its inputs hold their safe values at once, marked bad
    wait_for(lambda: device(client).state == "lost")
    assert values(client)["level"] == -1 and values(client)["ready"] is False
    assert values(client)["pump"] is False  # the program sees the safe inputs
    points = {p.variable: p for p in client.ask(GetIo()).points}
    assert points["level"].quality == "bad" and points["level"].value == -1
    assert any(m.startswith("Modbus device rack lost") for m in events(client))
    # a watch set shows the device's inputs as bad, the program's own variables as live
    qualities: dict[str, str] = {}
    handle = client.watch(
        ["level", "speed"],
        lambda m: qualities.update({k: v.quality for k, v in m.values.items()}),
    )
    try:
        wait_for(lambda: qualities == {"level": "bad", "speed": "live"})
    finally:
        handle.close()
    failures = device(client).failures
    wait_for(lambda: device(client).failures > failures)  # it keeps trying
    with device_process(port):
        wait_for(lambda: device(client).state == "connected")
        wait_for(lambda: values(client)["level"] == 5)
        assert "Modbus device rack connected again" in events(client)
        assert device(client).last_error is None


@contextmanager
def silent_device(port: int) -> Iterator[None]:
    """A device that takes the connection and never answers."""
    listener = socket.create_server(("127.0.0.1", port))
    held: list[socket.socket] = []

    def accept() -> None:
        while True:
            try:
                held.append(listener.accept()[0])
            except OSError:
                return

    threading.Thread(target=accept, daemon=True).start()
    try:
        yield
    finally:
        listener.close()
        for connection in held:
            connection.close()


def test_a_device_that_does_not_answer_is_lost_after_its_timeout(
    polling: tuple[ResourceClient, int],
) -> None:
    client, port = polling
    with silent_device(port):
        # the device was not there when the resource came up; now it takes the connection
        wait_for(lambda: device(client).last_error == "no answer within 300 ms")
        assert device(client).state == "lost" and values(client)["level"] == -1
