"""The value representation of the contract (docs/artifact.md): how each IEC elementary
type is held at run time and on the bus (BOOL as a boolean, integers as integers in the
range of their type, REAL rounded to 32 bits, TIME as integer nanoseconds, strings as
text), how a value from outside is checked against its type, and how values are shown to
people (IEC literals: TRUE, T#1s500ms, not Python reprs).
"""

from __future__ import annotations

import fractions
import functools
import itertools
import math
import re
import struct
from collections.abc import Callable
from dataclasses import dataclass
from datetime import datetime, timedelta
from typing import Any


@dataclass(frozen=True)
class ArrayShape:
    dims: tuple[tuple[int, int], ...]
    element: str  # type name of one element (itself an array type for arrays of arrays)

    def indices(self) -> list[str]:
        """IEC index texts ("2", "0,1") in the order of the flat list: last index fastest,
        as generated code lays multi-dimensional arrays out."""
        ranges = [range(low, high + 1) for low, high in self.dims]
        return [",".join(map(str, index)) for index in itertools.product(*ranges)]


_ARRAY = re.compile(r"ARRAY\[([^\]]*)\] OF (.+)", re.IGNORECASE)


def array_shape(type_name: str) -> ArrayShape | None:
    """`ARRAY[0..1, 1..3] OF INT` -> its bounds and element type; None for other types."""
    match = _ARRAY.fullmatch(type_name)
    if match is None:
        return None
    dims = []
    for part in match.group(1).split(","):
        low, _, high = part.strip().partition("..")
        dims.append((int(low), int(high)))
    return ArrayShape(tuple(dims), match.group(2))


_F32 = struct.Struct("f")


def to_real32(value: float) -> float:
    """Round to the nearest IEEE 754 single (REAL is 32 bit)."""
    try:
        return float(_F32.unpack(_F32.pack(value))[0])
    except OverflowError:
        return math.copysign(math.inf, value)


_TIME_UNITS = (
    ("d", 86_400_000_000_000), ("h", 3_600_000_000_000), ("m", 60_000_000_000),
    ("s", 1_000_000_000), ("ms", 1_000_000), ("us", 1_000), ("ns", 1),
)  # fmt: skip


_UNIT_NS = {unit.upper(): size for unit, size in _TIME_UNITS}
_TIME_PART = re.compile(r"([0-9][0-9_]*(?:\.[0-9_]+)?)(D|H|MS|M|S|US|NS)", re.IGNORECASE)


def parse_time_literal(text: str) -> tuple[int, bool]:
    """`T#1h2m3.5s` -> (nanoseconds, is_LTIME): what the compiler and a debugger's
    conditions read a duration literal as."""
    prefix, _, body = text.partition("#")
    negative = body.startswith("-")
    body = body.lstrip("-")
    total = 0
    for number, unit in _TIME_PART.findall(body):
        # exact decimal arithmetic: LT#123456789.123456789s must keep its last nanosecond
        value = fractions.Fraction(number.replace("_", ""))
        total += round(value * _UNIT_NS[unit.upper()])
    return (-total if negative else total), prefix.upper() in ("LT", "LTIME")


def format_time(ns: int, prefix: str = "T#") -> str:
    """TIME_TO_STRING: `T#1h2m3s4ms`, the largest units first, zero parts left out (also how
    the PADT shows TIME values)."""
    if ns == 0:
        return f"{prefix}0s"
    sign, rest = ("-", -ns) if ns < 0 else ("", ns)
    parts = []
    for unit, size in _TIME_UNITS:
        count, rest = divmod(rest, size)
        if count:
            parts.append(f"{count}{unit}")
    return f"{prefix}{sign}{''.join(parts)}"


# the prefixes ST writes the dates with (TIME_TO_STRING and friends print the same)
_DATE_PREFIXES = {
    "DATE": "D#", "LDATE": "LDATE#", "TOD": "TOD#", "LTOD": "LTOD#", "DT": "DT#", "LDT": "LDT#",
}  # fmt: skip
_EPOCH = datetime(1970, 1, 1)


