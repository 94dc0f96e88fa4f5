"""The demo over Modbus TCP: `padt demo` polls its simulated plant as remote I/O and serves
its image; mbpoll (Debian, libmodbus) reads the tank level at input register 0 and the pump
command at coil 0, and they are what the resource holds. The tank's two levels are written
closer together first (online writes), so that a whole tank cycle takes seconds, not half
a minute."""

from __future__ import annotations

from itertools import pairwise

from backend.engineering.resource_client import ResourceClient
from runtime.contract.protocol import Write
from runtime.contract.session import open_client
from tests.runtime.test_modbus_server import mbpoll, polled, wait_for
from tests.support.modbus_device import modbus_client, reachable
from tests.ui.browser_steps import Demo


def test_mbpoll_reads_the_demos_level_and_pump(demo: Demo) -> None:
    port = demo.modbus_port
    wait_for(lambda: reachable(port), 30)  # the runtime comes up after the UI
    with modbus_client(port) as modbus:
        # the level moves: the plant fills and drains the tank as the pump command says
        first = modbus.read_input_registers(0, count=1).registers[0]
        wait_for(lambda: modbus.read_input_registers(0, count=1).registers[0] != first, 20)
        # the loop is closed: TankControl reads the plant's level and commands its pump,
        # so over a tank cycle the pump stops at the high level and starts again after the
        # refill delay at the low one, and the level served stays between them (give or
        # take a poll period and the refill delay's draining: 60 l)
        level = modbus.read_input_registers(0, count=1).registers[0]
        low, high = max(level - 50, 150), max(level - 50, 150) + 100
        with open_client(demo.zenoh) as session:
            client = ResourceClient(session, "Tank1")
            client.login("admin", demo.password)
            client.ask(Write("TankControl.lowLevel", low))
            client.ask(Write("TankControl.highLevel", high))
        samples: list[tuple[int, bool]] = []

        def restarted() -> bool:
            level = modbus.read_input_registers(0, count=1).registers[0]
            samples.append((level, modbus.read_coils(0, count=1).bits[0]))
            pumping = [on for _, on in samples]
            runs = pumping[:1] + [on for was, on in pairwise(pumping) if on != was]
            return runs[-3:] == [True, False, True]  # on, stopped, started again

        wait_for(restarted, 60)
        assert all(low - 100 <= level <= high + 100 for level, _ in samples), samples
        switches = [i for i in range(1, len(samples)) if samples[i][1] != samples[i - 1][1]]
        stopped_at, started_at = (samples[i - 1][0] for i in switches[-2:])
        assert stopped_at >= high - 20 and started_at <= low, samples
    served = polled(mbpoll(port, "-t", "3", "-r", "0", "-c", "1"))[0]
    assert 0 <= int(served.split()[0]) <= 1000
    assert polled(mbpoll(port, "-t", "0", "-r", "0", "-c", "1"))[0] in ("0", "1")
    assert polled(mbpoll(port, "-t", "1", "-r", "0", "-c", "1"))[0] in ("0", "1")  # feedback
    refused = mbpoll(port, "-t", "0", "-r", "0", write="1")  # the demo serves nothing writable
    assert refused.returncode != 0 and "Illegal data address" in refused.stdout + refused.stderr
