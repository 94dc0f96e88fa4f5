"""A file's text cut where its top-level declarations start (POU, TYPE, VAR_GLOBAL,
CONFIGURATION, INTERFACE), so that a keystroke re-parses the one declaration it changed.

The cut is made by reading the text as the lexer does (comments, strings and pragmas hide
keywords) and following each declaration to its END keyword; each chunk starts at the start
of a line, so its columns are the file's and only its lines are offset. METHOD, PROPERTY
and ACTIONS after a block stay in the chunk before them: they belong to the block."""

from __future__ import annotations

import re
from dataclasses import dataclass

from backend.compiler.limits import MAX_COMMENT_NESTING
from backend.compiler.parse import nested_comment

# the declarations a chunk may start with, and the keyword that ends each
_CHUNK_STARTS = {
    "PROGRAM": "END_PROGRAM",
    "FUNCTION_BLOCK": "END_FUNCTION_BLOCK",
    "FUNCTION": "END_FUNCTION",
    "TYPE": "END_TYPE",
    "VAR_GLOBAL": "END_VAR",
    "CONFIGURATION": "END_CONFIGURATION",
    "INTERFACE": "END_INTERFACE",
}
# top-level declarations that belong to the declaration before them
_ATTACHED = {"METHOD": "END_METHOD", "PROPERTY": "END_PROPERTY", "ACTIONS": "END_ACTIONS"}

# what the lexer skips or reads as one token, in the grammar's order of priority: a keyword
# inside any of these is no keyword; a word (group 1) may be one
_TOKENS = re.compile(
    "|".join(
        (
            nested_comment(MAX_COMMENT_NESTING),
            r"\(\*.*?\*\)",
            r"/\*.*?\*/",
            r"//[^\n]*",
            r"\{\{.*?\}\}|\{[^}]*\}",
            r"'(?:[^'$]|\$.)*+'",
            r'"(?:[^"$]|\$.)*+"',
            r"[0-9][A-Za-z0-9_#.]*",
            r"([A-Za-z_][A-Za-z0-9_]*)",
            # a comment, pragma or string that is not closed: the lexer stops there with a
            # syntax error, so the rest of the text is cut no more (nor read again)
            r"(\(\*|/\*|\{|'|\")",
        )
    ),
    re.DOTALL,
)


@dataclass(frozen=True)
class Chunk:
    line_offset: int  # lines of the file before the chunk
    text: str


def chunks(text: str) -> list[Chunk]:
    """The text cut before each top-level declaration that starts a line; joined again the
    chunks are the text."""
    starts = [0]  # offsets in the text where a chunk starts
    closing: str | None = None  # the END keyword of the declaration being read
    position = 0
    while (match := _TOKENS.search(text, position)) is not None:
        position = match.end()
        if match.group(2) is not None:
            break
        word = match.group(1)
        if word is None:
            continue
        word = word.upper()
        if closing is not None:
            if word == closing:
                closing = None
            continue
        if word in _ATTACHED:
            closing = _ATTACHED[word]
        elif word in _CHUNK_STARTS:
            closing = _CHUNK_STARTS[word]
            line_start = text.rfind("\n", 0, match.start()) + 1
            if line_start > starts[-1] and not text[line_start : match.start()].strip():
                starts.append(line_start)
    result: list[Chunk] = []
    line = 0
    for begin, end in zip(starts, [*starts[1:], len(text)], strict=True):
        piece = text[begin:end]
        result.append(Chunk(line, piece))
        line += piece.count("\n")
    return result
