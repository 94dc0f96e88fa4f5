"""How values become Modbus registers and back, in every encoding and order."""

from __future__ import annotations

import struct

import pytest

from runtime.contract.modbus import Point, decode, encode, modbus_config, served_place


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


def _device(*points: dict[str, object]) -> dict[str, object]:
    device = {"name": "rack", "host": "127.0.0.1", "port": 502, "unit_id": 1}
    device |= {"period_ms": 50, "timeout_ms": 300, "points": list(points)}
    return {"serve": False, "host": "127.0.0.1", "port": 502, "served": [], "devices": [device]}


def test_an_input_holds_its_safe_value_in_its_variables_type() -> None:
    real = {"variable": "flow", "location": "%ID1", "type": "REAL", "area": "input_register"}
    config = modbus_config(_device(real | {"address": 2, "safe_value": 0}))
    safe = config.devices[0].points[0].input_safe_value
    assert safe == 0.0 and isinstance(safe, float)


def test_the_decoder_refuses_an_input_safe_value_its_type_cannot_hold() -> None:
    bit = {"variable": "ready", "location": "%IX0.0", "type": "BOOL", "area": "discrete_input"}
    with pytest.raises(TypeError, match=r"safe value of Modbus point 'ready'.*BOOL"):
        modbus_config(_device(bit | {"address": 3, "safe_value": 0}))
    pump = {"variable": "pump", "location": "%QX0.0", "type": "BOOL", "area": "coil"}
    assert modbus_config(_device(pump | {"address": 5}))  # an output's is the resource's


@pytest.mark.parametrize(
    ("field", "value"),
    [("type", None), ("location", 5), ("variable", ["v"]), ("address", "0"), ("address", True)],
)
def test_the_decoder_refuses_a_point_whose_fields_are_of_the_wrong_type(
    field: str, value: object
) -> None:
    """A CRC is no signature: a crafted artifact is refused (an ArtifactError for the
    load), never an AttributeError out of the decoder."""
    point: dict[str, object] = {"variable": "v", "location": "%IW0", "type": "INT"}
    point |= {"area": "input_register", "address": 0, field: value}
    with pytest.raises(TypeError, match=f"the {field} of a Modbus point"):
        modbus_config(_device(point))
    served = {**_device(), "served": [point]}
    with pytest.raises(TypeError, match=f"the {field} of a Modbus point"):
        modbus_config(served)
