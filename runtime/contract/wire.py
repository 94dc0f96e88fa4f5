"""How a typed message (a dataclass of the protocol) becomes JSON and back.

One mechanism for every message that crosses the bus, in both directions: `encode` turns a
message into plain JSON data; `decode` checks plain JSON data against a message type (every
field's type, range and size, see `Range`, `MaxLength` and `Pattern`) and builds the
message, or raises `Refusal("bad_request")` naming the first field that is wrong. Nothing
that comes off the bus reaches the rest of a program unchecked.
"""

from __future__ import annotations

import dataclasses
import enum
import functools
import math
import re
import types
import typing
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, TypeVar, Union

from runtime.contract.refusal import Refusal

MAX_DEPTH = 16  # nesting of arrays and objects in any message (values of arrays of arrays)
T = TypeVar("T")


@dataclass(frozen=True)
class Range:
    """An integer or number from `low` to `high` (either may be None: no bound)."""

    low: float | None = None
    high: float | None = None


@dataclass(frozen=True)
class MaxLength:
    """A text, list or object of at most `limit` characters or items."""

    limit: int


@dataclass(frozen=True)
class Pattern:
    """A text that matches `regex` as a whole."""

    regex: str
    explained: str  # what it means, for the refusal


class JsonValue:
    """Marks a field that holds any JSON value (a variable's value): only its depth is
    checked here; the receiver checks it against the variable's type."""


_PLAIN = frozenset({int, str, bool, type(None)})  # exactly these types: not an enum's


def encode(message: Any) -> Any:
    """A message (dataclass, enum, list, dict, scalar) as plain JSON data; non-finite
    REALs as text, as strict JSON has no NaN."""
    # values first, cheaply: a reply of 100,000 of them took 62 ms here without this
    kind = type(message)
    if kind in _PLAIN:
        return message
    if kind is float:
        return message if math.isfinite(message) else repr(message)
    if dataclasses.is_dataclass(message) and not isinstance(message, type):
        return {f.name: encode(getattr(message, f.name)) for f in _fields(type(message))}
    if isinstance(message, enum.Enum):
        return message.value
    if isinstance(message, float) and not math.isfinite(message):
        return repr(message)
    if isinstance(message, list | tuple):
        return [encode(item) for item in message]
    if isinstance(message, dict):
        return {str(key): encode(value) for key, value in message.items()}
    return message


def decode(kind: type[T], data: Any, where: str = "") -> T:
    """`data` checked against `kind` and built into it; Refusal("bad_request") otherwise."""
    result: T = _decoder(typing.cast(Any, kind))(data, where)
    return result


def depth(data: Any, limit: int = MAX_DEPTH) -> int:
    """How deeply arrays and objects nest in `data`, counted without recursion (stops
    counting at `limit + 1`)."""
    deepest = 0
    stack: list[tuple[Any, int]] = [(data, 0)]
    while stack:
        item, level = stack.pop()
        if isinstance(item, list | dict):
            level += 1
            deepest = max(deepest, level)
            if level > limit:
                return level
            stack.extend(
                (child, level) for child in (item.values() if isinstance(item, dict) else item)
            )
    return deepest


# ---- the decoders, one built per type and kept

Decoder = Callable[[Any, str], Any]


def _bad(where: str, expected: str) -> Refusal:
    name = where or "the request"
    return Refusal("bad_request", f'"{name}" must be {expected}')


@functools.cache
def _fields(kind: type) -> tuple[dataclasses.Field[Any], ...]:
    return tuple(dataclasses.fields(kind))


@functools.cache
def _decoder(kind: Any) -> Decoder:
    origin = typing.get_origin(kind)
    if origin is typing.Annotated:
        base, *marks = typing.get_args(kind)
        checked = tuple(mark for mark in marks if isinstance(mark, Range | MaxLength | Pattern))
        if not checked:  # JsonValue on Any: a mark of what the field holds, nothing to check
            return _decoder(base)
        return _constrained(_decoder(base), checked)
    if kind is JsonValue or kind is Any:
        return _json_value
    if origin in (Union, types.UnionType):
        return _union(typing.get_args(kind))
    if origin is list:
        return _list(_decoder(typing.get_args(kind)[0]))
    if origin is tuple and typing.get_args(kind)[1:] == (...,):
        return _tuple(_list(_decoder(typing.get_args(kind)[0])))
    if origin is dict:
        key, value = typing.get_args(kind)
        if key is not str:
            raise TypeError(f"object keys are text, not {key}")
        return _dict(_decoder(value))
    if origin is typing.Literal:
        return _literal(typing.get_args(kind))
    if isinstance(kind, type) and issubclass(kind, enum.Enum):
        return _enum(kind)
    if isinstance(kind, type) and dataclasses.is_dataclass(kind):
        return _dataclass(kind)
    if kind in _SCALARS:
        return _SCALARS[kind]
    if kind is type(None):
        return _none
    raise TypeError(f"no decoder for {kind!r}")


def _json_value(data: Any, where: str) -> Any:
    if type(data) in _FLAT:
        return data
    if depth(data) > MAX_DEPTH:
        raise _bad(where, f"a value nested at most {MAX_DEPTH} deep")
    return data


def _none(data: Any, where: str) -> None:
    if data is not None:
        raise _bad(where, "null")


