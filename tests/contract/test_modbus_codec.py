"""How values become Modbus registers and back, in every encoding and order."""

from __future__ import annotations

import struct

import pytest

from runtime.contract.modbus import Point, decode, encode, served_place


def _point(type_name: str, byte_order: str = "big", word_order: str = "big") -> Point:
    return Point("v", "%IW0", type_name, "input_register", 0, byte_order, word_order)


@pytest.mark.parametrize(
    ("type_name", "value"),
    [("INT", -2), ("INT", 32767), ("UINT", 65535), ("WORD", 0x1234), ("SINT", -5),
     ("DINT", -70000), ("UDINT", 4_000_000_000), ("DWORD", 0xDEADBEEF), ("REAL", 12.5)],
)  # fmt: skip
@pytest.mark.parametrize("byte_order", ["big", "little"])
@pytest.mark.parametrize("word_order", ["big", "little"])
def test_round_trip(type_name: str, value: int | float, byte_order: str, word_order: str) -> None:
    point = _point(type_name, byte_order, word_order)
    registers = encode(point, value)
    assert len(registers) == point.count and all(0 <= r <= 0xFFFF for r in registers)
    assert decode(point, registers) == value


def test_orders_on_the_wire() -> None:
    high, low = struct.unpack(">HH", struct.pack(">f", 1.5))
    assert encode(_point("REAL"), 1.5) == [high, low]
    assert encode(_point("REAL", word_order="little"), 1.5) == [low, high]
    assert encode(_point("INT", byte_order="little"), 0x0102) == [0x0201]
    infinity = list(struct.unpack(">HH", struct.pack(">f", float("inf"))))
    assert encode(_point("REAL"), 1e39) == infinity  # beyond REAL on the wire


def test_openplc_map() -> None:
    assert served_place("%IX1.2", "BOOL") == ("discrete_input", 10)
    assert served_place("%QX0.7", "BOOL") == ("coil", 7)
    assert served_place("%IW3", "INT") == ("input_register", 3)
    assert served_place("%QW3", "WORD") == ("holding_register", 3)
    assert served_place("%MW3", "INT") == ("holding_register", 1027)
    assert served_place("%MD1", "REAL") == ("holding_register", 2050)
    assert served_place("%QW0", "REAL") is None and served_place("%IX0.0", "INT") is None
