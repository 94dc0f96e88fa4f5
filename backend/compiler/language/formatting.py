"""Formatting a file: each line indented by the blocks it stands in (two spaces a level:
var blocks, structures, IF, CASE, FOR, WHILE, REPEAT; a CASE's statements under their
labels), keywords in upper case. Nothing else changes: names keep their spelling,
comments and strings their text, lines their breaks. A file is formatted only if it
parses, and only if it parses the same after (else the reason is given)."""

from __future__ import annotations

import re
from dataclasses import dataclass

from backend.compiler.diagnostics import CompileError
from backend.compiler.language.analysis import Analysis
from backend.compiler.language.tokens import KEYWORDS, VAR_KINDS, Lexed, Token, lex
from backend.compiler.parse import parse_source
from backend.compiler.types import elementary

INDENT = "  "
# a keyword that opens a block of indented lines, and the one that ends it
_OPENERS = {
    "IF": "END_IF",
    "CASE": "END_CASE",
    "FOR": "END_FOR",
    "WHILE": "END_WHILE",
    "REPEAT": "END_REPEAT",
    "STRUCT": "END_STRUCT",
} | {kind: "END_VAR" for kind in VAR_KINDS}
_CLOSERS = frozenset(_OPENERS.values())
_MIDDLES = frozenset({"ELSIF", "ELSE", "UNTIL"})  # a line of the block's own level
_LABEL = "label"  # the statements under a CASE label
_POSITIONS = re.compile(r"Pos\(file='[^']*', line=\d+, col=\d+\)")


@dataclass(frozen=True)
class Formatted:
    text: str  # the formatted text; the text as it was when refused
    refusal: str = ""  # why it was not formatted; "" when it was

    @property
    def ok(self) -> bool:
        return not self.refusal


def format_file(analysis: Analysis, file: str) -> Formatted:
    text = analysis.texts.get(file)
    if text is None:
        return Formatted("", f"the project has no file '{file}'")
    return format_text(file, text)


def format_text(file: str, text: str) -> Formatted:
    """`text` formatted, if it parses and parses the same formatted."""
    before = _shape(file, text)
    if before is None:
        return Formatted(text, "the file does not parse: its errors come first")
    formatted = _formatted(lex(text))
    if _shape(file, formatted) != before:
        return Formatted(text, "formatted, the file would read differently: left as it is")
    return Formatted(formatted)


def _shape(file: str, text: str) -> str | None:
    """What the file declares, without places and case (ST ignores case): equal for two
    texts that mean the same."""
    try:
        unit = parse_source(file, text)
    except CompileError:
        return None
    parts = (unit.pous, unit.globals, unit.types, unit.configurations, unit.interfaces)
    return _POSITIONS.sub("", repr(parts)).upper()


def _formatted(lexed: Lexed) -> str:
    text = lexed.text
    chars = list(text)
    for token in lexed.tokens:  # keywords in upper case: the same length, so in place
        if token.kind == "ident" and _is_keyword(token) and token.text != token.upper:
            chars[token.offset : token.end] = token.upper
    cased = "".join(chars)
    indents = _indents(lexed)
    lines = cased.split("\n")
    for number, indent in indents.items():
        line = lines[number - 1]
        lines[number - 1] = INDENT * indent + line.lstrip(" \t") if line.strip() else ""
    return "\n".join(
        line.rstrip(" \t") if n in indents else line for n, line in enumerate(lines, 1)
    )


def _is_keyword(token: Token) -> bool:
    return token.upper in KEYWORDS or elementary(token.upper) is not None


def _indents(lexed: Lexed) -> dict[int, int]:
    """The level of each line to indent (1-based line -> level); the lines that start in
    a comment or pragma that began above are left as they are."""
    by_line: dict[int, list[Token]] = {}
    for token in lexed.tokens:
        by_line.setdefault(token.line, []).append(token)
    blocks = [(c.line, c.end_line) for c in lexed.comments] + list(lexed.pragmas)
    starts_in_comment = {line for first, last in blocks for line in range(first + 1, last + 1)}
    stack: list[str] = []
    parentheses = 0
    indents: dict[int, int] = {}
    for number in range(1, len(lexed.line_starts) + 1):
        if number in starts_in_comment:
            continue
        tokens = by_line.get(number, [])
        first = tokens[0] if tokens else None
        if first is None or first.offset != _first_char(lexed, number):
            indents[number] = len(stack) if parentheses == 0 else len(stack) + 2
            continue  # a comment's or an empty line
        if parentheses > 0:
            indents[number] = len(stack) + 2  # a continued statement
        else:
            indents[number] = _line_level(stack, tokens)
        parentheses = _follow(stack, tokens, parentheses)
    return indents


def _first_char(lexed: Lexed, line: int) -> int:
    start = lexed.line_starts[line - 1]
    end = lexed.line_starts[line] if line < len(lexed.line_starts) else len(lexed.text)
    chunk = lexed.text[start:end]
    return start + len(chunk) - len(chunk.lstrip(" \t"))


def _line_level(stack: list[str], tokens: list[Token]) -> int:
    """The level of a line that starts with `tokens[0]`, the stack updated for what that
    first token closes or continues."""
    word = tokens[0].upper
    if word in _CLOSERS:
        while stack and stack[-1] == _LABEL:
            stack.pop()
        return max(len(stack) - 1, 0)
    if word in _MIDDLES:
        if stack and stack[-1] == _LABEL:
            stack.pop()
        return max(len(stack) - 1, 0)
    if stack and stack[-1] in ("CASE", _LABEL) and _is_label(tokens):
        if stack[-1] == _LABEL:
            stack.pop()
        level = len(stack)
        stack.append(_LABEL)
        return level
    return len(stack)


def _is_label(tokens: list[Token]) -> bool:
    """`1:`, `2, 3:`, `Color#Red:`, `10..20:` (a ':' not inside parentheses, not `:=`)."""
    depth = 0
    for token in tokens:
        if token.text in ("(", "["):
            depth += 1
        elif token.text in (")", "]"):
            depth -= 1
        elif token.text == ":" and depth == 0:
            return True
        elif token.text in (":=", ";") or (token.kind == "ident" and token.upper in KEYWORDS):
            return False
    return False


def _follow(stack: list[str], tokens: list[Token], parentheses: int) -> int:
    """The stack and the open parentheses after a line's tokens."""
    for token in tokens:
        if token.text in ("(", "["):
            parentheses += 1
        elif token.text in (")", "]"):
            parentheses = max(parentheses - 1, 0)
        elif token.kind != "ident":
            continue
        word = token.upper
        if word in _OPENERS:
            stack.append(word)
        elif word in _CLOSERS:
            while stack and stack[-1] == _LABEL:
                stack.pop()
            if stack and _OPENERS.get(stack[-1]) == word:
                stack.pop()
        elif word == "ELSE" and stack and stack[-1] == _LABEL:
            stack.pop()
    return parentheses
