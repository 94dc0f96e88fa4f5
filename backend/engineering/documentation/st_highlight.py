"""ST source as HTML with line numbers and syntax highlighting: keywords, comments (also
across lines), strings and literals each get a class the style sheet colours. Long lines
wrap inside their line, the number stays in its column."""

from __future__ import annotations

import re
from collections.abc import Iterable

from backend.engineering.documentation.markup import escape

KEYWORDS = frozenset(
    [
        "ACTION",
        "AND",
        "ARRAY",
        "AT",
        "BY",
        "CASE",
        "CONFIGURATION",
        "CONSTANT",
        "DO",
        "ELSE",
        "ELSIF",
        "END_ACTION",
        "END_CASE",
        "END_CONFIGURATION",
        "END_FOR",
        "END_FUNCTION",
        "END_FUNCTION_BLOCK",
        "END_IF",
        "END_PROGRAM",
        "END_REPEAT",
        "END_RESOURCE",
        "END_STEP",
        "END_STRUCT",
        "END_TRANSITION",
        "END_TYPE",
        "END_VAR",
        "END_WHILE",
        "EXIT",
        "CONTINUE",
        "FALSE",
        "FOR",
        "FROM",
        "FUNCTION",
        "FUNCTION_BLOCK",
        "F_EDGE",
        "IF",
        "INITIAL_STEP",
        "MOD",
        "NOT",
        "OF",
        "ON",
        "OR",
        "PROGRAM",
        "READ_ONLY",
        "READ_WRITE",
        "REPEAT",
        "RESOURCE",
        "RETAIN",
        "NON_RETAIN",
        "PERSISTENT",
        "RETURN",
        "R_EDGE",
        "STEP",
        "STRUCT",
        "TASK",
        "THEN",
        "TO",
        "TRANSITION",
        "TRUE",
        "TYPE",
        "UNTIL",
        "VAR",
        "VAR_ACCESS",
        "VAR_CONFIG",
        "VAR_EXTERNAL",
        "VAR_GLOBAL",
        "VAR_INPUT",
        "VAR_IN_OUT",
        "VAR_OUTPUT",
        "VAR_TEMP",
        "WHILE",
        "WITH",
        "XOR",
        "PRIORITY",
    ]
)
_TOKEN = re.compile(
    r"""(?P<comment_open>\(\*)
    |(?P<line_comment>//.*)
    |(?P<string>'(?:\$.|[^'$])*'?|"(?:\$.|[^"$])*"?)
    |(?P<literal>\b(?:[A-Za-z_]+\#)?[0-9][0-9A-Za-z_.#:+-]*|\b(?:T|TIME|LT|D|DT|TOD)\#[0-9A-Za-z_.:-]+)
    |(?P<word>[A-Za-z_][A-Za-z0-9_]*)
    |(?P<other>[^'"(/A-Za-z_0-9]+|.)""",
    re.VERBOSE,
)


def highlight_lines(lines: Iterable[str]) -> list[str]:
    """Each line as HTML; a comment opened on one line continues on the next."""
    result = []
    in_comment = False
    for line in lines:
        html, in_comment = _line(line.expandtabs(4), in_comment)
        result.append(html)
    return result


def _line(line: str, in_comment: bool) -> tuple[str, bool]:
    parts: list[str] = []
    position = 0
    if in_comment:
        end = line.find("*)")
        if end < 0:
            return _span("c", line), True
        parts.append(_span("c", line[: end + 2]))
        position = end + 2
    while position < len(line):
        match = _TOKEN.match(line, position)
        assert match is not None  # `other` takes any character
        kind = match.lastgroup
        text = match.group()
        if kind == "comment_open":
            end = line.find("*)", match.end())
            if end < 0:
                parts.append(_span("c", line[position:]))
                return "".join(parts), True
            parts.append(_span("c", line[position : end + 2]))
            position = end + 2
            continue
        if kind == "line_comment":
            parts.append(_span("c", text))
        elif kind == "string":
            parts.append(_span("s", text))
        elif kind == "literal":
            parts.append(_span("n", text))
        elif kind == "word" and text.upper() in KEYWORDS:
            parts.append(_span("k", text))
        else:
            parts.append(escape(text))
        position = match.end()
    return "".join(parts), False


def _span(css_class: str, text: str) -> str:
    return f'<span class="{css_class}">{escape(text)}</span>'


def listing(lines: Iterable[str], first_line: int, marks: dict[int, str] | None = None) -> str:
    """Numbered source lines (numbers as in the file); `marks`: line -> a class for the
    line (the comparison marks added and removed lines)."""
    rows = []
    for number, html in enumerate(highlight_lines(lines), first_line):
        klass = f"ln {marks[number]}" if marks and number in marks else "ln"
        rows.append(f'<div class="{klass}"><span class="no">{number}</span>{html or " "}</div>')
    return '<div class="listing">' + "".join(rows) + "</div>"
