"""A small FileCheck for the rusty-lit corpus: the expected output lives in the ST source.

The corpus files carry LLVM FileCheck directives in comments, often behind code on the same
line (``printf('%d$N', x);  // CHECK: 10``). `parse_checks` extracts them and `match_output`
checks a program's printed output against them with FileCheck's rules, so that a test here
passes exactly when rusty's own lit run would.

Whole lines or substrings. Plain FileCheck matches a positive pattern anywhere in a line,
but rusty's `tests/lit/lit.cfg` defines ``%CHECK`` as ``FileCheck --check-prefixes CHECK
--allow-unused-prefixes --match-full-lines``, and the corpus is written for that: every
positive check spells out the whole printed line (``main=31``, ``0 0 0 0``, ``Global REAL
positive: 15.620000``), and the expect-error files wrap theirs in ``{{.*}}`` to reach the
ends of the line. So `match_output` matches whole lines by default, exactly as
``--match-full-lines`` does: a CHECK, CHECK-NEXT or CHECK-SAME pattern must cover the whole
line (from the current position, for the first line searched), leading and trailing blanks
of the output line aside. CHECK-NOT always looks for a substring, as in FileCheck. Pass
``match_full_lines=False`` for plain FileCheck behaviour.

Supported directives: ``CHECK:``, ``CHECK-NEXT:``, ``CHECK-SAME:``, ``CHECK-NOT:`` and
``CHECK-EMPTY:``, with the ``{LITERAL}`` modifier. As in FileCheck a directive is found
anywhere in a line, but not inside a longer word (``XCHECK:`` is not a directive), and a line
whose first directive-like word is ``COM:`` or ``RUN:`` is a comment. ``CHECK-DAG``,
``CHECK-LABEL`` and ``CHECK-COUNT-n`` are recognised so that they are never ignored in
silence, but `match_output` reports them as unsupported, like ``[[...]]`` variables.

Patterns are literal text except for ``{{...}}`` blocks, which are Python regular
expressions (FileCheck uses POSIX ones). Leading and trailing blanks of a pattern are
ignored, and as in FileCheck every run of spaces and tabs, in the pattern and in the output,
counts as one space. A pattern never matches across a line break.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from enum import StrEnum

__all__ = [
    "Check",
    "CheckKind",
    "FileCheckResult",
    "match_output",
    "parse_checks",
    "run_line",
]


class CheckKind(StrEnum):
    CHECK = "CHECK"
    NEXT = "CHECK-NEXT"
    SAME = "CHECK-SAME"
    NOT = "CHECK-NOT"
    EMPTY = "CHECK-EMPTY"
    DAG = "CHECK-DAG"
    LABEL = "CHECK-LABEL"
    COUNT = "CHECK-COUNT"


_SUPPORTED = frozenset(
    {CheckKind.CHECK, CheckKind.NEXT, CheckKind.SAME, CheckKind.NOT, CheckKind.EMPTY}
)
# Directives that must sit right after a previous match; FileCheck rejects them first.
_FOLLOWERS = frozenset({CheckKind.NEXT, CheckKind.SAME, CheckKind.EMPTY})


@dataclass(frozen=True)
class Check:
    """One directive: its kind, its pattern (blanks at both ends removed), its source line."""

    kind: CheckKind
    pattern: str
    line: int
    literal: bool = False

    def describe(self) -> str:
        modifier = "{LITERAL}" if self.literal else ""
        return f"{self.kind.value}{modifier}: {self.pattern} (source line {self.line})"


@dataclass(frozen=True)
class FileCheckResult:
    ok: bool
    message: str


# FileCheck's word characters: a prefix preceded by one of them is part of another word.
_WORD_BEFORE = r"(?<![A-Za-z0-9_-])"
_PREFIX = re.compile(_WORD_BEFORE + r"(CHECK|COM|RUN)")
_SUFFIX = re.compile(r"(-NEXT|-SAME|-NOT|-EMPTY|-DAG|-LABEL|-COUNT-[0-9]+)?(\{LITERAL\})?:")
_RUN = re.compile(_WORD_BEFORE + r"RUN:")
_BLANKS = re.compile(r"[ \t]+")


def parse_checks(source_text: str) -> list[Check]:
    """The FileCheck directives of `source_text`, in source order."""
    checks: list[Check] = []
    for number, line in enumerate(_source_lines(source_text), start=1):
        check = _directive(line, number)
        if check is not None:
            checks.append(check)
    return checks


def run_line(source_text: str) -> str | None:
    """The lit ``RUN:`` command of `source_text`, or None when there is none.

    Several RUN lines (lit runs them one after the other) come back one per line; a RUN
    line ending in a backslash is joined with the next one, as lit does.
    """
    commands: list[str] = []
    continuing = False
    for line in _source_lines(source_text):
        found = _RUN.search(line)
        if found is None:
            continue
        command = line[found.end() :].strip()
        if continuing:
            commands[-1] += " " + command
        else:
            commands.append(command)
        continuing = commands[-1].endswith("\\")
        if continuing:
            commands[-1] = commands[-1][:-1].rstrip()
    return "\n".join(commands) if commands else None


def _source_lines(text: str) -> list[str]:
    # Only \n ends a line (splitlines() would also split at form feeds and the like); a
    # CRLF file keeps no \r in its patterns.
    return [line.removesuffix("\r") for line in text.split("\n")]


def _directive(line: str, number: int) -> Check | None:
    for prefix in _PREFIX.finditer(line):
        if prefix.group(1) != "CHECK":
            if line.startswith(":", prefix.end()):
                return None
            continue
        suffix = _SUFFIX.match(line, prefix.end())
        if suffix is None:
            # "%CHECK %s" in a RUN line, "CHECK-NEXT" without colon in prose: not directives.
            continue
        name = suffix.group(1) or ""
        kind = CheckKind("CHECK-COUNT" if name.startswith("-COUNT-") else "CHECK" + name)
        pattern = line[suffix.end() :].strip(" \t")
        return Check(kind, pattern, number, literal=suffix.group(2) is not None)
    return None


class _PatternError(Exception):
    pass


@dataclass(frozen=True)
class _Matcher:
    check: Check
    regex: re.Pattern[str]
    full_line: bool

    def search(self, segment: str) -> tuple[int, int] | None:
        if self.full_line:
            return (0, len(segment)) if self.regex.fullmatch(segment) else None
        found = self.regex.search(segment)
        return None if found is None else found.span()


def _canonical(text: str) -> str:
    return _BLANKS.sub(" ", text)


def _compile(check: Check, match_full_lines: bool) -> _Matcher:
    if check.kind not in _SUPPORTED:
        raise _PatternError(f"{check.kind.value} is not supported")
    if check.kind is CheckKind.EMPTY:
        if check.pattern:
            raise _PatternError("CHECK-EMPTY must have an empty pattern")
        # _Run finds empty lines itself; the matcher only carries the check.
        return _Matcher(check, re.compile(""), full_line=True)
    if not check.pattern:
        raise _PatternError("empty pattern")
    pattern = _canonical(check.pattern)
    body = re.escape(pattern) if check.literal else _regex_body(pattern)
    full_line = match_full_lines and check.kind is not CheckKind.NOT
    if full_line:
        # The output is canonical too, so a single optional space covers any leading or
        # trailing blanks, as FileCheck's " *" does.
        body = f" ?(?:{body}) ?"
    try:
        regex = re.compile(body)
    except re.error as error:
        raise _PatternError(f"invalid regular expression: {error}") from None
    return _Matcher(check, regex, full_line)


def _regex_body(pattern: str) -> str:
    parts: list[str] = []
    rest = pattern
    while rest:
        if rest.startswith("{{"):
            end = rest.find("}}", 2)
            if end < 0:
                raise _PatternError("'{{' without a closing '}}'")
            # A group, so that an alternation stays inside its block.
            parts.append(f"(?:{rest[2:end]})")
            rest = rest[end + 2 :]
            continue
        if rest.startswith("[["):
            raise _PatternError("[[...]] substitution blocks are not supported")
        stops = [index for index in (rest.find("{{"), rest.find("[[")) if index >= 0]
        end = min(stops) if stops else len(rest)
        parts.append(re.escape(rest[:end]))
        rest = rest[end:]
    return "".join(parts)


@dataclass
class _Position:
    line: int
    column: int


def match_output(
    checks: list[Check], output: str, *, match_full_lines: bool = True
) -> FileCheckResult:
    """Check `output` against `checks` with FileCheck's rules (see the module docstring)."""
    if not checks:
        return FileCheckResult(False, "no CHECK directives to match")
    matchers: list[_Matcher] = []
    seen_positive = False
    for check in checks:
        if check.kind in _FOLLOWERS and not seen_positive:
            return FileCheckResult(
                False, f"{check.describe()}: has no previous CHECK match to follow"
            )
        seen_positive = seen_positive or check.kind is not CheckKind.NOT
        try:
            matchers.append(_compile(check, match_full_lines))
        except _PatternError as error:
            return FileCheckResult(False, f"{check.describe()}: {error}")
    return _Run(output).run(matchers)