def format_date(ns: int, type_name: str) -> str:
    """A DATE, TOD or DT (or an L form) held as nanoseconds since 1970 (TOD: since
    midnight) as its literal: `D#2024-01-15`, `TOD#12:30:05.5`, `DT#2024-01-15-12:30:05`.
    A count no calendar date holds (before year 1, after 9999) stays a number."""
    seconds, fraction = divmod(ns, 1_000_000_000)
    try:
        moment = _EPOCH + timedelta(seconds=seconds)
    except OverflowError:
        return str(ns)
    day = f"{moment.year:04d}-{moment.month:02d}-{moment.day:02d}"
    clock = f"{moment.hour:02d}:{moment.minute:02d}:{moment.second:02d}"
    clock += f".{fraction:09d}".rstrip("0") if fraction else ""
    kind = type_name.upper()
    if kind in ("DATE", "LDATE"):
        return f"{_DATE_PREFIXES[kind]}{day}"
    if kind in ("TOD", "LTOD"):
        return f"{_DATE_PREFIXES[kind]}{clock}"
    return f"{_DATE_PREFIXES[kind]}{day}-{clock}"


def jsonable(value: Any) -> Any:
    """A run-time value as strict JSON takes it: non-finite REALs as text."""
    if isinstance(value, float) and not math.isfinite(value):
        return repr(value)
    if isinstance(value, list):
        return [jsonable(item) for item in value]
    return value


# ---- run-time representation of elementary values (docs/artifact.md)

_INT_RANGES: dict[str, tuple[int, int]] = {
    **{name: (-(1 << (bits - 1)), (1 << (bits - 1)) - 1)
       for name, bits in (("SINT", 8), ("INT", 16), ("DINT", 32), ("LINT", 64))},
    **{name: (0, (1 << bits) - 1)
       for name, bits in (("USINT", 8), ("UINT", 16), ("UDINT", 32), ("ULINT", 64),
                          ("BYTE", 8), ("WORD", 16), ("DWORD", 32), ("LWORD", 64))},
    # durations and dates are 64-bit nanosecond counts
    **dict.fromkeys(("TIME", "LTIME", "DATE", "LDATE", "TOD", "LTOD", "DT", "LDT"),
                    (-(1 << 63), (1 << 63) - 1)),
}  # fmt: skip
_REALS = ("REAL", "LREAL")


def int_range(type_name: str) -> tuple[int, int] | None:
    """The values an integer type (also TIME and the dates, as nanoseconds) holds; None for
    any other type."""
    return _INT_RANGES.get(type_name.upper())


_STRINGS = ("STRING", "WSTRING", "CHAR", "WCHAR")
TIME_TYPES = ("TIME", "LTIME")


def base_type(type_name: str) -> tuple[str, int]:
    """`STRING[4]` -> ("STRING", 4); other names -> (name, 0). The artifact keeps string
    lengths in the type name."""
    name, _, rest = type_name.upper().partition("[")
    return name, int(rest.rstrip("]")) if rest.rstrip("]").isdigit() else 0


class ValueRejected(ValueError):
    """A value that a variable of the given type cannot hold; the message says why."""


REFERENCE_PREFIXES = ("REF_TO ", "POINTER TO ", "REFERENCE TO ", "INTERFACE ")


def is_reference_type(type_name: str) -> bool:
    """`REF_TO INT` and the like: a reference, which the program alone sets; at run time it
    reads as the path of what it refers to, or None for NULL. A variable of an interface
    type (`INTERFACE IMotor`) is a reference to the instance assigned to it."""
    return type_name.upper().startswith(REFERENCE_PREFIXES)


