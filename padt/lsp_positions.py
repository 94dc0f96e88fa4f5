"""Positions between an LSP client and the language services.

LSP counts lines from 0 and characters in code units of the encoding agreed at
initialisation (UTF-16 unless the client offers another); the language services count
lines and columns from 1 in characters of the Python string. Everything that crosses
between them goes through this module, so that a comment with "ü", "≥" or "😀" before the
cursor does not shift the place by one or two.

Lines end at "\\n" only, as the compiler counts them (a "\\r" before it is the line's
last character; a lone "\\r" is not a line break to the compiler, so it is none here)."""

from __future__ import annotations

from dataclasses import dataclass

from lsprotocol import types

UTF8 = types.PositionEncodingKind.Utf8.value
UTF16 = types.PositionEncodingKind.Utf16.value
UTF32 = types.PositionEncodingKind.Utf32.value


def width(text: str, encoding: str) -> int:
    """The code units of `text` in `encoding`."""
    if encoding == UTF32:
        return len(text)
    if encoding == UTF16:  # a character beyond the BMP is a surrogate pair
        return len(text) + sum(1 for char in text if ord(char) > 0xFFFF)
    return len(text.encode("utf-8", "surrogatepass"))


@dataclass(frozen=True)
class Lines:
    """A text split into its lines once, for the many positions of one request."""

    text: str
    starts: tuple[int, ...]  # the offset of each line's first character

    @classmethod
    def of(cls, text: str) -> Lines:
        starts = [0]
        at = text.find("\n")
        while at >= 0:
            starts.append(at + 1)
            at = text.find("\n", at + 1)
        return cls(text, tuple(starts))

    def line(self, index: int) -> str:
        """The line at 0-based `index` without its "\\n"."""
        end = self.starts[index + 1] - 1 if index + 1 < len(self.starts) else len(self.text)
        return self.text[self.starts[index] : end]

    def offset(self, position: types.Position, encoding: str) -> int:
        """The offset in the text of an LSP position. A line past the end is the end of
        the text, a character past the line's end its end (as LSP asks), a character in
        the middle of a character's units the character after it."""
        if position.line >= len(self.starts):
            return len(self.text)
        line = self.line(position.line)  # lsprotocol refuses a negative one
        counted = 0
        for index, char in enumerate(line):
            if counted >= position.character:
                return self.starts[position.line] + index
            counted += width(char, encoding)
        return self.starts[position.line] + len(line)

    def place(self, position: types.Position, encoding: str) -> tuple[int, int]:
        """The services' (line, col), both from 1, of an LSP position."""
        offset = self.offset(position, encoding)
        line = min(position.line, len(self.starts) - 1)
        return line + 1, offset - self.starts[line] + 1

    def position(self, line: int, col: int, encoding: str) -> types.Position:
        """The LSP position of the services' (line, col); a place past the text is its
        end, a column past its line the line's end."""
        if line > len(self.starts):
            last = len(self.starts) - 1
            return types.Position(last, width(self.line(last), encoding))
        text = self.line(max(line, 1) - 1)
        return types.Position(max(line, 1) - 1, width(text[: max(col, 1) - 1], encoding))

    def range(self, line: int, col: int, end_line: int, end_col: int, encoding: str) -> types.Range:
        return types.Range(
            self.position(line, col, encoding), self.position(end_line, end_col, encoding)
        )


def edited(text: str, change: types.TextDocumentContentChangeEvent, encoding: str) -> str:
    """The text after one change of `textDocument/didChange`: a range replaced, or all."""
    if isinstance(change, types.TextDocumentContentChangeWholeDocument):
        return change.text
    lines = Lines.of(text)
    start = lines.offset(change.range.start, encoding)
    end = max(start, lines.offset(change.range.end, encoding))
    return text[:start] + change.text + text[end:]
