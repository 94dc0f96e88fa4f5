"""The server's copy of a document open in the browser's editor: its lines, the version
the browser numbered its last changes with, and the hash of the file it was read from
(the base a save names). The browser sends changes, never the whole text per keystroke;
they are applied here to the lines they touch."""

from __future__ import annotations

from dataclasses import dataclass, field

from frontend.editor.messages import MAX_TEXT, TextChange


class BadChange(ValueError):
    """Changes that do not fit the text: the browser and the server disagree."""


@dataclass
class Document:
    project: str
    file: str
    base_hash: str  # of the file on disk the text was read from, or last saved
    lines: list[str] = field(default_factory=lambda: [""])
    version: int = 0
    saved_version: int = 0  # the version that is on disk (unchanged since)
    disk_changed: bool = False  # another tool or user changed the file since

    @classmethod
    def of(cls, project: str, file: str, text: str, base_hash: str) -> Document:
        return cls(project, file, base_hash, text.split("\n"))

    def text(self) -> str:
        return "\n".join(self.lines)

    def apply(self, version: int, changes: tuple[TextChange, ...]) -> None:
        """The browser's changes, ascending positions in the text before them; applied from
        the last so that the earlier positions still hold. BadChange when a position is
        outside the text or the version does not follow."""
        if version != self.version + 1:
            raise BadChange(f"version {version} does not follow {self.version}")
        lines = self.lines
        previous: tuple[int, int] | None = None
        for change in changes:
            start, end = (change.from_line, change.from_col), (change.to_line, change.to_col)
            if start > end:
                raise BadChange("a change ends before it starts")
            if previous is not None and start < previous:
                raise BadChange("changes overlap or are out of order")
            previous = end
        grown = sum(len(c.insert) for c in changes)
        if sum(len(line) + 1 for line in lines) + grown > MAX_TEXT:
            raise BadChange("the text would be larger than a file may be")
        for change in reversed(changes):
            if change.to_line > len(lines):
                raise BadChange(f"line {change.to_line} is past the end of the text")
            first, last = lines[change.from_line - 1], lines[change.to_line - 1]
            head = first[: python_col(first, change.from_col)]
            tail = last[python_col(last, change.to_col) :]
            replaced = (head + change.insert + tail).split("\n")
            lines[change.from_line - 1 : change.to_line] = replaced
        self.version = version

    def line(self, number: int) -> str:
        return self.lines[number - 1] if 1 <= number <= len(self.lines) else ""


def python_col(line: str, utf16_col: int) -> int:
    """The index in `line` of a 0-based column counted in UTF-16 code units (the
    browser's); BadChange past the line's end."""
    if line.isascii() or all(ord(c) < 0x10000 for c in line):
        if utf16_col > len(line):
            raise BadChange(f"column {utf16_col} is past the end of its line")
        return utf16_col
    units = 0
    for index, char in enumerate(line):
        if units >= utf16_col:
            if units > utf16_col:
                raise BadChange("a column splits a character")
            return index
        units += 2 if ord(char) >= 0x10000 else 1
    if units != utf16_col:
        raise BadChange(f"column {utf16_col} is past the end of its line")
    return len(line)


def utf16_col(line: str, col: int) -> int:
    """The 0-based UTF-16 column of the 0-based index `col` in `line`."""
    head = line[:col]
    return len(head) + sum(1 for c in head if ord(c) >= 0x10000)
