"""The demo over Modbus TCP: `padt demo` polls its simulated plant as remote I/O and serves
its image; mbpoll (Debian, libmodbus) reads the tank level at input register 0 and the pump
command at coil 0, and they are what the resource holds."""

from __future__ import annotations

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
        # over a whole tank cycle the pump command is on once and off once
        seen: set[bool] = set()

        def both_seen() -> bool:
            seen.add(modbus.read_coils(0, count=1).bits[0])
            return len(seen) == 2

        wait_for(both_seen, 60)
    level = polled(mbpoll(port, "-t", "3", "-r", "0", "-c", "1"))[0]
    assert 0 <= int(level.split()[0]) <= 1000
    assert polled(mbpoll(port, "-t", "0", "-r", "0", "-c", "1"))[0] in ("0", "1")
    assert polled(mbpoll(port, "-t", "1", "-r", "0", "-c", "1"))[0] in ("0", "1")  # feedback
    refused = mbpoll(port, "-t", "0", "-r", "0", write="1")  # the demo serves nothing writable
    assert refused.returncode != 0 and "Illegal data address" in refused.stdout + refused.stderr