def _bool(data: Any, where: str) -> bool:
    if not isinstance(data, bool):
        raise _bad(where, "true or false")
    return data


def _int(data: Any, where: str) -> int:
    if isinstance(data, bool) or not isinstance(data, int):
        raise _bad(where, "an integer")
    return data


def _float(data: Any, where: str) -> float:
    if isinstance(data, bool) or not isinstance(data, int | float):
        raise _bad(where, "a number")
    return float(data)


def _str(data: Any, where: str) -> str:
    if not isinstance(data, str):
        raise _bad(where, "a text")
    return data


_SCALARS: dict[Any, Decoder] = {bool: _bool, int: _int, float: _float, str: _str}
_FLAT = frozenset({bool, int, float, str, type(None)})


def _union(options: tuple[Any, ...]) -> Decoder:
    decoders = [_decoder(option) for option in options]
    names = " or ".join(_describe(option) for option in options)
    not_null = [d for d, option in zip(decoders, options, strict=True) if option is not type(None)]

    def decode_union(data: Any, where: str) -> Any:
        if data is not None and len(not_null) == 1:  # `X | None`: X's own refusal says more
            return not_null[0](data, where)
        for decoder in decoders:
            try:
                return decoder(data, where)
            except Refusal:
                continue
        raise _bad(where, names)

    return decode_union


def _describe(kind: Any) -> str:
    if typing.get_origin(kind) is typing.Annotated:
        kind = typing.get_args(kind)[0]
    return {type(None): "null", bool: "true or false", int: "an integer", str: "a text"}.get(
        kind, "a " + getattr(kind, "__name__", str(kind))
    )


def _list(item: Decoder) -> Decoder:
    def decode_list(data: Any, where: str) -> list[Any]:
        if not isinstance(data, list):
            raise _bad(where, "a list")
        if item is _json_value and all(type(element) in _FLAT for element in data):
            return data  # the 10,000 values of a watch message: a test of each, no call
        return [item(element, f"{where}[{i}]") for i, element in enumerate(data)]

    return decode_list


def _tuple(as_list: Decoder) -> Decoder:
    def decode_tuple(data: Any, where: str) -> tuple[Any, ...]:
        return tuple(as_list(data, where))

    return decode_tuple


def _dict(value: Decoder) -> Decoder:
    def decode_dict(data: Any, where: str) -> dict[str, Any]:
        if not isinstance(data, dict):
            raise _bad(where, "an object")
        return {key: value(element, f"{where}.{key}") for key, element in data.items()}

    return decode_dict


def _literal(options: tuple[Any, ...]) -> Decoder:
    def decode_literal(data: Any, where: str) -> Any:
        if isinstance(data, bool) or data not in options:
            raise _bad(where, "one of " + ", ".join(map(str, options)))
        return data

    return decode_literal


def _enum(kind: type[enum.Enum]) -> Decoder:
    def decode_enum(data: Any, where: str) -> enum.Enum:
        try:
            return kind(data)
        except ValueError:
            raise _bad(where, "one of " + ", ".join(str(m.value) for m in kind)) from None

    return decode_enum


def _constrained(base: Decoder, marks: tuple[Any, ...]) -> Decoder:
    def decode_constrained(data: Any, where: str) -> Any:
        value = base(data, where)
        for mark in marks:
            _check(mark, value, where)
        return value

    return decode_constrained


def _check(mark: Any, value: Any, where: str) -> None:
    if isinstance(mark, Range) and value is not None:
        if mark.low is not None and value < mark.low:
            raise _bad(where, _bounds(mark))
        if mark.high is not None and value > mark.high:
            raise _bad(where, _bounds(mark))
    elif isinstance(mark, MaxLength) and value is not None and len(value) > mark.limit:
        raise _bad(where, f"at most {mark.limit} long")
    elif isinstance(mark, Pattern) and value is not None and not re.fullmatch(mark.regex, value):
        raise _bad(where, mark.explained)


def _bounds(mark: Range) -> str:
    if mark.high is None:
        return f"at least {_number(mark.low)}"
    if mark.low is None:
        return f"at most {_number(mark.high)}"
    return f"from {_number(mark.low)} to {_number(mark.high)}"


def _number(bound: float | None) -> str:
    """As people write it: 1000000000, not 1e+09; 0.5 as 0.5."""
    return str(bound) if isinstance(bound, int) else f"{bound:g}"


def _dataclass(kind: type) -> Decoder:
    hints = typing.get_type_hints(kind, include_extras=True)
    fields = [(f, _decoder(hints[f.name])) for f in _fields(kind) if f.init]
    known = {f.name for f, _ in fields}

    def decode_dataclass(data: Any, where: str) -> Any:
        if not isinstance(data, dict):
            raise _bad(where, "an object")
        unknown = sorted(set(data) - known)
        if unknown:
            raise Refusal("bad_request", f'unknown argument "{_join(where, unknown[0])}"')
        values: dict[str, Any] = {}
        for field, decoder in fields:
            name = _join(where, field.name)
            if field.name in data:
                values[field.name] = decoder(data[field.name], name)
            elif (
                field.default is dataclasses.MISSING
                and field.default_factory is dataclasses.MISSING
            ):
                raise Refusal("bad_request", f'"{name}" is missing')
        return kind(**values)

    return decode_dataclass


def _join(where: str, name: str) -> str:
    return f"{where}.{name}" if where else name
