"""Go to definition and find references: where the symbol at a place is declared, and
every place in the project's files that names that same symbol (a local `x` of one POU is
not the `x` of another; a member is found through whatever instance names it)."""

from __future__ import annotations

from backend.compiler.ast import key
from backend.compiler.language.analysis import Analysis
from backend.compiler.language.position import (
    Location,
    Range,
    Symbol,
    current_declaration,
    symbol_at,
    token_range,
    token_symbol,
)
from backend.compiler.language.tokens import pieces


def definition(analysis: Analysis, file: str, line: int, col: int) -> Location | None:
    """Where the symbol at file:line:col is declared; None for a name of the standard
    library (it has no file in the project) or a name nothing declares."""
    located = symbol_at(analysis, file, line, col)
    if located is None:
        return None
    return declaration(analysis, located.symbol)


def declaration(analysis: Analysis, symbol: Symbol) -> Location | None:
    """The name in the symbol's declaration, if the project holds it, where it stands in
    the text now."""
    if symbol.standard:
        return None
    pos = current_declaration(analysis, symbol)
    if pos is None:
        return None
    return Location(pos.file, Range(pos.line, pos.col, pos.line, pos.col + len(symbol.name)))


def references(
    analysis: Analysis, file: str, line: int, col: int, *, include_declaration: bool = True
) -> list[Location]:
    """Every place in the project's files that names the symbol at file:line:col, in file,
    line and column order; the declaration among them unless left out."""
    located = symbol_at(analysis, file, line, col)
    if located is None:
        return []
    found = uses(analysis, located.symbol)
    if not include_declaration:
        declared = declaration(analysis, located.symbol)
        found = [location for location in found if location != declared]
    return found


def uses(analysis: Analysis, symbol: Symbol) -> list[Location]:
    """Every place in the project's files that names `symbol` (its declaration too)."""
    wanted = key(symbol.name)
    identity = symbol.identity
    found = []
    for name in sorted(analysis.texts):
        for lexed, before in pieces(analysis.texts[name]):
            for index, token in enumerate(lexed.tokens):
                if token.kind != "ident" or token.upper != wanted:
                    continue
                named = token_symbol(analysis, name, lexed, index, before)
                if named is not None and named.identity == identity:
                    found.append(Location(name, token_range(token, before)))
    return found
