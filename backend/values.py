"""How values are shown to people: IEC literals (TRUE, T#1s500ms), not Python reprs."""

from __future__ import annotations

from typing import Any

from runtime.intrinsics import format_time


def format_value(value: Any, type_name: str) -> str:
    if isinstance(value, bool):
        return "TRUE" if value else "FALSE"
    if type_name in ("TIME", "LTIME") and isinstance(value, int):
        return format_time(value, "LTIME#" if type_name == "LTIME" else "T#")
    if isinstance(value, str):
        return f"'{value}'"
    return str(value)
