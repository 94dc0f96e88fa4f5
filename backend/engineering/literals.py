"""ST literals typed by a person (`TRUE`, `-3.5`, `16#FF`, `T#20ms`, `'text'`) as values of
a variable's type in the run-time representation: what `padt sim --set`, `padt write` and
`padt force set` take, and the REST API's `literal` of a write or a force. The compiler's
own literal rules decide, so a value means here what it means in a program. The other way,
values as literals (`literals_of`), is what `padt values --json` and the REST API give
beside the run-time values."""

from __future__ import annotations

import re
from collections.abc import Mapping
from typing import Any

from backend.compiler.parse import (
    BadEscape,
    decode_string_literal,
    parse_date_literal,
    parse_int_literal,
)
from runtime.contract.protocol import WatchValues
from runtime.contract.values import (
    TIME_TYPES,
    base_type,
    format_value,
    is_reference_type,
    parse_time_literal,
)
from runtime.contract.wire import encode


class LiteralError(ValueError):
    """Text that is no ST literal of the type; the message says what is expected."""


_INT = re.compile(r"([+-]?)((?:2|8|16)#[0-9A-Fa-f_]+|[0-9][0-9_]*)")
_REAL = re.compile(r"[+-]?[0-9][0-9_]*(?:\.[0-9][0-9_]*)?(?:[eE][+-]?[0-9]+)?")
_TIME = re.compile(
    r"(?:T|TIME|LT|LTIME)#[+-]?(?:[0-9][0-9_]*(?:\.[0-9_]+)?(?:MS|US|NS|D|H|M|S))+",
    re.IGNORECASE,
)
_TYPED = re.compile(r"([A-Za-z_][A-Za-z0-9_]*)#(.+)", re.DOTALL)
_INTEGERS = (
    *("SINT", "INT", "DINT", "LINT", "USINT", "UINT", "UDINT", "ULINT"),
    *("BYTE", "WORD", "DWORD", "LWORD"),
)
_DATES = ("DATE", "LDATE", "TOD", "LTOD", "DT", "LDT")
_STRING_TYPES = {"STRING": False, "CHAR": False, "WSTRING": True, "WCHAR": True}  # -> wide
_TYPE_PREFIXES = {"BOOL", "REAL", "LREAL", *_INTEGERS, *_STRING_TYPES}
_SETTABLE = {*_TYPE_PREFIXES, *TIME_TYPES, *_DATES}


def parse_literal(text: str, type_name: str) -> Any:
    """An ST literal (`TRUE`, `-3.5`, `16#FF`, `T#20ms`, `'text'`) as a value of
    `type_name` in its run-time representation (TIME in nanoseconds)."""
    if is_reference_type(type_name):
        raise LiteralError(
            f"a reference ({type_name}) is set by the program only: it cannot be written or forced"
        )
    target, _length = base_type(type_name)  # the length is checked when the value is written
    if target not in _SETTABLE:  # enumerations, arrays: the artifact has no literals for them
        raise LiteralError(f"variables of type {type_name} cannot be set")
    literal = text.strip()
    typed = _TYPED.fullmatch(literal)
    if typed is not None and typed[1].upper() in _TYPE_PREFIXES:
        literal = typed[2]  # `INT#5`, `BOOL#TRUE`: the variable's type decides
    value = _literal_value(literal, target)
    if value is None:
        hint = ""
        if target in _STRING_TYPES:  # a shell eats the quotes of `s='text'`
            hint = f"; text is written in quotes: '{text}' (in a shell: \"'{text}'\")"
        raise LiteralError(f"{text} is not an ST literal of type {type_name}{hint}")
    return value


def literals_of(values: Mapping[str, Any], types: Mapping[str, str]) -> dict[str, str]:
    """Each value of `values` (by path) as the ST literal of its variable's type (`types`
    by path, as `get_variables` lists them): `T#1s500ms`, `D#2024-01-15`, `TRUE`."""
    return {path: format_value(value, types.get(path, "")) for path, value in values.items()}


def watch_values_shown(message: WatchValues, types: Mapping[str, str]) -> dict[str, Any]:
    """A watch set's message as JSON, each entry with its `literal` beside `value` and
    `quality` (the REST API's live WebSocket, `padt values --follow --json`)."""
    shown: dict[str, Any] = encode(message)
    for path, entry in shown["values"].items():
        entry["literal"] = format_value(message.values[path].value, types.get(path, ""))
    return shown


def _literal_value(literal: str, target: str) -> Any:
    if target == "BOOL":
        return {"TRUE": True, "FALSE": False, "1": True, "0": False}.get(literal.upper())
    if target in _INTEGERS:
        return _int_value(literal)
    if target in ("REAL", "LREAL"):
        if _REAL.fullmatch(literal):
            return float(literal.replace("_", ""))
        return None
    if target in TIME_TYPES:
        if not _TIME.fullmatch(literal):
            return None
        try:
            return parse_time_literal(literal)[0]
        except OverflowError:  # more seconds than a float holds: far beyond any TIME
            return None
    if target in _DATES:
        return _date_value(literal, target)
    return _string_value(literal, _STRING_TYPES[target])


def _int_value(literal: str) -> int | None:
    match = _INT.fullmatch(literal)
    if match is None:
        return None
    try:
        magnitude = parse_int_literal(match[2])
    except ValueError:  # digits outside the base (2#12), or none at all (16#_)
        return None
    return -magnitude if match[1] == "-" else magnitude


def _date_value(literal: str, target: str) -> int | None:
    try:
        kind, ns = parse_date_literal(literal)
    except (KeyError, ValueError, IndexError):  # no date prefix, or a malformed date
        return None
    return ns if kind == target else None


def _string_value(literal: str, wide: bool) -> str | None:
    if len(literal) < 2 or literal[0] not in "'\"" or literal[-1] != literal[0]:
        return None
    try:
        return decode_string_literal(literal[1:-1], wide)
    except BadEscape as exc:
        raise LiteralError(f"{literal}: {exc}") from None