class _Run:
    """One pass of the checks over the output, keeping the position of the last match."""

    def __init__(self, output: str) -> None:
        self.raw = output.split("\n")
        self.lines = [_canonical(line) for line in self.raw]
        self.position = _Position(0, 0)

    def run(self, matchers: list[_Matcher]) -> FileCheckResult:
        pending_nots: list[_Matcher] = []
        for matcher in matchers:
            if matcher.check.kind is CheckKind.NOT:
                pending_nots.append(matcher)
                continue
            failure = self._positive(matcher, pending_nots)
            if failure is not None:
                return FileCheckResult(False, failure)
            pending_nots = []
        end = _Position(len(self.lines) - 1, len(self.lines[-1]))
        failure = self._nots(pending_nots, end)
        if failure is not None:
            return FileCheckResult(False, failure)
        return FileCheckResult(True, f"all {len(matchers)} checks passed")

    def _positive(self, matcher: _Matcher, nots: list[_Matcher]) -> str | None:
        check = matcher.check
        previous = self.position
        found = self._find_empty() if check.kind is CheckKind.EMPTY else self._find(matcher)
        if found is None:
            return (
                f"{check.describe()}: not found in the output; scanning from "
                f"{self._show(previous.line)}"
            )
        line, start, end = found
        if check.kind in (CheckKind.NEXT, CheckKind.EMPTY) and line != previous.line + 1:
            where = "the same line as" if line == previous.line else "not the line after"
            return (
                f"{check.describe()}: first match is on {self._show(line)}, {where} the "
                f"previous match on {self._show(previous.line)}"
            )
        if check.kind is CheckKind.SAME and line != previous.line:
            return (
                f"{check.describe()}: first match is on {self._show(line)}, not on the "
                f"line of the previous match, {self._show(previous.line)}"
            )
        failure = self._nots(nots, _Position(line, start))
        if failure is not None:
            return failure
        self.position = _Position(line, end)
        return None

    def _find(self, matcher: _Matcher) -> tuple[int, int, int] | None:
        line, column = self.position.line, self.position.column
        found = matcher.search(self.lines[line][column:])
        if found is not None:
            return line, column + found[0], column + found[1]
        for index in range(line + 1, len(self.lines)):
            found = matcher.search(self.lines[index])
            if found is not None:
                return index, found[0], found[1]
        return None

    def _find_empty(self) -> tuple[int, int, int] | None:
        for index in range(self.position.line + 1, len(self.lines)):
            if not self.lines[index]:
                return index, 0, 0
        return None

    def _nots(self, nots: list[_Matcher], end: _Position) -> str | None:
        """The failure of the first CHECK-NOT found between the position and `end`."""
        start = self.position
        for matcher in nots:
            for index in range(start.line, end.line + 1):
                first = start.column if index == start.line else 0
                last = end.column if index == end.line else len(self.lines[index])
                if matcher.search(self.lines[index][first:last]) is not None:
                    return f"{matcher.check.describe()}: excluded text found on {self._show(index)}"
        return None

    def _show(self, index: int) -> str:
        if index >= len(self.raw):
            return "the end of the output"
        return f"output line {index + 1}: {self.raw[index]!r}"
