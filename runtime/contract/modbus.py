"""Modbus TCP in the artifact: the served process image and the remote devices a resource
polls, and how a located variable's value becomes Modbus bits and registers and back.

The compiler checks a project's `[modbus]` settings and writes what it found here; the
runtime serves and polls exactly that. The map of the served image is OpenPLC's, so SCADA
and HMI tools set up for OpenPLC read a resource unchanged (docs/modbus.md):

| located variable | Modbus table | address |
|---|---|---|
| `%IXa.b` (BOOL) | discrete inputs | a * 8 + b |
| `%QXa.b` (BOOL) | coils | a * 8 + b |
| `%IWn` (16 bits) | input registers | n |
| `%QWn` (16 bits) | holding registers | n |
| `%MWn` (16 bits) | holding registers | 1024 + n |
| `%MDn` (32 bits, REAL) | holding registers | 2048 + 2n, two registers |
"""

from __future__ import annotations

import math
import re
import struct
from dataclasses import dataclass
from typing import Any

from runtime.contract.values import ValueRejected, representation

# the four tables of the Modbus data model
COIL = "coil"
DISCRETE_INPUT = "discrete_input"
INPUT_REGISTER = "input_register"
HOLDING_REGISTER = "holding_register"
AREAS = (COIL, DISCRETE_INPUT, INPUT_REGISTER, HOLDING_REGISTER)
BIT_AREAS = (COIL, DISCRETE_INPUT)
WRITABLE_AREAS = (COIL, HOLDING_REGISTER)  # what a client can write, and a device be sent
ORDERS = ("big", "little")

DEFAULT_HOST = "127.0.0.1"
DEFAULT_PORT = 5020
MEMORY_WORDS = 1024  # %MW0 is holding register 1024 (OpenPLC)
MEMORY_DWORDS = 2048  # %MD0 is holding register 2048
MAX_ADDRESS = 65535
FLOAT32_MAX = 3.4028234663852886e38

# the bits each elementary type takes on the wire
SIXTEEN_BITS = {"INT": "h", "UINT": "H", "WORD": "H", "SINT": "h", "USINT": "H", "BYTE": "H"}
THIRTY_TWO_BITS = {"DINT": "i", "UDINT": "I", "DWORD": "I", "REAL": "f"}
# what the narrow types hold, so that a register from the field is checked before it is stored
_LIMITS = {"SINT": (-128, 127), "USINT": (0, 255), "BYTE": (0, 255)}

_LOCATION = re.compile(r"%([IQM])([XBWDL]?)(\d+)(?:\.(\d+))?$", re.IGNORECASE)


@dataclass(frozen=True)
class Point:
    """A located global variable on a Modbus table: what the served image shows, or what a
    device delivers (for `%I` variables) or is sent (for `%Q` variables)."""

    variable: str  # the global's name, as declared
    location: str  # its location, `%IW0`
    type: str  # its elementary type
    area: str  # one of AREAS
    address: int  # the first bit or register
    byte_order: str = "big"  # within a register
    word_order: str = "big"  # of the two registers of a 32-bit value: high word first
    safe_value: bool | int | float = 0  # an input's value while its device is lost
    writable: bool = False  # a client may write it (served points only)

    @property
    def count(self) -> int:
        """Bits or registers the point takes."""
        return 2 if self.type in THIRTY_TWO_BITS else 1

    @property
    def input_safe_value(self) -> bool | int | float:
        """The safe value as the variable holds it: a REAL's `0` as `0.0`, which the native
        tier's type checks need. (The artifact keeps the value as written, under its CRC;
        `modbus_config` checked that it suits the type.)"""
        value: bool | int | float = representation(self.type, self.safe_value)
        return value

    @property
    def is_input(self) -> bool:
        return self.location.upper().startswith("%I")


@dataclass(frozen=True)
class Device:
    """A remote I/O device the resource polls as a Modbus TCP client."""

    name: str
    host: str
    port: int
    unit_id: int = 1
    period_ms: int = 100  # from the start of one poll to the next
    timeout_ms: int = 1000  # an answer later than this: the device is lost
    points: tuple[Point, ...] = ()


@dataclass(frozen=True)
class ModbusConfig:
    """What a resource does over Modbus TCP; `serve` off and no devices: nothing at all."""

    serve: bool = False
    host: str = DEFAULT_HOST
    port: int = DEFAULT_PORT
    served: tuple[Point, ...] = ()  # every located variable the map covers, sorted
    devices: tuple[Device, ...] = ()


