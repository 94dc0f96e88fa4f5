"""A declaration as the source writes it: the type, the initial value and the comment
that describes it (`level : INT := 500; (* current tank level *)`). The AST keeps the
meaning; the document shows the text the engineer wrote."""

from __future__ import annotations

import re
from dataclasses import dataclass

from backend.compiler import ast

_COMMENT = re.compile(r"\(\*(.*?)\*\)|//([^\n]*)", re.DOTALL)
_MAX_LINES = 8  # a declaration longer than this is shown by its first lines' text


@dataclass(frozen=True)
class Declared:
    name: str
    type: str
    initial: str
    location: str
    comment: str
    line: int


def declared(decl: ast.VarDecl, lines: tuple[str, ...]) -> Declared:
    text, comment = _statement_text(lines, decl.pos.line, decl.pos.col)
    type_text, initial = _type_and_initial(text)
    return Declared(decl.name, type_text, initial, decl.location or "", comment, decl.pos.line)


def _statement_text(lines: tuple[str, ...], line: int, col: int) -> tuple[str, str]:
    """The declaration from its name to its `;` (comments removed), and the comments on its
    lines after the name (the description)."""
    first = line - 1
    chunk = lines[first : first + _MAX_LINES] if 0 <= first < len(lines) else ()
    joined = "\n".join(chunk)[col - 1 :] if chunk else ""
    comments: list[str] = []
    code_parts: list[str] = []
    position = 0
    for match in _COMMENT.finditer(joined):
        before = joined[position : match.start()]
        code_parts.append(before)
        if ";" in before:
            break
        comments.append((match.group(1) or match.group(2) or "").strip())
        position = match.end()
    else:
        code_parts.append(joined[position:])
    code = "".join(code_parts)
    statement, semicolon, _ = code.partition(";")
    if semicolon:  # a comment right after the `;`, on the same line, describes it too
        rest = joined[len(statement) + 1 :].lstrip(" \t")
        trailing = _COMMENT.match(rest)
        if trailing is not None and not comments:
            comments.append((trailing.group(1) or trailing.group(2) or "").strip())
    return statement, " ".join(" ".join(c.split()) for c in comments if c)


def _type_and_initial(statement: str) -> tuple[str, str]:
    """`level : INT := 500` -> ("INT", "500"); `x AT %IX0.0 : BOOL` -> ("BOOL", "")."""
    match = re.search(r":(?!=)", statement)
    if match is None:
        return "", ""
    rest = statement[match.end() :]
    type_text, assign, initial = rest.partition(":=")
    return " ".join(type_text.split()), " ".join(initial.split()) if assign else ""
