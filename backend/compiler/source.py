"""Source files as the compiler sees them: a display name and the text; and positions in
them, which every AST node and every diagnostic carries."""

from __future__ import annotations

from dataclasses import dataclass
from importlib import resources
from pathlib import Path


@dataclass(frozen=True)
class Pos:
    file: str
    line: int
    col: int

    def __str__(self) -> str:
        return f"{self.file}:{self.line}:{self.col}"


@dataclass(frozen=True)
class SourceFile:
    name: str  # shown in diagnostics: a path relative to the project, or stdlib/<file>
    text: str


def read_source(path: Path, display_name: str | None = None) -> SourceFile:
    # newline="" keeps CRLF files' columns right; the lexer treats \r as white space
    with path.open(encoding="utf-8", errors="replace", newline="") as handle:
        return SourceFile(display_name or str(path), handle.read())


def stdlib_sources() -> list[SourceFile]:
    """The standard function blocks written in ST, in a fixed order."""
    folder = resources.files("backend.compiler").joinpath("stdlib")
    names = sorted(entry.name for entry in folder.iterdir() if entry.name.endswith(".st"))
    return [SourceFile(f"stdlib/{name}", folder.joinpath(name).read_text()) for name in names]
