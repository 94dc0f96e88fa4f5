"""The served process image: a Modbus TCP server (pymodbus) that answers from the latest
snapshot the cycle left, on the I/O thread's event loop (`../io_thread.py`).

The cycle never waits on it: it hands over an immutable `ServedImage` after each cycle (one
reference assignment) and takes the writes of clients from a queue before the next one.
pymodbus decodes the frames; malformed ones and unknown function codes get its exception
responses. Everything else is decided here: a table is as long as its highest mapped
address (unmapped addresses below it read 0); reading beyond it, or writing anything but a
configured writable point, is ILLEGAL ADDRESS; nothing of a refused request is written.
No more requests are read than the meter allows (`request_meter.py`), all clients together.
"""

from __future__ import annotations

import asyncio
import queue
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

from pymodbus.constants import ExcCodes
from pymodbus.server import ModbusTcpServer
from pymodbus.server.requesthandler import ServerRequestHandler
from pymodbus.simulator import SimData, SimDevice

from runtime.contract.modbus import (
    BIT_AREAS,
    COIL,
    DISCRETE_INPUT,
    HOLDING_REGISTER,
    INPUT_REGISTER,
    Point,
    decode,
    encode,
)
from runtime.field_io.modbus.request_meter import RequestMeter

# function codes by table (pymodbus maps 22 and 23 to holding registers too)
_AREA_OF_CODE = {1: COIL, 5: COIL, 15: COIL, 2: DISCRETE_INPUT, 4: INPUT_REGISTER}
_AREA_OF_CODE.update({code: HOLDING_REGISTER for code in (3, 6, 16, 22, 23)})


@dataclass(frozen=True)
class ServedImage:
    """What the served points held after a cycle (outputs: the output image, safe in STOP
    and ERROR STOP), and the last client write the cycle had taken by then."""

    values: tuple[Any, ...]  # in the order of the store's points
    applied: int = 0


@dataclass(frozen=True)
class ClientWrite:
    seq: int
    variable: str
    value: Any


@dataclass
class ServerCounts:
    requests: int = 0  # frames received
    exceptions: int = 0  # exception responses sent
    writes: int = 0  # write requests taken


@dataclass
class ImageStore:
    """The datastore pymodbus asks (`async_getValues`, `async_setValues`, `device_ids`):
    any unit id, as OpenPLC does."""

    points: tuple[Point, ...]
    image: ServedImage = field(init=False)
    writes: queue.SimpleQueue[ClientWrite] = field(default_factory=queue.SimpleQueue)
    counts: ServerCounts = field(default_factory=ServerCounts)

    def __post_init__(self) -> None:
        self.image = ServedImage(tuple(p.safe_value for p in self.points))
        # (table, address) -> (index of the point, its register or bit within the point)
        self._at: dict[tuple[str, int], tuple[int, int]] = {}
        self._length = {COIL: 0, DISCRETE_INPUT: 0, INPUT_REGISTER: 0, HOLDING_REGISTER: 0}
        for index, point in enumerate(self.points):
            for offset in range(point.count):
                self._at[(point.area, point.address + offset)] = (index, offset)
            end = point.address + point.count
            self._length[point.area] = max(self._length[point.area], end)
        self._pending: dict[int, tuple[int, Any]] = {}  # point index -> (write seq, value)
        self._seq = 0

    def device_ids(self) -> list[int]:
        return [0]

    def _value(self, index: int) -> Any:
        """A point's value: a client's write the cycle has not taken yet, else the image's."""
        pending = self._pending.get(index)
        if pending is not None and pending[0] > self.image.applied:
            return pending[1]
        return self.image.values[index]

    def _read(self, area: str, address: int, count: int) -> list[Any] | ExcCodes:
        if count < 1 or address + count > self._length[area]:
            return ExcCodes.ILLEGAL_ADDRESS
        result: list[Any] = []
        bits = area in BIT_AREAS
        for current in range(address, address + count):
            place = self._at.get((area, current))
            if place is None:
                result.append(False if bits else 0)
                continue
            index, offset = place
            value = self._value(index)
            result.append(bool(value) if bits else encode(self.points[index], value)[offset])
        return result

    async def async_getValues(
        self, device_id: int, func_code: int, address: int, count: int = 1
    ) -> list[Any] | ExcCodes:
        area = _AREA_OF_CODE.get(func_code)
        if area is None:
            return ExcCodes.ILLEGAL_FUNCTION
        return self._read(area, address, count)

    async def async_setValues(
        self, device_id: int, func_code: int, address: int, values: Sequence[Any]
    ) -> ExcCodes | None:
        area = _AREA_OF_CODE.get(func_code)
        if area is None or area not in (COIL, HOLDING_REGISTER):
            return ExcCodes.ILLEGAL_FUNCTION
        touched: dict[int, list[int]] = {}  # point index -> its registers as written
        for number, written in enumerate(values):
            place = self._at.get((area, address + number))
            if place is None or not self.points[place[0]].writable:
                return ExcCodes.ILLEGAL_ADDRESS
            index, offset = place
            point = self.points[index]
            if area == COIL:
                touched[index] = [bool(written)]
                continue
            registers = touched.get(index) or encode(point, self._value(index))
            registers[offset] = int(written) & 0xFFFF
            touched[index] = registers
        for index, registers in sorted(touched.items()):
            point = self.points[index]
            value = registers[0] if area == COIL else decode(point, registers)
            self._seq += 1
            self._pending[index] = (self._seq, value)
            self.writes.put(ClientWrite(self._seq, point.variable, value))
        self.counts.writes += 1
        return None

    def show(self, image: ServedImage) -> None:
        """The image after a cycle (from the cycle thread: one assignment); writes it has
        taken are no longer pending."""
        self.image = image


