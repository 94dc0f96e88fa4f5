"""The text of a source as the language services read it around a cursor: its tokens (the
identifiers with their places, the comments kept apart) and the blocks they stand in
(POUs, methods, properties, var blocks, types), found from the keywords alone.

Both work on any text, also one that does not parse while it is being typed: completion,
hover and navigation find the POU or method a cursor is in from here, then look the names
up in the last analysis that resolved."""

from __future__ import annotations

import re
import threading
from bisect import bisect_right
from collections import OrderedDict
from dataclasses import dataclass
from typing import NamedTuple

from backend.compiler.language.cuts import cut
from backend.compiler.limits import MAX_COMMENT_NESTING
from backend.compiler.parse import nested_comment

# words of the language that are never a name (upper case); the modifiers (PUBLIC, FINAL...)
# and the words of a configuration (TASK, WITH...) may be names elsewhere (OSCAT's OVERRIDE)
KEYWORDS = frozenset(
    {
        "ACTION",
        "AND",
        "ARRAY",
        "AT",
        "BY",
        "CASE",
        "CONFIGURATION",
        "CONSTANT",
        "CONTINUE",
        "DO",
        "ELSE",
        "ELSIF",
        "END_ACTION",
        "END_CASE",
        "END_CONFIGURATION",
        "END_FOR",
        "END_FUNCTION",
        "END_FUNCTION_BLOCK",
        "END_GET",
        "END_IF",
        "END_INTERFACE",
        "END_METHOD",
        "END_PROGRAM",
        "END_PROPERTY",
        "END_REPEAT",
        "END_RESOURCE",
        "END_SET",
        "END_STEP",
        "END_STRUCT",
        "END_TRANSITION",
        "END_TYPE",
        "END_VAR",
        "END_WHILE",
        "EXIT",
        "EXTENDS",
        "F_EDGE",
        "FALSE",
        "FOR",
        "FUNCTION",
        "FUNCTION_BLOCK",
        "IF",
        "IMPLEMENTS",
        "INITIAL_STEP",
        "INTERFACE",
        "METHOD",
        "MOD",
        "NOT",
        "NON_RETAIN",
        "NULL",
        "OF",
        "OR",
        "PROGRAM",
        "PROPERTY",
        "REF_TO",
        "REPEAT",
        "RESOURCE",
        "RETAIN",
        "RETURN",
        "R_EDGE",
        "STEP",
        "STRUCT",
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
        "XOR",
    }
)
VAR_KINDS = frozenset(
    {
        "VAR",
        "VAR_INPUT",
        "VAR_OUTPUT",
        "VAR_IN_OUT",
        "VAR_TEMP",
        "VAR_EXTERNAL",
        "VAR_GLOBAL",
        "VAR_CONFIG",
        "VAR_ACCESS",
    }
)
# a block keyword and the keyword that ends it
_NAMED_BLOCKS = {
    "PROGRAM": "END_PROGRAM",
    "FUNCTION_BLOCK": "END_FUNCTION_BLOCK",
    "FUNCTION": "END_FUNCTION",
    "INTERFACE": "END_INTERFACE",
    "METHOD": "END_METHOD",
    "PROPERTY": "END_PROPERTY",
    "CONFIGURATION": "END_CONFIGURATION",
    "RESOURCE": "END_RESOURCE",
}
_PLAIN_BLOCKS = {"TYPE": "END_TYPE", "STRUCT": "END_STRUCT", "GET": "END_GET", "SET": "END_SET"}
_ENDS = {end: kind for kind, end in (*_NAMED_BLOCKS.items(), *_PLAIN_BLOCKS.items())} | {
    "END_VAR": "VAR"
}

