"""How values are shown to people: IEC literals (TRUE, T#1s500ms), not Python reprs."""

from __future__ import annotations

from typing import Any

_TIME_UNITS = (
    ("d", 86_400_000_000_000),
    ("h", 3_600_000_000_000),
    ("m", 60_000_000_000),
    ("s", 1_000_000_000),
    ("ms", 1_000_000),
    ("us", 1_000),
    ("ns", 1),
)


def format_time(nanoseconds: int) -> str:
    if nanoseconds == 0:
        return "T#0s"
    sign, rest = ("-", -nanoseconds) if nanoseconds < 0 else ("", nanoseconds)
    parts = []
    for unit, size in _TIME_UNITS:
        count, rest = divmod(rest, size)
        if count:
            parts.append(f"{count}{unit}")
    return f"T#{sign}{''.join(parts)}"


def format_value(value: Any, type_name: str) -> str:
    if isinstance(value, bool):
        return "TRUE" if value else "FALSE"
    if type_name in ("TIME", "LTIME") and isinstance(value, int):
        return format_time(value)
    if isinstance(value, str):
        return f"'{value}'"
    return str(value)