class _MeteredHandler(ServerRequestHandler):
    """A connection of the server: every request it receives takes a token of the meter."""

    meter: RequestMeter

    def callback_data(self, data: bytes, addr: tuple[Any, ...] | None = None) -> int:
        used: int = super().callback_data(data, addr)
        if used:
            self.meter.take(self.loop, self.transport)
        return used


class _MeteredServer(ModbusTcpServer):
    meter: RequestMeter

    def callback_new_connection(self) -> ServerRequestHandler:
        handler = _MeteredHandler(  # type: ignore[no-untyped-call]  # pymodbus' own __init__
            self, self.trace_packet, self.trace_pdu, self.trace_connect
        )
        handler.meter = self.meter
        return handler


class ImageServer:
    """The pymodbus TCP server over an `ImageStore`, on the Modbus event loop."""

    def __init__(
        self, store: ImageStore, host: str, port: int, meter: RequestMeter | None = None
    ) -> None:
        self.store = store
        self.meter = meter or RequestMeter()
        self.host = host
        self.wanted_port = port
        self.port = 0  # where it listens (port 0 asks for any free one)
        self.error: str | None = None
        self._server: ModbusTcpServer | None = None
        self._codes: dict[bytes, int] = {}  # transaction id -> function code received

    def _trace(self, sending: bool, data: bytes) -> bytes:
        """Every frame in and out (pymodbus' hook): counted; and as pymodbus answers a
        function code it does not know with code 0x80, where Modbus (and libmodbus, which
        checks it) wants the request's code + 0x80, the answer gets the request's code."""
        counts = self.store.counts
        if not sending:
            counts.requests += 1
            if len(self._codes) > 1024:
                self._codes.clear()
            if len(data) >= 8:
                self._codes[data[:2]] = data[7]
            return data
        if len(data) >= 8 and data[7] & 0x80:
            counts.exceptions += 1
        if len(data) >= 9 and data[7] == 0x80:
            code = self._codes.get(data[:2])
            if code is not None and code < 0x80:
                return data[:7] + bytes([code | 0x80]) + data[8:]
        return data

    async def start(self) -> None:
        # pymodbus wants a device to build its own store from; it answers from ours
        placeholder = SimDevice(id=0, simdata=[SimData(0)])
        server = _MeteredServer(
            placeholder, address=(self.host, self.wanted_port), trace_packet=self._trace
        )
        server.meter = self.meter
        server.context = self.store  # type: ignore[assignment]  # same protocol, our data
        try:
            await server.serve_forever(background=True)
        except (RuntimeError, OSError) as exc:
            self.error = f"cannot listen on {self.host}:{self.wanted_port}: {exc}"
            server.close()
            return
        self._server = server
        sockets = getattr(server.transport, "sockets", None) or ()
        self.port = sockets[0].getsockname()[1] if sockets else self.wanted_port

    async def stop(self) -> None:
        if self._server is not None:
            await self._server.shutdown()  # type: ignore[no-untyped-call]
            self._server = None
            await asyncio.sleep(0)