_DATE_PREFIX = (
    "DATE_AND_TIME|LDATE_AND_TIME|TIME_OF_DAY|LTIME_OF_DAY|DT|LDT|DATE|LDATE|TOD|LTOD|D|LD"
)
# a comment nests as the compiler reads it (up to its limit); one whose nesting never closes
# ends at its first `*)`; one never closed runs to the end
_TOKEN = re.compile(
    r"(?P<ws>\s+)"
    rf"|(?P<comment>{nested_comment(MAX_COMMENT_NESTING)}|\(\*.*?(?:\*\)|\Z)"
    r"|//[^\n]*|/\*.*?(?:\*/|\Z))"
    r"|(?P<pragma>\{[^}]*\}?)"
    r"|(?P<string>'(?:[^'$\n]|\$.)*+'?|\"(?:[^\"$\n]|\$.)*+\"?)"
    rf"|(?P<literal>(?i:(?:LTIME|LT|TIME|T)#[-+]?[\w.]*|(?:{_DATE_PREFIX})#[\w.:-]*))"
    r"|(?P<number>\d[\d_]*(?:#[0-9A-Fa-f_]+|\.\d[\d_]*(?:[eE][-+]?\d+)?|[eE][-+]?\d+)?)"
    r"|(?P<address>%[A-Za-z]*[\d.]*)"
    r"|(?P<ident>[A-Za-z_]\w*)"
    r"|(?P<punct>:=|=>|<=|>=|<>|\*\*|\.\.|\?=|\S)",
    re.DOTALL,
)


class Token(NamedTuple):
    kind: str  # ident, number, literal, string, address, punct
    text: str
    line: int  # 1-based
    col: int  # 1-based, in characters
    offset: int  # in the text
    end: int  # offset after it
    upper: str  # the text in upper case (ST's names ignore case)

    @property
    def end_col(self) -> int:
        """The column after it (tokens other than comments stay on one line)."""
        return self.col + self.end - self.offset

    def is_name(self) -> bool:
        """An identifier that is no keyword."""
        return self.kind == "ident" and self.upper not in KEYWORDS


@dataclass(frozen=True)
class Comment:
    text: str  # without its delimiters, stripped
    line: int
    end_line: int
    offset: int  # in the text
    end: int  # offset after it
    closed: bool  # by `*)` or `*/`; a `//` comment, or one never closed, goes on at its end

    def holds(self, offset: int) -> bool:
        """Whether a cursor at `offset` is in the comment (what it types is comment)."""
        return self.offset < offset < self.end or (offset == self.end and not self.closed)


@dataclass(frozen=True)
class Span:
    """A block of the text: a POU, method, property or accessor, var block, type or struct."""

    kind: str  # PROGRAM, FUNCTION_BLOCK, ..., METHOD, PROPERTY, GET, SET, TYPE, STRUCT, VAR...
    name: str  # "" where the block has none (accessors, var blocks, TYPE)
    start: tuple[int, int]  # line, column of its keyword
    end: tuple[int, int]  # line, column after its END_ keyword (the text's end if unclosed)
    name_token: int  # index of its name's token; -1 if none
    parent: int  # index of the span it stands in; -1 at the top

    def holds(self, line: int, col: int) -> bool:
        return self.start <= (line, col) < self.end


@dataclass(frozen=True)
class Lexed:
    text: str
    tokens: tuple[Token, ...]  # without comments and pragmas
    comments: tuple[Comment, ...]
    spans: tuple[Span, ...]  # in the order their keywords stand
    line_starts: tuple[int, ...]
    pragmas: tuple[tuple[int, int], ...]  # first and last line of each `{...}`

    def offset(self, line: int, col: int) -> int:
        return self.line_starts[min(max(line, 1), len(self.line_starts)) - 1] + col - 1

    def index_at(self, line: int, col: int) -> int:
        """The index of the first token that starts at or after line:col."""
        target = (line, col)
        low, high = 0, len(self.tokens)
        while low < high:
            mid = (low + high) // 2
            token = self.tokens[mid]
            if (token.line, token.col) < target:
                low = mid + 1
            else:
                high = mid
        return low

    def name_at(self, line: int, col: int) -> int:
        """The index of the name token under line:col or just before it (a cursor at the
        end of a word), or -1."""
        index = self.index_at(line, col)
        for candidate in (index, index - 1):
            if 0 <= candidate < len(self.tokens):
                token = self.tokens[candidate]
                if token.line == line and token.col <= col <= token.end_col and token.is_name():
                    return candidate
        return -1

    def innermost(self, line: int, col: int, kinds: frozenset[str] | None = None) -> list[Span]:
        """The spans holding line:col, outermost first (only those of `kinds`, if given)."""
        return [
            span
            for span in self.spans
            if span.holds(line, col) and (kinds is None or span.kind in kinds)
        ]