def parse_location(location: str) -> tuple[str, str, int, int | None] | None:
    """(`I`|`Q`|`M`, size letter, index, bit) of a direct address, or None."""
    match = _LOCATION.match(location.strip())
    if match is None:
        return None
    kind, size, index, bit = match.groups()
    return kind.upper(), (size or "X").upper(), int(index), None if bit is None else int(bit)


def served_place(location: str, type_name: str) -> tuple[str, int] | None:
    """The table and address the default (OpenPLC) map gives a located variable of this
    type; None when the map has no place for it."""
    parsed = parse_location(location)
    if parsed is None:
        return None
    kind, size, index, bit = parsed
    type_name = type_name.upper()
    if size == "X" and type_name == "BOOL" and kind in "IQ":
        return (DISCRETE_INPUT if kind == "I" else COIL), index * 8 + (bit or 0)
    if size == "W" and type_name in SIXTEEN_BITS:
        if kind == "I":
            return INPUT_REGISTER, index
        return HOLDING_REGISTER, index + (MEMORY_WORDS if kind == "M" else 0)
    if size == "D" and kind == "M" and type_name in THIRTY_TWO_BITS:
        return HOLDING_REGISTER, MEMORY_DWORDS + 2 * index
    return None


def fits(type_name: str, area: str) -> bool:
    """Whether a value of this type can live on this table."""
    if area in BIT_AREAS:
        return type_name == "BOOL"
    return type_name in SIXTEEN_BITS or type_name in THIRTY_TWO_BITS


def encode(point: Point, value: bool | int | float) -> list[int]:
    """A register point's value as its registers (16-bit unsigned each)."""
    if point.type in SIXTEEN_BITS:
        raw = int(value) & 0xFFFF
        return [_swap16(raw) if point.byte_order == "little" else raw]
    fmt = THIRTY_TWO_BITS[point.type]
    if fmt == "f":
        number = float(value)
        if math.isfinite(number) and abs(number) > FLOAT32_MAX:  # beyond REAL on the wire
            number = math.copysign(math.inf, number)
        data = struct.pack(">f", number)
    else:
        data = struct.pack(">I", int(value) & 0xFFFFFFFF)
    high, low = struct.unpack(">HH", data)
    if point.byte_order == "little":
        high, low = _swap16(high), _swap16(low)
    return [high, low] if point.word_order == "big" else [low, high]


def decode(point: Point, registers: list[int]) -> int | float:
    """A register point's value from its registers, in the range of its type."""
    if point.type in SIXTEEN_BITS:
        raw = registers[0] & 0xFFFF
        if point.byte_order == "little":
            raw = _swap16(raw)
        value = raw - 0x10000 if SIXTEEN_BITS[point.type] == "h" and raw & 0x8000 else raw
        low, high = _LIMITS.get(point.type, (-0x8000, 0xFFFF))
        return min(max(value, low), high)
    first, second = registers[0] & 0xFFFF, registers[1] & 0xFFFF
    high, low = (first, second) if point.word_order == "big" else (second, first)
    if point.byte_order == "little":
        high, low = _swap16(high), _swap16(low)
    data = struct.pack(">HH", high, low)
    fmt = THIRTY_TWO_BITS[point.type]
    result: int | float = struct.unpack(">" + fmt, data)[0]
    return result


def _swap16(word: int) -> int:
    return ((word & 0xFF) << 8) | (word >> 8)


def modbus_config(data: dict[str, Any]) -> ModbusConfig:
    """The artifact's `modbus` object back into its dataclasses (KeyError, TypeError when
    it is incomplete)."""
    return ModbusConfig(
        serve=data["serve"],
        host=data["host"],
        port=data["port"],
        served=tuple(_point(p) for p in data["served"]),
        devices=tuple(
            Device(**{**d, "points": tuple(_device_point(p) for p in d["points"])})
            for d in data["devices"]
        ),
    )


_TEXT_FIELDS = ("variable", "location", "type", "area", "byte_order", "word_order")


def _point(data: dict[str, Any]) -> Point:
    point = Point(**data)
    wrong = [name for name in _TEXT_FIELDS if not isinstance(getattr(point, name), str)]
    if wrong or type(point.address) is not int:
        raise TypeError(f"the {(wrong or ['address'])[0]} of a Modbus point is of the wrong type")
    return point


def _device_point(data: dict[str, Any]) -> Point:
    point = _point(data)
    if not point.is_input:  # an output's safe value is the resource's (`safe_values`)
        return point
    try:
        point.input_safe_value  # noqa: B018 (checked here, so that a poller never raises)
    except ValueRejected as exc:
        raise TypeError(f"the safe value of Modbus point '{point.variable}': {exc}") from None
    return point
