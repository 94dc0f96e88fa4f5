"""A remote I/O device for tests: a plain pymodbus TCP server (its simulator's data model,
four tables of 64 bits or registers each), run as its own process so that a test can kill
it and start it again: `python -m tests.support.modbus_device PORT [INITIAL_JSON]`.

INITIAL_JSON sets values: `{"input_register": {"0": 5}, "discrete_input": {"3": true}}`.
"""

from __future__ import annotations

import asyncio
import json
import sys
from collections.abc import Iterator
from contextlib import contextmanager

from pymodbus.client import ModbusTcpClient
from pymodbus.server import ModbusTcpServer
from pymodbus.simulator import DataType, SimData, SimDevice

SIZE = 64


def device(initial: dict[str, dict[str, int | bool]]) -> SimDevice:
    def table(name: str, bits: bool) -> list[SimData]:
        values: list[int | bool] = [False if bits else 0] * SIZE
        for address, value in initial.get(name, {}).items():
            values[int(address)] = value
        kind = DataType.BITS if bits else DataType.REGISTERS
        return [SimData(0, values=values, datatype=kind)]

    return SimDevice(
        id=0,
        simdata=(
            table("coil", True),
            table("discrete_input", True),
            table("holding_register", False),
            table("input_register", False),
        ),
        use_bit_addressing=True,
    )


async def serve(port: int, initial: dict[str, dict[str, int | bool]]) -> None:
    server = ModbusTcpServer(device(initial), address=("127.0.0.1", port))
    await server.serve_forever()


def reachable(port: int) -> bool:
    """Whether a Modbus server takes connections on 127.0.0.1:`port`."""
    client = ModbusTcpClient("127.0.0.1", port=port, timeout=1)
    try:
        return bool(client.connect())  # type: ignore[no-untyped-call]  # pymodbus lacks it
    finally:
        client.close()  # type: ignore[no-untyped-call]


@contextmanager
def modbus_client(port: int) -> Iterator[ModbusTcpClient]:
    """A pymodbus client connected to 127.0.0.1:`port`, closed afterwards."""
    client = ModbusTcpClient("127.0.0.1", port=port, timeout=3)
    assert client.connect(), f"no Modbus server on port {port}"  # type: ignore[no-untyped-call]
    try:
        yield client
    finally:
        client.close()  # type: ignore[no-untyped-call]


if __name__ == "__main__":
    asyncio.run(serve(int(sys.argv[1]), json.loads(sys.argv[2]) if len(sys.argv) > 2 else {}))