class _Kept:
    """The texts lexed lately, least recently used first out, some 8 MB of text at most
    (a piece of each declaration of a large project and its versions while one types;
    the tokens take some ten times their text)."""

    def __init__(self, limit: int) -> None:
        self._lock = threading.Lock()
        self._limit = limit
        self._size = 0
        self._kept: OrderedDict[str, Lexed] = OrderedDict()

    def get(self, text: str) -> Lexed | None:
        with self._lock:
            found = self._kept.get(text)
            if found is not None:
                self._kept.move_to_end(text)
            return found

    def put(self, text: str, lexed: Lexed) -> None:
        with self._lock:
            if text in self._kept or len(text) > self._limit:
                return
            self._kept[text] = lexed
            self._size += len(text)
            while self._size > self._limit:
                dropped, _ = self._kept.popitem(last=False)
                self._size -= len(dropped)


_KEPT = _Kept(8 * 1024 * 1024)


def lex(text: str) -> Lexed:
    """The tokens, comments and blocks of `text` (kept: the services ask of the same text
    again and again while a cursor moves)."""
    found = _KEPT.get(text)
    if found is None:
        found = _lexed(text)
        _KEPT.put(text, found)
    return found


def _lexed(text: str) -> Lexed:
    line_starts = [0, *(m.end() for m in re.finditer("\n", text))]
    tokens: list[Token] = []
    comments: list[Comment] = []
    pragmas: list[tuple[int, int]] = []
    line, line_start = 1, 0
    for match in _TOKEN.finditer(text):
        kind = match.lastgroup or "punct"
        start, end = match.span()
        if kind == "ws" or kind == "comment" or kind == "pragma":
            first_line = line
            breaks = text.count("\n", start, end)
            if breaks:
                line += breaks
                line_start = text.rfind("\n", start, end) + 1
            if kind == "comment":
                comments.append(_comment(match.group(), first_line, line, start, end))
            elif kind == "pragma":
                pragmas.append((first_line, line))
            continue
        word = match.group()
        upper = word.upper() if kind == "ident" else word
        tokens.append(Token(kind, word, line, start - line_start + 1, start, end, upper))
    return Lexed(
        text,
        tuple(tokens),
        tuple(comments),
        _spans(tokens, len(text), line_starts),
        tuple(line_starts),
        tuple(pragmas),
    )


def pieces(text: str) -> list[tuple[Lexed, int]]:
    """The text lexed declaration by declaration (a POU with its methods, a TYPE, a global
    list: `chunks`), each with the lines of the text before it. A keystroke changes one
    declaration: only that one is lexed again, however long the file."""
    return [(lex(chunk.text), chunk.line_offset) for chunk in cut(text)]


def piece_at(text: str, line: int) -> tuple[Lexed, int]:
    """The lexed declaration that holds `line` of the text, and the lines before it (its
    lines are the text's minus that; its columns are the text's)."""
    found = cut(text)
    offsets = [chunk.line_offset for chunk in found]
    chunk = found[max(bisect_right(offsets, line - 1) - 1, 0)]
    return lex(chunk.text), chunk.line_offset


def declarations(lexed: Lexed, span: int) -> list[tuple[int, str]]:
    """The declarations `a, b : T ...;` directly in span `span` (a var block, a STRUCT, a
    TYPE): each name's token index and the text of its type (`ARRAY[1..3] OF INT`)."""
    block = lexed.spans[span]
    first = lexed.index_at(*block.start) + 1
    last = min(lexed.index_at(*block.end), len(lexed.tokens))
    nested = [s for s in lexed.spans if s.parent == span]
    found: list[tuple[int, str]] = []
    names: list[int] = []
    expect_name = True
    index = first
    while index < last:
        token = lexed.tokens[index]
        inner = next((s for s in nested if (token.line, token.col) == s.start), None)
        if inner is not None:  # a STRUCT in a TYPE: its members are its own
            index = lexed.index_at(*inner.end)
            continue
        if token.text == ";":
            names, expect_name = [], True
        elif expect_name and token.is_name():
            names.append(index)
            expect_name = False
        elif token.text == "," and names:
            expect_name = True
        elif token.text == ":" and names:
            found += [(name, _type_text(lexed, index + 1, last)) for name in names]
            names = []
        else:
            expect_name = False
        index += 1
    return found


