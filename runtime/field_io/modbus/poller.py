"""Polling one remote I/O device as a Modbus TCP client (pymodbus), on the I/O thread.

Each period the poller reads the device's input points (in blocks of adjacent addresses)
and sends the output points whose value changed (all of them after a reconnect). What it
read goes to the cycle as one immutable `Delivery` (one reference assignment); the cycle
never waits for it. A device that does not answer within its timeout, refuses, or drops the
connection is lost: the poller delivers the inputs' safe values marked bad at once, closes
the connection, and tries again each period until the device answers.
"""

from __future__ import annotations

import asyncio
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from pymodbus.client import AsyncModbusTcpClient
from pymodbus.exceptions import ModbusException

from runtime.contract.modbus import (
    BIT_AREAS,
    COIL,
    DISCRETE_INPUT,
    HOLDING_REGISTER,
    INPUT_REGISTER,
    Device,
    Point,
    decode,
    encode,
)
from runtime.field_io.delivery import Delivery

MAX_REGISTERS = 120  # per request (Modbus allows 125 to read, 123 to write)
MAX_BITS = 1968
MAX_GAP = 8  # unmapped addresses read along rather than in a request of their own


@dataclass(frozen=True)
class Block:
    area: str
    address: int
    count: int
    points: tuple[Point, ...]


class DeviceLost(Exception):
    """The device answered with an exception, or not at all."""


def blocks(points: list[Point], gap: int = MAX_GAP) -> list[Block]:
    """Adjacent points of one table in one request, within the request size."""
    result: list[Block] = []
    for area in (COIL, DISCRETE_INPUT, INPUT_REGISTER, HOLDING_REGISTER):
        limit = MAX_BITS if area in BIT_AREAS else MAX_REGISTERS
        current: list[Point] = []
        for point in sorted((p for p in points if p.area == area), key=lambda p: p.address):
            if current:
                start, end = current[0].address, current[-1].address + current[-1].count
                if point.address - end > gap or point.address + point.count - start > limit:
                    result.append(_block(current))
                    current = []
            current.append(point)
        if current:
            result.append(_block(current))
    return result


def _block(points: list[Point]) -> Block:
    start = points[0].address
    end = max(p.address + p.count for p in points)
    return Block(points[0].area, start, end - start, tuple(points))


class DevicePoller:
    def __init__(self, device: Device, outputs: Callable[[], dict[str, Any]]) -> None:
        self.device = device
        self._outputs = outputs  # the output image of the last cycle
        inputs = [p for p in device.points if p.is_input]
        self._reads = blocks(inputs)
        # outputs go in blocks of strictly adjacent points: a gap would overwrite the device
        self._writes = blocks([p for p in device.points if not p.is_input], gap=0)
        self._safe = {p.variable: p.input_safe_value for p in inputs}
        # until the device first answers, its inputs hold their safe values, marked bad
        self.delivery = Delivery(1, dict(self._safe), False)
        self.state = "connecting"
        self.last_error: str | None = None
        self.requests = 0
        self.failures = 0
        self.round_trip_ms = 0.0
        self.sent: dict[str, Any] = {}  # output values the device has taken
        self._client: AsyncModbusTcpClient | None = None

    async def run(self) -> None:
        period = self.device.period_ms / 1000
        try:
            while True:
                began = time.monotonic()
                await self.poll()
                await asyncio.sleep(max(0.0, period - (time.monotonic() - began)))
        finally:
            self._close()

    async def poll(self) -> None:
        timeout = self.device.timeout_ms / 1000
        began = time.monotonic()
        try:
            values = await asyncio.wait_for(self._exchange(), timeout)
        except (TimeoutError, ModbusException, OSError, DeviceLost) as exc:
            self._lost(_reason(exc, self.device.timeout_ms))
            return
        self.round_trip_ms = (time.monotonic() - began) * 1000
        self.delivery = Delivery(self.delivery.seq + 1, values, True)
        self.state, self.last_error = "connected", None

    def _lost(self, reason: str) -> None:
        self.failures += 1
        self.last_error = reason
        self.sent = {}  # everything goes again after the reconnect
        self.delivery = Delivery(self.delivery.seq + 1, dict(self._safe), False)
        self.state = "lost"  # after the delivery: the cycle reads them the other way round
        self._close()

    def _close(self) -> None:
        if self._client is not None:
            self._client.close()
            self._client = None

    async def _connected(self) -> AsyncModbusTcpClient:
        if self._client is None or not self._client.connected:
            self._close()
            timeout = self.device.timeout_ms / 1000
            client = AsyncModbusTcpClient(
                self.device.host, port=self.device.port, timeout=timeout, retries=0,
                reconnect_delay=0,
            )  # fmt: skip
            self._client = client
            if not await client.connect():
                raise DeviceLost(f"no connection to {self.device.host}:{self.device.port}")
        return self._client

    async def _exchange(self) -> dict[str, Any]:
        client = await self._connected()
        values: dict[str, Any] = {}
        for block in self._reads:
            data = await self._read(client, block)
            for point in block.points:
                offset = point.address - block.address
                if block.area in BIT_AREAS:
                    values[point.variable] = bool(data[offset])
                else:
                    values[point.variable] = decode(point, data[offset : offset + point.count])
        outputs = self._outputs()
        for block in self._writes:
            wanted = {p.variable: outputs.get(p.variable, p.safe_value) for p in block.points}
            if all(self.sent.get(name) == value for name, value in wanted.items()):
                continue
            await self._write(client, block, wanted)
            self.sent.update(wanted)
        return values

    async def _read(self, client: AsyncModbusTcpClient, block: Block) -> list[Any]:
        unit, address, count = self.device.unit_id, block.address, block.count
        self.requests += 1
        if block.area == COIL:
            response = await client.read_coils(address, count=count, device_id=unit)
        elif block.area == DISCRETE_INPUT:
            response = await client.read_discrete_inputs(address, count=count, device_id=unit)
        elif block.area == INPUT_REGISTER:
            response = await client.read_input_registers(address, count=count, device_id=unit)
        else:
            response = await client.read_holding_registers(address, count=count, device_id=unit)
        if response.isError():
            raise DeviceLost(_refused(response, block))
        data: list[Any] = list(response.bits if block.area in BIT_AREAS else response.registers)
        if len(data) < count:
            raise DeviceLost(f"{block.area} {address}: {len(data)} values for {count}")
        return data

    async def _write(
        self, client: AsyncModbusTcpClient, block: Block, values: dict[str, Any]
    ) -> None:
        unit = self.device.unit_id
        self.requests += 1
        if block.area == COIL:
            bits = [bool(values[p.variable]) for p in block.points]
            response = await client.write_coils(block.address, bits, device_id=unit)
        else:
            registers = [r for p in block.points for r in encode(p, values[p.variable])]
            response = await client.write_registers(block.address, registers, device_id=unit)
        if response.isError():
            raise DeviceLost(_refused(response, block))


def _refused(response: Any, block: Block) -> str:
    code = getattr(response, "exception_code", "?")
    return f"exception {code} for {block.area} {block.address}..{block.address + block.count - 1}"


def _reason(exc: BaseException, timeout_ms: int) -> str:
    if isinstance(exc, TimeoutError):
        return f"no answer within {timeout_ms} ms"
    return str(exc) or type(exc).__name__
