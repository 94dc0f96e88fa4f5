"""Rename: every place that names the symbol at the cursor, given the new name, as edits
per file; or a refusal that says why (not an identifier, a keyword, a name of the
standard library, a name already meaning something where the symbol is named). The
edits are then checked by the compiler: applied to the texts and analysed again, they
are refused if that adds an error."""

from __future__ import annotations

import re
from collections import Counter
from dataclasses import dataclass

from backend.compiler import builtins
from backend.compiler.ast import key
from backend.compiler.diagnostics import Diagnostic
from backend.compiler.language.analysis import Analysis
from backend.compiler.language.completion import ELEMENTARY_TYPES
from backend.compiler.language.language_project import LanguageProject
from backend.compiler.language.navigation import uses
from backend.compiler.language.position import (
    Location,
    Range,
    Symbol,
    lookup,
    member,
    scope_at,
    symbol_at,
)
from backend.compiler.language.tokens import KEYWORDS, piece_at
from backend.compiler.types import FbType, StructType

_IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
_MAX_NAME = 127  # characters; longer names help no reader


@dataclass(frozen=True)
class TextEdit:
    range: Range
    new_text: str


@dataclass(frozen=True)
class FileEdits:
    file: str
    edits: tuple[TextEdit, ...]  # in line, column order; they do not overlap


@dataclass(frozen=True)
class RenameResult:
    files: tuple[FileEdits, ...]  # by file name; empty when refused
    refusal: str = ""  # why the rename cannot be made; "" when it can

    @property
    def ok(self) -> bool:
        return not self.refusal


def rename(analysis: Analysis, file: str, line: int, col: int, new_name: str) -> RenameResult:
    """The edits that rename the symbol at file:line:col to `new_name` everywhere the
    project names it, or a refusal with its reason."""
    located = symbol_at(analysis, file, line, col)
    if located is None:
        return _refused("there is no name of a variable, POU, type or member here")
    symbol = located.symbol
    problem = _name_problem(new_name) or _symbol_problem(symbol)
    if problem:
        return _refused(problem)
    places = uses(analysis, symbol)
    if new_name == symbol.name:
        return RenameResult(())
    if key(new_name) != key(symbol.name):
        clash = _clash(analysis, symbol, places, new_name)
        if clash:
            return _refused(clash)
    files = _edits(places, new_name)
    return _checked(analysis, files, symbol, new_name)


def _refused(reason: str) -> RenameResult:
    return RenameResult((), reason)


def _name_problem(name: str) -> str:
    if not _IDENTIFIER.fullmatch(name) or "__" in name or len(name) > _MAX_NAME:
        return (
            f"'{name[:40]}' is not an identifier: a letter or _ first, then letters, digits "
            f"and single underscores, at most {_MAX_NAME} characters"
        )
    upper = name.upper()
    if upper in KEYWORDS:
        return f"'{name}' is a keyword of the language"
    if upper in ELEMENTARY_TYPES:
        return f"'{name}' is an elementary type"
    if builtins.lookup(name) is not None:
        return f"'{name}' is the name of a standard function"
    return ""


def _symbol_problem(symbol: Symbol) -> str:
    if symbol.kind == "standard_function" or symbol.standard:
        return f"'{symbol.name}' belongs to the standard library; its name cannot change"
    if symbol.kind in ("namespace", "self"):
        return f"'{symbol.name}' is a name of the language; it cannot change"
    if symbol.kind == "variable" and symbol.detail == "SYSTEM":
        return f"'{symbol.name}' is a system variable; its name cannot change"
    if symbol.kind == "pou" and symbol.detail == "PROGRAM":
        return (
            f"'{symbol.name}' is a PROGRAM, which padt.toml's program instances name: rename it "
            "in the project tree, which renames them too"
        )
    return ""


def _clash(analysis: Analysis, symbol: Symbol, places: list[Location], new_name: str) -> str:
    """What `new_name` already means where the symbol is named, if anything."""
    resolved = analysis.resolved
    owner_type: StructType | FbType | None = None
    if symbol.owner and key(symbol.owner) in resolved.structs:
        owner_type = StructType(symbol.owner)
    elif symbol.owner and key(symbol.owner.split(".")[0]) in resolved.pous:
        owner_type = FbType(symbol.owner.split(".")[0])
    if owner_type is not None and symbol.kind in ("variable", "method", "property"):
        found = member(analysis, owner_type, new_name)
        if found is not None:
            return _clash_message(new_name, found, symbol.owner)
    if symbol.kind == "variable" and symbol.detail == "MEMBER":
        return ""  # a structure's member is named only after a dot
    for place in places:
        lexed, before = piece_at(analysis.texts[place.file], place.range.line)
        index = lexed.index_at(place.range.line - before, place.range.col)
        if index > 0 and lexed.tokens[index - 1].text in (".", "#"):
            continue  # named through an instance: checked against the owner's members
        scope = scope_at(analysis, lexed, place.range.line - before, place.range.col)
        found = lookup(analysis, scope, new_name)
        if found is not None and found.identity != symbol.identity:
            where = scope.name if scope is not None else place.file
            return _clash_message(new_name, found, where)
    return ""


def _clash_message(new_name: str, found: Symbol, where: str) -> str:
    declared = f", declared at {found.declared}" if found.declared is not None else ""
    kind = found.kind.replace("_", " ")
    return f"'{new_name}' already names a {kind} in {where}{declared}"


def _edits(places: list[Location], new_name: str) -> tuple[FileEdits, ...]:
    by_file: dict[str, list[TextEdit]] = {}
    for place in places:
        by_file.setdefault(place.file, []).append(TextEdit(place.range, new_name))
    return tuple(
        FileEdits(name, tuple(sorted(edits, key=lambda e: e.range)))
        for name, edits in sorted(by_file.items())
    )


def apply(text: str, edits: tuple[TextEdit, ...]) -> str:
    """`text` with the edits (each on one line) made."""
    lines = text.split("\n")
    for edit in sorted(edits, key=lambda e: e.range, reverse=True):
        line = lines[edit.range.line - 1]
        lines[edit.range.line - 1] = (
            line[: edit.range.col - 1] + edit.new_text + line[edit.range.end_col - 1 :]
        )
    return "\n".join(lines)


def _checked(
    analysis: Analysis, files: tuple[FileEdits, ...], symbol: Symbol, new_name: str
) -> RenameResult:
    """The edits, unless the project with them made has an error it had not before."""
    texts = dict(analysis.texts)
    for edits in files:
        texts[edits.file] = apply(texts[edits.file], edits.edits)
    before = Counter(_error(d.code, d.message, symbol.name, new_name) for d in _errors(analysis))
    after = LanguageProject(texts).analysis()  # the declarations not renamed parse from cache
    for diagnostic in _errors(after):
        problem = _error(diagnostic.code, diagnostic.message, "", "")
        if before[problem] > 0:
            before[problem] -= 1
            continue
        return _refused(
            f"renamed, the project would not compile: {diagnostic.file}:{diagnostic.line}: "
            f"{diagnostic.message} [{diagnostic.code}]"
        )
    return RenameResult(files)


def _errors(analysis: Analysis) -> list[Diagnostic]:
    return [d for d in analysis.diagnostics if d.severity == "error"]


def _error(code: str, message: str, old: str, new: str) -> tuple[str, str]:
    """An error as compared before and after: its message names the new name for the old."""
    return (code, message.replace(f"'{old}'", f"'{new}'") if old else message)