def _type_text(lexed: Lexed, first: int, last: int) -> str:
    """The text from token `first` to the `:=` or `;` that ends a declaration's type."""
    depth = 0
    end = first
    while end < last:
        text = lexed.tokens[end].text
        if text in ("(", "["):
            depth += 1
        elif text in (")", "]"):
            depth -= 1
        elif depth <= 0 and text in (";", ":="):
            break
        end += 1
    if end == first:
        return ""
    words = lexed.text[lexed.tokens[first].offset : lexed.tokens[end - 1].end].split()
    return " ".join(words)


def _comment(raw: str, line: int, end_line: int, start: int, end: int) -> Comment:
    """A comment from its text with its delimiters."""
    closed = not raw.startswith("//") and len(raw) >= 4 and raw.endswith(("*)", "*/"))
    body = raw[2:-2] if closed else raw[2:]
    return Comment(body.strip(), line, end_line, start, end, closed)


def _spans(tokens: list[Token], length: int, line_starts: list[int]) -> tuple[Span, ...]:
    last_line = len(line_starts)
    text_end = (last_line, length - line_starts[-1] + 1)
    opened: list[tuple[int, str, str, Token, int]] = []  # span index, kind, name, keyword, name
    spans: list[Span | None] = []
    starts: dict[int, tuple[str, str, Token, int, int]] = {}

    def close(index: int, end: tuple[int, int]) -> None:
        kind, name, keyword, name_index, parent = starts[index]
        spans[index] = Span(kind, name, (keyword.line, keyword.col), end, name_index, parent)

    for i, token in enumerate(tokens):
        if token.kind != "ident":
            continue
        word = token.upper
        top = opened[-1][1] if opened else ""
        if word in _ENDS:
            wanted = _ENDS[word]
            match = [n for n, entry in enumerate(opened) if _closes(wanted, entry[1])]
            if match:
                end = (token.line, token.end_col)
                while len(opened) > match[-1]:
                    close(opened.pop()[0], end)
            continue
        opens = word in _NAMED_BLOCKS or word in ("TYPE", "STRUCT") or word in VAR_KINDS
        opens = opens or (word in ("GET", "SET") and top == "PROPERTY")
        # `PROGRAM inst WITH task : Main;` in a RESOURCE declares an instance, not a POU
        if word == "PROGRAM" and any(entry[1] in ("RESOURCE", "CONFIGURATION") for entry in opened):
            opens = False
        if word == "STRUCT" and top != "TYPE":
            opens = False
        if not opens:
            continue
        name, name_index = "", -1
        if word in _NAMED_BLOCKS:
            name_index = _name_after(tokens, i)
            name = tokens[name_index].text if name_index >= 0 else ""
        elif word == "STRUCT" and i >= 2 and tokens[i - 1].text == ":":
            name_index = i - 2
            name = tokens[name_index].text
        parent = opened[-1][0] if opened else -1
        starts[len(spans)] = (word, name, token, name_index, parent)
        opened.append((len(spans), word, name, token, name_index))
        spans.append(None)
    while opened:
        close(opened.pop()[0], text_end)
    return tuple(span for span in spans if span is not None)


def _closes(wanted: str, kind: str) -> bool:
    return kind == wanted or (wanted == "VAR" and kind in VAR_KINDS)


def _name_after(tokens: list[Token], index: int) -> int:
    """The index of the name after a block keyword: the last word on the keyword's line
    before anything else (`METHOD PUBLIC FINAL Name : T`, `FUNCTION_BLOCK OVERRIDE`);
    -1 if none."""
    found = -1
    for i in range(index + 1, min(index + 8, len(tokens))):
        token = tokens[i]
        if token.kind != "ident" or token.line != tokens[index].line:
            break
        if token.upper in KEYWORDS:
            break
        found = i
    return found
