"""One analysis of a project's sources as the language services read it: the parsed units,
the symbol tables and every diagnostic, for the texts as the editor has them (which may
differ from the files on disk)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

from backend.compiler import ast
from backend.compiler.check import check
from backend.compiler.diagnostics import Diagnostic
from backend.compiler.language.reuse import Reuse
from backend.compiler.pipeline import Parsed, in_reading_order, parse_project
from backend.compiler.resolve import Resolved, resolve
from backend.compiler.source import SourceFile


@dataclass(frozen=True)
class Analysis:
    texts: Mapping[str, str]  # file name as diagnostics name it -> its text
    units: tuple[ast.SourceUnit, ...]  # the user's units, then the standard library's
    resolved: Resolved
    user_pous: frozenset[str]  # the keys of the user's POUs
    # of every file, the cause before its consequences: the files that did not parse
    # first, then each file's by place (`pipeline.in_reading_order`)
    diagnostics: tuple[Diagnostic, ...]

    def diagnostics_of(self, file: str) -> list[Diagnostic]:
        """The diagnostics of one file, by place."""
        return sorted(d for d in self.diagnostics if d.file == file)


def analyse(texts: Mapping[str, str]) -> Analysis:
    """The whole project analysed from scratch."""
    return analysed(texts, parse_project([SourceFile(name, texts[name]) for name in sorted(texts)]))


def analysed(texts: Mapping[str, str], parsed: Parsed, reuse: Reuse | None = None) -> Analysis:
    """The analysis of `texts` from their parse, `parse_project(texts)` or its equal;
    with `reuse`, of what the last analysis of the same project found."""
    units, diagnostics, user_pous = parsed
    if reuse is None:
        resolved = resolve(units)
        checked = check(resolved)
    else:
        resolved = resolve(units, reuse.resolve)
        checked = reuse.check(units, resolved)
    found = [*diagnostics, *resolved.diagnostics, *checked]
    unparsed = set(texts) - {unit.file for unit in units}
    ordered = in_reading_order(found, unparsed)
    return Analysis(dict(texts), tuple(units), resolved, frozenset(user_pous), tuple(ordered))
