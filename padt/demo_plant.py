"""The demo's plant: a tank with its pump, simulated as a Modbus TCP device (a plain
pymodbus server) in the demo's process, for the resource to poll as remote I/O.

Every 100 ms the pump, while its command (coil 0) is on, delivers 8 litres, and the plant
draws 3; the level (0..1000 litres) is input register 0, the pump's feedback discrete
input 0. It answers any unit id.
"""

from __future__ import annotations

import asyncio
import threading

from pymodbus.server import ModbusTcpServer
from pymodbus.simulator import DataType, SimData, SimDevice

INFLOW, OUTFLOW, START_LEVEL, MAX_LEVEL = 8, 3, 500, 1000
TICK_S = 0.1
COIL, DISCRETE_INPUT, INPUT_REGISTER = 1, 2, 4  # the function codes that reach each table


def _device() -> SimDevice:
    def table(bits: bool) -> list[SimData]:
        kind = DataType.BITS if bits else DataType.REGISTERS
        return [SimData(0, values=[False if bits else 0] * 16, datatype=kind)]

    return SimDevice(
        id=0,
        simdata=(table(True), table(True), table(False), table(False)),
        use_bit_addressing=True,
    )


def tick(level: int, running: bool) -> int:
    """The tank's level after one tick, the pump running or not."""
    if running:
        level = min(MAX_LEVEL, level + INFLOW)
    return max(0, level - OUTFLOW)


class DemoPlant:
    """Runs on a thread of its own; `port` is where it listens once it is started."""

    def __init__(self, host: str = "127.0.0.1", port: int = 0) -> None:
        self.host, self.port = host, port
        self.level = START_LEVEL
        self._loop = asyncio.new_event_loop()
        self._server: ModbusTcpServer | None = None
        self._simulation: asyncio.Task[None] | None = None
        self._thread = threading.Thread(target=self._loop.run_forever, name="demo-plant")
        self._thread.daemon = True

    def start(self) -> int:
        """Listen and start the simulation; the port it listens on (OSError when busy)."""
        self._thread.start()
        asyncio.run_coroutine_threadsafe(self._start(), self._loop).result(10)
        return self.port

    async def _start(self) -> None:
        server = ModbusTcpServer(_device(), address=(self.host, self.port))
        try:
            await server.serve_forever(background=True)
        except RuntimeError as exc:
            raise OSError(f"the demo plant cannot listen on {self.host}:{self.port}") from exc
        self._server = server
        sockets = getattr(server.transport, "sockets", None) or ()
        self.port = sockets[0].getsockname()[1] if sockets else self.port
        self._simulation = asyncio.get_running_loop().create_task(self._simulate(server))

    async def _simulate(self, server: ModbusTcpServer) -> None:
        while True:
            command = await server.async_getValues(0, COIL, 0, 1)
            running = bool(command[0])
            self.level = tick(self.level, running)
            await server.async_setValues(0, INPUT_REGISTER, 0, [self.level])
            await server.async_setValues(0, DISCRETE_INPUT, 0, [running])
            await asyncio.sleep(TICK_S)

    def close(self) -> None:
        async def stop() -> None:
            if self._simulation is not None:
                self._simulation.cancel()
            if self._server is not None:
                await self._server.shutdown()  # type: ignore[no-untyped-call]

        if self._thread.is_alive():
            asyncio.run_coroutine_threadsafe(stop(), self._loop).result(5)
            self._loop.call_soon_threadsafe(self._loop.stop)
            self._thread.join(5)
