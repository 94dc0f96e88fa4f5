"""Checking a table of settings in padt.toml ([modbus], [opcua]): every problem is a
diagnostic at the line of its setting, under the table's own code, and the check goes on
after one, so that the user sees them all; a wrong setting counts as its default."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from backend.compiler.codes import Code
from backend.compiler.diagnostics import Diagnostic
from backend.compiler.source import Pos
from backend.compiler.toml_lines import line_of


class SettingsChecker:
    def __init__(
        self,
        config_file: str,
        lines: dict[str, int],
        code: Code,
        hints: dict[str, str] | None = None,
    ) -> None:
        """`code`: a setting unknown or wrong; `hints`: what to say of an unknown setting
        by its name, instead of that it is unknown."""
        self.config_file, self.lines, self.code = config_file, lines, code
        self.hints = hints or {}
        self.diagnostics: list[Diagnostic] = []

    def report(self, path: str, code: Code, message: str) -> None:
        pos = Pos(self.config_file, line_of(self.lines, path), 1)
        self.diagnostics.append(Diagnostic.at(pos, code, message))

    def unknown_keys(self, table: dict[str, Any], allowed: tuple[str, ...], path: str) -> None:
        for name in sorted(set(table) - set(allowed)):
            hint = self.hints.get(name, f"unknown setting '{name}'")
            self.report(f"{path}.{name}", self.code, f"[{shown(path)}]: {hint}")

    def setting(
        self,
        table: dict[str, Any],
        name: str,
        path: str,
        default: Any,
        valid: Callable[[Any], bool],
        expected: str,
    ) -> Any:
        """A setting that passes `valid`, or its default after a diagnostic."""
        if name not in table:
            return default
        value = table[name]
        if not valid(value):
            message = f"[{shown(path)}] {name} must be {expected}, not {value!r}"
            self.report(f"{path}.{name}", self.code, message)
            return default
        return value

    def integer(
        self, table: dict[str, Any], name: str, path: str, default: int, low: int, high: int
    ) -> int:
        valid = lambda v: isinstance(v, int) and not isinstance(v, bool) and low <= v <= high  # noqa: E731
        result: int = self.setting(table, name, path, default, valid, f"an integer {low}..{high}")
        return result

    def flag(self, table: dict[str, Any], name: str, path: str, default: bool) -> bool:
        result: bool = self.setting(
            table, name, path, default, lambda v: isinstance(v, bool), "true or false"
        )
        return result

    def choice(
        self, table: dict[str, Any], name: str, path: str, default: str, choices: tuple[str, ...]
    ) -> str:
        expected = " or ".join(f'"{c}"' for c in choices)
        result: str = self.setting(table, name, path, default, choices.__contains__, expected)
        return result


def shown(path: str) -> str:
    """A path as the user wrote the table: `modbus.device` for `modbus.device.0`."""
    return ".".join(part for part in path.split(".") if not part.isdigit())
