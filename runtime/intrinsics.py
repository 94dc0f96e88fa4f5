"""What generated code may call: the runtime's side of the artifact contract.

Generated source runs with exactly these names in its global namespace (plus the classes
of the other POUs). `docs/artifact.md` lists them; changing one is a new artifact version.
"""

from __future__ import annotations

import builtins
import math
import struct
from dataclasses import dataclass
from typing import Any


class ProgramFault(Exception):
    """A run-time error of a user program (puts that program in ERROR)."""


class DivisionByZero(ProgramFault):
    def __init__(self) -> None:
        super().__init__("integer division by zero")


@dataclass
class SystemView:
    """The system values a program sees; the scheduler sets them before each program cycle."""

    now_ns: int = 0


def _idiv(a: int, b: int) -> int:
    """IEC integer division: truncates toward zero; division by zero is a program error."""
    if b == 0:
        raise DivisionByZero()
    q = abs(a) // abs(b)
    return q if (a >= 0) == (b >= 0) else -q


def _imod(a: int, b: int) -> int:
    if b == 0:
        raise DivisionByZero()
    return a - b * _idiv(a, b)


def _fdiv(a: float, b: float) -> float:
    if b == 0:
        if a == 0 or math.isnan(a):
            return math.nan
        return math.copysign(math.inf, a) * math.copysign(1.0, b)
    return a / b


def _tdiv(a: int, b: float) -> int:
    if b == 0:
        raise DivisionByZero()
    return int(a / b)


def _pow(a: float, b: float) -> float:
    try:
        result: float = float(a) ** b
        return result
    except (ZeroDivisionError, OverflowError):
        return math.inf


_F32 = struct.Struct("f")


def _f32(value: float) -> float:
    """Round to the nearest IEEE 754 single (REAL is 32 bit)."""
    try:
        return float(_F32.unpack(_F32.pack(value))[0])
    except OverflowError:
        return math.copysign(math.inf, value)


def namespace(system: SystemView) -> dict[str, Any]:
    """A fresh global namespace for one resource's generated code."""
    return {
        # only what generated classes need: user code cannot reach open(), import, ...
        "__builtins__": {
            "__build_class__": builtins.__build_class__,
            "float": float,
            "int": int,
            "abs": abs,
        },
        "__name__": "padt_generated",
        "_SYS": system,
        "_idiv": _idiv,
        "_imod": _imod,
        "_fdiv": _fdiv,
        "_tdiv": _tdiv,
        "_pow": _pow,
        "_f32": _f32,
    }
