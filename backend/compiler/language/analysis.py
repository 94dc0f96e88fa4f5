"""One analysis of a project's sources as the language services read it: the parsed units,
the symbol tables and every diagnostic, for the texts as the editor has them (which may
differ from the files on disk)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

from backend.compiler import ast
from backend.compiler.check import check
from backend.compiler.diagnostics import Diagnostic
from backend.compiler.pipeline import parse_project
from backend.compiler.resolve import Resolved, resolve
from backend.compiler.source import SourceFile


@dataclass(frozen=True)
class Analysis:
    texts: Mapping[str, str]  # file name as diagnostics name it -> its text
    units: tuple[ast.SourceUnit, ...]  # the user's units, then the standard library's
    resolved: Resolved
    user_pous: frozenset[str]  # the keys of the user's POUs
    diagnostics: tuple[Diagnostic, ...]  # of every file, sorted by place


def analyse(texts: Mapping[str, str]) -> Analysis:
    """The whole project analysed from scratch."""
    sources = [SourceFile(name, texts[name]) for name in sorted(texts)]
    units, diagnostics, user_pous = parse_project(sources)
    resolved = resolve(units)
    found = [*diagnostics, *resolved.diagnostics, *check(resolved)]
    return Analysis(dict(texts), tuple(units), resolved, frozenset(user_pous), tuple(sorted(found)))