def representation(type_name: str, value: Any) -> Any:
    """`value` as generated code keeps a variable of `type_name`, or ValueRejected.

    Generated code relies on every stored value being in the range of its type (it wraps at
    each store), so values from outside (OLT, simulation) are checked, never wrapped.
    """
    if is_reference_type(type_name):
        raise ValueRejected(
            f"a reference ({type_name}) is set by the program only: it cannot be written or forced"
        )
    name, length = base_type(type_name)
    if name == "BOOL":
        if isinstance(value, bool):
            return value
        raise ValueRejected(f"type BOOL takes TRUE or FALSE, not {value!r}")
    if name in _INT_RANGES:
        if isinstance(value, bool) or not isinstance(value, int):
            raise ValueRejected(f"type {name} takes an integer, not {value!r}")
        low, high = _INT_RANGES[name]
        if not low <= value <= high:
            raise ValueRejected(f"{value} is outside the range of {name} ({low}..{high})")
        return value
    if name in _REALS:
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise ValueRejected(f"type {name} takes a number, not {value!r}")
        try:
            number = float(value)
        except OverflowError:
            raise ValueRejected(f"{value} is outside the range of {name}") from None
        if name == "LREAL":
            return number
        single = to_real32(number)
        if math.isinf(single) and math.isfinite(number):
            raise ValueRejected(f"{value} is outside the range of REAL")
        return single
    if name in _STRINGS:
        if not isinstance(value, str):
            raise ValueRejected(f"type {name} takes a string, not {value!r}")
        if name in ("CHAR", "WCHAR") and len(value) > 1:  # '' is the NUL character
            raise ValueRejected(f"type {name} takes one character, not {value!r}")
        if length and len(value) > length:
            raise ValueRejected(f"type {type_name} holds at most {length} characters")
        return value
    raise ValueRejected(f"variables of type {type_name} cannot be written")


@functools.cache
def representation_of(type_name: str) -> Callable[[Any], Any]:
    """`representation` for one type, found once: for values that come by the thousand (a
    message of the exchange between resources), the common case of each elementary type is
    checked at once, and anything else goes through `representation` with its reasons."""
    name, _ = base_type(type_name)
    slow = functools.partial(representation, type_name)
    if is_reference_type(type_name):
        return slow
    if name == "BOOL":
        return lambda value: value if type(value) is bool else slow(value)
    if name in _INT_RANGES:
        low, high = _INT_RANGES[name]
        return lambda value: value if type(value) is int and low <= value <= high else slow(value)
    if name == "LREAL":
        return lambda value: value if type(value) is float else slow(value)
    return slow


def format_value(value: Any, type_name: str) -> str:
    """A run-time value as the ST literal of its type (TRUE, T#1s500ms, D#2024-01-15,
    'text'; an array as `[1, 2]` of its elements' literals): what the CLI, the API and the
    UI show."""
    if is_reference_type(type_name):
        return "NULL" if value is None else str(value)
    if isinstance(value, bool):
        return "TRUE" if value else "FALSE"
    if isinstance(value, list):
        shape = array_shape(type_name)
        element = shape.element if shape is not None else type_name
        return "[" + ", ".join(format_value(item, element) for item in value) + "]"
    if type_name in ("TIME", "LTIME") and isinstance(value, int):
        return format_time(value, "LTIME#" if type_name == "LTIME" else "T#")
    if type_name.upper() in _DATE_PREFIXES and isinstance(value, int):
        return format_date(value, type_name)
    if type_name in _REALS and value in ("inf", "-inf", "nan"):
        return str(value)  # a non-finite REAL as JSON carries it (`jsonable`): no string
    if isinstance(value, str):
        return f"'{value}'"
    return str(value)


MILLISECOND = 1_000_000


def format_for_display(value: Any, type_name: str, time_resolution_ns: int = MILLISECOND) -> str:
    """A value as an engineer reads it on a screen: TIME cut to `time_resolution_ns` (ms
    unless asked for more), REAL with the 7 significant digits a single holds (LREAL 15),
    everything else as `format_value`. Exact values (CLI, API) keep `format_value`."""
    if type_name in ("TIME", "LTIME") and isinstance(value, int) and not isinstance(value, bool):
        cut = abs(value) // time_resolution_ns * time_resolution_ns  # toward zero, as clocks
        return format_value(-cut if value < 0 else cut, type_name)
    if isinstance(value, float) and math.isfinite(value):
        return f"{value:.{15 if type_name == 'LREAL' else 7}g}"
    return format_value(value, type_name)
