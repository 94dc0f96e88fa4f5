"""Compiler diagnostics, printed as `file:line:col: severity: message [code]`.

That is the form of gcc and clang, which the problem matchers of editors and CI read; the
code (from `codes`) comes last so that matchers written for the form without it still work.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from backend.compiler.codes import Code, Severity
from backend.compiler.source import Pos

QUOTE_MAX = 120  # characters of a name quoted in a message, beyond which it is cut
_LONG_QUOTE = re.compile(rf"'([^'\n]{{{QUOTE_MAX + 1},}})'")


def clipped(message: str) -> str:
    """The message with every quoted name longer than QUOTE_MAX cut to its start and its
    end: a name of 5,000 parts made a diagnostic of 58 KB, in a terminal or the browser."""
    return _LONG_QUOTE.sub(lambda m: f"'{shortened(m.group(1))}'", message)


def shortened(text: str) -> str:
    """`text` as a message shows it: over QUOTE_MAX characters, its start and its end."""
    return text if len(text) <= QUOTE_MAX else f"{text[:80]}[...]{text[-30:]}"


@dataclass(frozen=True, order=True)
class Diagnostic:
    file: str
    line: int
    col: int
    severity: Severity
    message: str
    code: str  # the id of a `Code`; last, so that diagnostics sort by place as before

    @classmethod
    def at(cls, pos: Pos, code: Code, message: str) -> Diagnostic:
        """A diagnostic of `code` at `pos`, with the severity of the code."""
        return cls(pos.file, pos.line, pos.col, code.severity, clipped(message), code.id)

    def __str__(self) -> str:
        return f"{self.file}:{self.line}:{self.col}: {self.severity}: {self.message} [{self.code}]"

    def as_json(self) -> dict[str, object]:
        return {
            "file": self.file,
            "line": self.line,
            "col": self.col,
            "severity": self.severity,
            "message": self.message,
            "code": self.code,
        }


class CompileError(Exception):
    """Raised by a stage that cannot go on; carries every diagnostic found so far."""

    def __init__(self, diagnostics: list[Diagnostic]) -> None:
        super().__init__("\n".join(str(d) for d in diagnostics))
        self.diagnostics = diagnostics
