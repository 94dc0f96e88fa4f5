"""What the import tells: stable codes and `file:line:col: severity: message [code]` lines.

The codes are the importer's own (P, then four digits), apart from the compiler's: an
import problem is a problem of the XML file, not of ST. docs/plcopen-import.md lists them.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum, unique
from typing import Literal

from backend.compiler.diagnostics import Diagnostic

Severity = Literal["error", "warning"]


@unique
class ImportCode(Enum):
    def __init__(self, id: str, severity: Severity, title: str) -> None:
        self.id = id
        self.severity = severity
        self.title = title

    MALFORMED = "P0001", "error", "the file is not well-formed XML"
    UNSAFE = "P0002", "error", "DOCTYPE, entity declaration or external entity refused"
    NOT_PLCOPEN = "P0003", "error", "not a PLCopen TC6 project"
    STRUCTURE = "P0004", "error", "element or attribute missing or out of place"
    NAME = "P0005", "error", "name that is no IEC identifier"
    NOT_IMPORTED = "P0006", "error", "POUs in IL, or with a part padt does not compile"
    DUPLICATE = "P0007", "error", "POU or data type declared twice"
    TOO_LARGE = "P0008", "error", "file larger than an import takes"
    UNREADABLE = "P0009", "error", "the file cannot be read"
    PARTS_NOT_IMPORTED = "P0010", "error", "CODESYS EXTENDS of a structure not imported"
    DRAWING = "P0011", "error", "FBD or LD body that cannot be read: its POU not imported"
    EXTRA_RESOURCE = "P0101", "warning", "resource or configuration ignored: one per project"
    TASK = "P0102", "warning", "task setting padt cannot keep"
    INSTANCE_LEFT_OUT = "P0103", "warning", "program instance of a POU not imported"
    CONFIGURATION_PART = "P0104", "warning", "VAR_ACCESS or VAR_CONFIG of a configuration"
    TOO_MANY_PROGRAMS = "P0105", "warning", "program instance beyond the 32 a resource runs"


@dataclass(frozen=True)
class Where:
    """A place in the XML file (line and column from 1)."""

    line: int
    col: int


class ImportFailed(Exception):
    """The file cannot be imported at all (nothing is written)."""

    def __init__(self, where: Where, code: ImportCode, message: str) -> None:
        super().__init__(message)
        self.where = where
        self.code = code
        self.message = message

    def diagnostic(self, file: str) -> Diagnostic:
        return diagnostic(file, self.where, self.code, self.message)


def diagnostic(file: str, where: Where, code: ImportCode, message: str) -> Diagnostic:
    return Diagnostic(file, where.line, where.col, code.severity, message, code.id)
