"""Compiler diagnostics, reported as `file:line:col: severity: message`."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from backend.compiler.source import Pos

Severity = Literal["error", "warning"]


@dataclass(frozen=True, order=True)
class Diagnostic:
    file: str
    line: int
    col: int
    severity: Severity
    message: str

    def __str__(self) -> str:
        return f"{self.file}:{self.line}:{self.col}: {self.severity}: {self.message}"

    def as_json(self) -> dict[str, object]:
        return {
            "file": self.file,
            "line": self.line,
            "col": self.col,
            "severity": self.severity,
            "message": self.message,
        }


def error(pos: Pos, message: str) -> Diagnostic:
    return Diagnostic(pos.file, pos.line, pos.col, "error", message)


def warning(pos: Pos, message: str) -> Diagnostic:
    return Diagnostic(pos.file, pos.line, pos.col, "warning", message)


class CompileError(Exception):
    """Raised by a stage that cannot go on; carries every diagnostic found so far."""

    def __init__(self, diagnostics: list[Diagnostic]) -> None:
        super().__init__("\n".join(str(d) for d in diagnostics))
        self.diagnostics = diagnostics
