"""The comment that describes a declaration: the one written on the declaration's line (after
it, as `level : INT; (* litres *)`), else the one that ends on the line right above it and
has no code on its lines (a POU's comment stands before it).

Hover shows it with a declaration (language/hover.py), and the compiler gives it to OPC UA
as a node's description (checks/opcua.py). It lives here, below both, because the language
services import the pipeline: the checks cannot import them.
"""

from __future__ import annotations

import re
from bisect import bisect_left
from dataclasses import dataclass
from functools import lru_cache

from backend.compiler.limits import MAX_COMMENT_NESTING
from backend.compiler.parse import nested_comment
from backend.compiler.source import Pos

MAX_COMMENT = 2000  # characters of a declaration's comment kept

# comments as the compiler reads them (nested up to its limit; one whose nesting never
# closes ends at its first `*)`, one never closed runs to the end), pragmas, and code: the
# strings whole (a `(*` in one is no comment), everything else in runs
_PIECE = re.compile(
    rf"(?P<comment>{nested_comment(MAX_COMMENT_NESTING)}|\(\*.*?(?:\*\)|\Z)"
    r"|//[^\n]*|/\*.*?(?:\*/|\Z))"
    r"|(?P<pragma>\{[^}]*\}?)"
    r"|(?P<code>'(?:[^'$\n]|\$.)*+'?|\"(?:[^\"$\n]|\$.)*+\"?|[^\s'\"(/{]+|[(/])",
    re.DOTALL,
)


@dataclass(frozen=True)
class _Comments:
    starting: dict[int, list[str]]  # the comments that start on a line, by line
    ending: dict[int, tuple[int, str]]  # the last comment that ends on a line: its first line
    code_lines: list[int]  # the lines that code starts on, sorted


def declaration_comment(text: str | None, pos: Pos) -> str:
    """The comment of the declaration at `pos` in `text` (its lines stripped, at most
    MAX_COMMENT characters), or ""."""
    if text is None:
        return ""
    found = _comments(text)
    same_line = found.starting.get(pos.line)
    if same_line:
        return _clip(" ".join(same_line))
    above = found.ending.get(pos.line - 1)
    if above is None:
        return ""
    first_line, comment = above
    code = bisect_left(found.code_lines, first_line)
    if code < len(found.code_lines) and found.code_lines[code] <= pos.line - 1:
        return ""  # a comment after code belongs to that code, not to the next line
    return _clip(comment)


@lru_cache(maxsize=16)
def _comments(text: str) -> _Comments:
    """The comments of a text, found once per text (hover asks again and again)."""
    starting: dict[int, list[str]] = {}
    ending: dict[int, tuple[int, str]] = {}
    code_lines: list[int] = []
    line, offset = 1, 0
    for match in _PIECE.finditer(text):
        start, end = match.span()
        line += text.count("\n", offset, start)
        offset = start
        kind = match.lastgroup
        if kind == "code":
            if not code_lines or code_lines[-1] != line:
                code_lines.append(line)
            continue
        end_line = line + text.count("\n", start, end)
        if kind == "comment":
            body = _body(match.group())
            starting.setdefault(line, []).append(body)
            ending[end_line] = (line, body)
        line, offset = end_line, end
    return _Comments(starting, ending, code_lines)


def _body(raw: str) -> str:
    """A comment without its delimiters, stripped."""
    closed = not raw.startswith("//") and len(raw) >= 4 and raw.endswith(("*)", "*/"))
    return (raw[2:-2] if closed else raw[2:]).strip()


def _clip(comment: str) -> str:
    comment = "\n".join(line.strip() for line in comment.splitlines())
    return comment if len(comment) <= MAX_COMMENT else comment[:MAX_COMMENT] + " ..."
