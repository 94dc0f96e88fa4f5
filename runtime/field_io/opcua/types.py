"""IEC 61131-3 elementary types as OPC UA built-in types, and values both ways.

Both the server (the resource's variables as nodes) and the client (a remote server's nodes
into located variables) convert here. The runtime holds durations and dates as 64-bit
nanosecond counts; OPC UA has Duration (a Double of milliseconds) and DateTime:

| IEC | OPC UA |
|---|---|
| BOOL | Boolean |
| SINT, USINT / BYTE | SByte, Byte |
| INT, UINT / WORD | Int16, UInt16 |
| DINT, UDINT / DWORD | Int32, UInt32 |
| LINT, ULINT / LWORD | Int64, UInt64 |
| REAL, LREAL | Float, Double |
| STRING, WSTRING, CHAR, WCHAR | String |
| TIME, LTIME, TOD, LTOD | Duration (ms; TOD: since midnight) |
| DATE, LDATE, DT, LDT | DateTime (UTC) |
"""

from __future__ import annotations

import math
from datetime import UTC, datetime, timedelta
from typing import Any

from asyncua import ua
from asyncua.ua.object_ids import ObjectIds

from runtime.contract.values import ValueRejected, array_shape, base_type, representation

_VARIANT: dict[str, ua.VariantType] = {
    "BOOL": ua.VariantType.Boolean,
    "SINT": ua.VariantType.SByte,
    "USINT": ua.VariantType.Byte,
    "BYTE": ua.VariantType.Byte,
    "INT": ua.VariantType.Int16,
    "UINT": ua.VariantType.UInt16,
    "WORD": ua.VariantType.UInt16,
    "DINT": ua.VariantType.Int32,
    "UDINT": ua.VariantType.UInt32,
    "DWORD": ua.VariantType.UInt32,
    "LINT": ua.VariantType.Int64,
    "ULINT": ua.VariantType.UInt64,
    "LWORD": ua.VariantType.UInt64,
    "REAL": ua.VariantType.Float,
    "LREAL": ua.VariantType.Double,
    "STRING": ua.VariantType.String,
    "WSTRING": ua.VariantType.String,
    "CHAR": ua.VariantType.String,
    "WCHAR": ua.VariantType.String,
    **dict.fromkeys(("TIME", "LTIME", "TOD", "LTOD"), ua.VariantType.Double),
    **dict.fromkeys(("DATE", "LDATE", "DT", "LDT"), ua.VariantType.DateTime),
}
_DURATIONS = ("TIME", "LTIME", "TOD", "LTOD")
_DATES = ("DATE", "LDATE", "DT", "LDT")
_EPOCH = datetime(1970, 1, 1, tzinfo=UTC)
_NS_PER_MS = 1_000_000


def variant_type(type_name: str) -> ua.VariantType | None:
    """The built-in type that carries an IEC elementary type (or an array's elements);
    None for a type OPC UA is not given (references, for one)."""
    shape = array_shape(type_name)
    element = shape.element if shape is not None else type_name
    return _VARIANT.get(base_type(element)[0])


def data_type(type_name: str) -> ua.NodeId:
    """The DataType node of a variable: Duration for the durations, else the built-in."""
    element = _element(type_name)
    if base_type(element)[0] in _DURATIONS:
        return ua.NodeId(ua.Int32(ObjectIds.Duration))
    found = variant_type(type_name)
    assert found is not None, type_name
    return ua.NodeId(ua.Int32(found.value))


def dimensions(type_name: str) -> list[int]:
    """An array's lengths per dimension (none for an elementary type)."""
    shape = array_shape(type_name)
    return [] if shape is None else [high - low + 1 for low, high in shape.dims]


def to_opcua(type_name: str, value: Any) -> Any:
    """A run-time value (an array as its flat list) as OPC UA carries it."""
    element = base_type(_element(type_name))[0]
    if isinstance(value, list):
        return [_scalar_to_opcua(element, item) for item in value]
    return _scalar_to_opcua(element, value)


def from_opcua(type_name: str, value: Any) -> Any:
    """A value from OPC UA as the variable of `type_name` holds it (an array as the flat
    list the runtime keeps, last index fastest); ValueRejected when it cannot hold it."""
    shape = array_shape(type_name)
    if shape is None:
        return representation(type_name, _scalar_from_opcua(base_type(type_name)[0], value))
    if not isinstance(value, list):
        raise ValueRejected(f"type {type_name} takes an array, not {value!r}")
    element = shape.element
    items = [representation(element, _scalar_from_opcua(base_type(element)[0], v)) for v in value]
    lengths = dimensions(type_name)
    if len(items) != math.prod(lengths):
        raise ValueRejected(f"type {type_name} takes {math.prod(lengths)} elements")
    return items


def _element(type_name: str) -> str:
    shape = array_shape(type_name)
    return shape.element if shape is not None else type_name


def _scalar_to_opcua(element: str, value: Any) -> Any:
    if element in _DURATIONS and isinstance(value, int):
        return value / _NS_PER_MS
    if element in _DATES and isinstance(value, int):
        return _EPOCH + timedelta(microseconds=value // 1000)
    if element == "REAL" and isinstance(value, str):  # non-finite, as JSON carries it
        return float(value)
    return value


def _scalar_from_opcua(element: str, value: Any) -> Any:
    if element in _DURATIONS and isinstance(value, int | float) and not isinstance(value, bool):
        if not math.isfinite(value):
            raise ValueRejected(f"{value} is not a duration")
        return round(value * _NS_PER_MS)
    if element in _DATES and isinstance(value, datetime):
        moment = value if value.tzinfo is not None else value.replace(tzinfo=UTC)
        delta = moment - _EPOCH
        return (delta.days * 86_400 + delta.seconds) * 1_000_000_000 + delta.microseconds * 1000
    return value
