"""The size in bytes CODESYS gives a value (SIZEOF, a CODESYS/TwinCAT extension).

padt keeps values as Python objects, so these sizes describe no memory of its own: they are
what CODESYS V3 reports on a 64-bit target with the default packing (`pack_mode` 8), so that
code computing buffer lengths with SIZEOF gets the numbers it was written for. A structure
lays out its members in order, each at a multiple of its own alignment (at most 8), and
ends padded to a multiple of its largest alignment; an array is its elements back to back;
a STRING[n] takes n + 1 bytes, a WSTRING[n] 2 (n + 1); TIME, DATE, TOD and DT are 32-bit
as in CODESYS, their L-forms 64-bit; a reference or pointer 8. A function block instance
has no size here: CODESYS adds hidden members of its own implementation to it.
"""

from __future__ import annotations

from dataclasses import dataclass

from backend.compiler.ast import key
from backend.compiler.resolve import Resolved
from backend.compiler.types import (
    ArrayType,
    ElementaryType,
    EnumType,
    RefType,
    StructType,
    Type,
)

MAX_ALIGNMENT = 8  # CODESYS pack_mode 8, the default on 64-bit targets
_THIRTY_TWO_BIT_TIMES = ("TIME", "DATE", "TOD", "DT")


@dataclass(frozen=True)
class Layout:
    size: int
    alignment: int


def codesys_layout(resolved: Resolved, value_type: Type) -> Layout | None:
    """The size and alignment of `value_type` in CODESYS; None when it has none here."""
    match value_type:
        case ElementaryType():
            return _elementary(value_type)
        case EnumType(base=base):
            return _elementary(base)
        case RefType():
            return Layout(8, 8)  # an address on a 64-bit target
        case ArrayType(element=element):
            inner = codesys_layout(resolved, element)
            return None if inner is None else Layout(inner.size * value_type.size, inner.alignment)
        case StructType(name=name):
            offset, alignment = 0, 1
            for member in resolved.structs[key(name)].members:
                layout = codesys_layout(resolved, member.type)
                if layout is None:
                    return None
                offset = _aligned(offset, layout.alignment) + layout.size
                alignment = max(alignment, layout.alignment)
            return Layout(_aligned(offset, alignment), alignment)
    return None


def _elementary(value_type: ElementaryType) -> Layout:
    if value_type.category == "string":
        wide = value_type.name in ("WSTRING", "WCHAR")
        if value_type.name in ("CHAR", "WCHAR"):
            return Layout(2 if wide else 1, 2 if wide else 1)
        count = value_type.max_length + 1
        return Layout(2 * count, 2) if wide else Layout(count, 1)
    if value_type.category == "bool":
        return Layout(1, 1)
    bits = 32 if value_type.name in _THIRTY_TWO_BIT_TIMES else value_type.bits
    size = bits // 8
    return Layout(size, min(size, MAX_ALIGNMENT))


def _aligned(offset: int, alignment: int) -> int:
    return -(-offset // alignment) * alignment
