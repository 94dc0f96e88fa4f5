"""Setting what a viser input shows. viser defines the `value` setter apart from its
getter, which mypy reads as a read-only property; this is the one place that says so."""

from __future__ import annotations

from typing import Any


def set_value(handle: Any, value: Any) -> None:
    handle.value = value
