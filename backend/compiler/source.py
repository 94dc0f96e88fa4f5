"""Source files as the compiler sees them: a display name and the text; and positions in
them, which every AST node and every diagnostic carries."""

from __future__ import annotations

from dataclasses import dataclass
from importlib import resources
from pathlib import Path

from backend.compiler.codes import Code
from backend.compiler.limits import MAX_FILE_BYTES, MAX_PROJECT_BYTES, MAX_PROJECT_FILES, MiB


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


def source_bytes(text: str) -> int:
    """The size of a source in UTF-8, or a lower bound when that is beyond every limit."""
    if len(text) > MAX_PROJECT_BYTES:
        return len(text)
    return len(text.encode("utf-8", "surrogatepass"))


@dataclass
class ProjectSize:
    """A project's files and bytes so far, counted as the compiler takes them one by one;
    of a file too large only what is read of it."""

    files: int = 0
    bytes: int = 0

    def add(self, text: str) -> tuple[Code, str] | None:
        """Count one more file: what is wrong with it, or with the project from now on."""
        size = min(source_bytes(text), MAX_FILE_BYTES + 1)
        self.files += 1
        self.bytes += size
        if self.files > MAX_PROJECT_FILES:
            return Code.PROJECT_SIZE, f"the project has more than {MAX_PROJECT_FILES:,} files"
        if self.bytes > MAX_PROJECT_BYTES:
            mib = MAX_PROJECT_BYTES // MiB
            return Code.PROJECT_SIZE, f"the project's sources are larger than {mib} MiB"
        if size > MAX_FILE_BYTES:
            return Code.FILE_SIZE, f"the file is larger than {MAX_FILE_BYTES // MiB} MiB"
        return None

    @property
    def exceeded(self) -> bool:
        return self.files > MAX_PROJECT_FILES or self.bytes > MAX_PROJECT_BYTES


def read_source(path: Path, display_name: str | None = None) -> SourceFile:
    """A file as the compiler sees it; of one too large to compile only a byte more than
    the limit is read, enough for the compiler to say so."""
    # bytes decoded as a whole: CRLF files keep their columns (the lexer treats \r as white
    # space)
    with path.open("rb") as handle:
        data = handle.read(MAX_FILE_BYTES + 1)
    return SourceFile(display_name or str(path), data.decode("utf-8", "replace"))


def read_sources(files: list[tuple[Path, str]]) -> list[SourceFile]:
    """The files of a project, (path, display name) in order, read until the project is too
    large to compile (the compiler then says so)."""
    sources: list[SourceFile] = []
    size = ProjectSize()
    for path, name in files:
        sources.append(read_source(path, name))
        size.add(sources[-1].text)
        if size.exceeded:
            break
    return sources


def stdlib_sources() -> list[SourceFile]:
    """The standard function blocks written in ST, in a fixed order."""
    folder = resources.files("backend.compiler").joinpath("stdlib")
    names = sorted(entry.name for entry in folder.iterdir() if entry.name.endswith(".st"))
    return [SourceFile(f"stdlib/{name}", folder.joinpath(name).read_text()) for name in names]
