"""The type system: elementary IEC types and references to function blocks.

Run-time representation (the artifact documents it for the runtime): integers and bit
strings as Python int kept inside their width, REAL/LREAL as float, BOOL as bool,
TIME/LTIME as int nanoseconds, STRING as str.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class ElementaryType:
    name: str
    category: str  # "bool" | "int" | "bits" | "real" | "time" | "string"
    bits: int = 0
    signed: bool = False

    @property
    def is_integer(self) -> bool:
        return self.category in ("int", "bits")

    @property
    def is_numeric(self) -> bool:
        return self.category in ("int", "bits", "real")

    @property
    def min(self) -> int:
        return -(1 << (self.bits - 1)) if self.signed else 0

    @property
    def max(self) -> int:
        return (1 << (self.bits - 1)) - 1 if self.signed else (1 << self.bits) - 1


@dataclass(frozen=True)
class FbType:
    """An instance of a FUNCTION_BLOCK (or a PROGRAM, for program instances)."""

    name: str


Type = ElementaryType | FbType

BOOL = ElementaryType("BOOL", "bool", 1)
TIME = ElementaryType("TIME", "time", 64, True)
LTIME = ElementaryType("LTIME", "time", 64, True)
REAL = ElementaryType("REAL", "real", 32, True)
LREAL = ElementaryType("LREAL", "real", 64, True)
STRING = ElementaryType("STRING", "string")
WSTRING = ElementaryType("WSTRING", "string")
# The type of an integer literal before the context gives it one.
ANY_INT = ElementaryType("ANY_INT", "int", 64, True)
ANY_REAL = ElementaryType("ANY_REAL", "real", 64, True)

ELEMENTARY: dict[str, ElementaryType] = {
    t.name: t
    for t in (
        BOOL,
        ElementaryType("SINT", "int", 8, True),
        ElementaryType("INT", "int", 16, True),
        ElementaryType("DINT", "int", 32, True),
        ElementaryType("LINT", "int", 64, True),
        ElementaryType("USINT", "int", 8, False),
        ElementaryType("UINT", "int", 16, False),
        ElementaryType("UDINT", "int", 32, False),
        ElementaryType("ULINT", "int", 64, False),
        ElementaryType("BYTE", "bits", 8, False),
        ElementaryType("WORD", "bits", 16, False),
        ElementaryType("DWORD", "bits", 32, False),
        ElementaryType("LWORD", "bits", 64, False),
        REAL,
        LREAL,
        TIME,
        LTIME,
        STRING,
        WSTRING,
    )
}


def common_numeric(a: ElementaryType, b: ElementaryType) -> ElementaryType | None:
    """The type of `a op b` for arithmetic, or None if the operands do not mix."""
    if a == b:
        return a
    if a in (ANY_INT, ANY_REAL) and b.is_numeric:
        return b if b.category == "real" or a == ANY_INT else LREAL
    if b in (ANY_INT, ANY_REAL) and a.is_numeric:
        return a if a.category == "real" or b == ANY_INT else LREAL
    if a.category == b.category == "real":
        return LREAL
    if a.category == b.category and a.is_integer and a.signed == b.signed:
        return a if a.bits >= b.bits else b
    return None


def assignable(target: Type, source: Type) -> bool:
    """Can a value of `source` be stored in `target` without an explicit conversion?"""
    if target == source:
        return True
    if not isinstance(target, ElementaryType) or not isinstance(source, ElementaryType):
        return False
    if source == ANY_INT:
        return target.is_numeric
    if source == ANY_REAL:
        return target.category == "real"
    if target.category == "real" and source.category == "real":
        return target.bits >= source.bits
    if target.category == "time" and source.category == "time":
        return True
    if target.category == "string" and source.category == "string":
        return target.name == source.name
    if target.is_integer and source.is_integer and target.category == source.category:
        # implicit widening only: a wider type of the same signedness, or unsigned -> wider signed
        if target.signed == source.signed:
            return target.bits >= source.bits
        return target.signed and target.bits > source.bits
    return False
