"""ST source as HTML with line numbers and syntax highlighting: keywords, comments (also
across lines) and strings each get a class the style sheet colours. A line too long for
the page is cut and continues under its code, the numbers keep their column."""

from __future__ import annotations

import re
from collections.abc import Iterable, Iterator

from backend.compiler.language.tokens import KEYWORDS as LANGUAGE_KEYWORDS
from backend.engineering.documentation.markup import escape

# the words the compiler never takes for a name, and those that are words of the language
# only in some places (a configuration's, the modifiers of edition 3): a listing shows
# them all as keywords; not GET and SET, which are names too (a method Get, a variable
# set) outside a property
KEYWORDS = LANGUAGE_KEYWORDS | frozenset(
    [
        "FROM",
        "ON",
        "PRIORITY",
        "READ_ONLY",
        "READ_WRITE",
        "PERSISTENT",
        "TASK",
        "WITH",
        "ABSTRACT",
        "FINAL",
        "INTERNAL",
        "OVERRIDE",
        "PRIVATE",
        "PROTECTED",
        "PUBLIC",
        "SUPER",
        "THIS",
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


Token = tuple[str, str]  # (class, text); class "" for plain text
CODE_COLUMNS = 104  # characters of code on a line of the listing; the rest wraps
_NUMBER_COLUMNS = 6
_CONTINUED = " " * (_NUMBER_COLUMNS - 1) + "\u21b3 "  # a wrapped line's continuation


def _token_lines(lines: Iterable[str]) -> Iterator[list[Token]]:
    in_comment = False
    for line in lines:
        tokens, in_comment = _tokens(line.expandtabs(4), in_comment)
        yield tokens


def _tokens(line: str, in_comment: bool) -> tuple[list[Token], bool]:
    tokens: list[Token] = []
    position = 0
    if in_comment:
        end = line.find("*)")
        if end < 0:
            return [("c", line)], True
        tokens.append(("c", line[: end + 2]))
        position = end + 2
    while position < len(line):
        match = _TOKEN.match(line, position)
        assert match is not None  # `other` takes any character
        kind = match.lastgroup
        text = match.group()
        if kind == "comment_open":
            end = line.find("*)", match.end())
            if end < 0:
                tokens.append(("c", line[position:]))
                return tokens, True
            tokens.append(("c", line[position : end + 2]))
            position = end + 2
            continue
        css_class = _CLASSES.get(kind or "", "")
        if kind == "word":
            css_class = "k" if text.upper() in KEYWORDS else ""
        _append(tokens, css_class, text)
        position = match.end()
    return tokens, False


def _append(tokens: list[Token], css_class: str, text: str) -> None:
    """Every run of one class is a box WeasyPrint lays out and draws, the dearest part of
    a listing: runs of a class merge, and so do two of a class with only blanks between
    them (`END_IF END_IF`, `AND NOT`), since a blank looks the same in every class."""
    if tokens and tokens[-1][0] == css_class:
        tokens[-1] = (css_class, tokens[-1][1] + text)
    elif css_class and len(tokens) > 1 and tokens[-2][0] == css_class and tokens[-1][1].isspace():
        tokens[-2:] = [(css_class, tokens[-2][1] + tokens[-1][1] + text)]
    else:
        tokens.append((css_class, text))


# numbers stay plain: every coloured run is a box to lay out, and a library's sources are
# full of constants
_CLASSES = {"line_comment": "c", "string": "s"}


def _html(tokens: list[Token]) -> str:
    return "".join(
        f'<span class="{css_class}">{escape(text)}</span>' if css_class else escape(text)
        for css_class, text in tokens
    )


def _wrapped(tokens: list[Token], width: int) -> list[list[Token]]:
    """The tokens of one line cut into lines of at most `width` characters."""
    rows: list[list[Token]] = [[]]
    used = 0
    for css_class, text in tokens:
        while text:
            if used == width:
                rows.append([])
                used = 0
            piece = text[: width - used]
            rows[-1].append((css_class, piece))
            used += len(piece)
            text = text[len(piece) :]
    return rows


def tokenized(lines: Iterable[str]) -> list[list[Token]]:
    return list(_token_lines(lines))


def listing(lines: Iterable[str], first_line: int) -> str:
    """Numbered source lines (numbers as in the file)."""
    rows = [(str(n), tokens, "") for n, tokens in enumerate(_token_lines(lines), first_line)]
    return numbered(rows)


def numbered(rows: Iterable[tuple[str, list[Token], str]]) -> str:
    """(label, tokens, class of the whole line) per line, in one preformatted block: one
    box per line would make a long program slow to lay out. The label is plain text for
    the same reason. A line longer than the page is cut and goes on after a continuation
    mark under its code."""
    out = []
    for label, tokens, css_class in rows:
        for index, row in enumerate(_wrapped(tokens, CODE_COLUMNS)):
            prefix = f"{label:>{_NUMBER_COLUMNS - 1}} " if index == 0 else _CONTINUED
            text = prefix + _html(row)
            out.append(f'<span class="{css_class}">{text}</span>' if css_class else text)
    return '<pre class="listing">' + "\n".join(out) + "</pre>"
