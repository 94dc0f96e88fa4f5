"""What one analysis of a `LanguageProject` leaves to the next: each declaration with its
qualified names resolved (`resolve.ResolveMemo`) and the diagnostics of each POU's check.
Typing in a POU's body changes no declaration of the project, so every other POU checks as
it did: its diagnostics are taken as they were. Typing in the declaration of a POU, a type,
an interface or a global checks again the POUs that name it, or name what names it; a
change in a configuration, or in the direct addresses bodies use, checks everything again.
`tests/compiler/language/test_incremental.py` proves the result equal to a full analysis
after random edits."""

from __future__ import annotations

from dataclasses import dataclass, fields, is_dataclass, replace
from typing import Any

from backend.compiler import ast
from backend.compiler.ast import key
from backend.compiler.check import check_declarations, check_pou
from backend.compiler.diagnostics import Diagnostic
from backend.compiler.resolve import Resolved, ResolveMemo
from backend.compiler.source import Pos

# a top-level declaration by the file it is in, its kind and its name
Place = tuple[str, str, str]


@dataclass(frozen=True)
class _Declarations:
    """All a project declares: each POU (without its body), type, interface and global
    block by place; the rest (configurations, the direct addresses the bodies name, which
    declare globals), as one."""

    named: dict[Place, Any]
    rest: tuple[Any, ...]


class Reuse:
    """Kept by one `LanguageProject` under its lock, for the analysis of its texts."""

    def __init__(self) -> None:
        self.resolve = ResolveMemo()
        self._declarations: _Declarations | None = None
        # by identity (each entry keeps its node alive, so that no other node has its id)
        self._bodiless: dict[int, tuple[ast.Pou, ast.Pou]] = {}
        self._checked: dict[int, tuple[ast.Pou, tuple[Diagnostic, ...]]] = {}
        # `_strings_in` of the nodes looked at last time a declaration changed, and this time
        self._strings: dict[int, tuple[Any, frozenset[str]]] = {}
        self._seen: dict[int, tuple[Any, frozenset[str]]] = {}
        self._declared: tuple[Diagnostic, ...] = ()  # of `check_declarations`

    def check(self, units: list[ast.SourceUnit], resolved: Resolved) -> list[Diagnostic]:
        """`check(resolved)`, the POUs whose check cannot have changed taken as they were:
        a POU of the very same AST that names nothing whose declaration changed."""
        declarations = self._declarations_of(units)
        changed = self._changed_names(self._declarations, declarations)
        kept = self._checked if changed is not None else {}
        self._declarations, self._checked = declarations, {}
        if changed != frozenset():  # the rules on data and globals see the declarations
            self._declared = tuple(check_declarations(resolved))
        diagnostics = list(self._declared)
        for pou in resolved.sorted_pous():
            found = kept.get(id(pou.pou))
            if found is not None and changed and self._strings_of(pou.pou) & changed:
                found = None
            if found is None:
                found = (pou.pou, tuple(check_pou(resolved, pou)))
            self._checked[id(pou.pou)] = found
            diagnostics.extend(found[1])
        if changed:  # what was looked at this time, for the next
            self._strings = self._seen
        return diagnostics

    def _declarations_of(self, units: list[ast.SourceUnit]) -> _Declarations:
        bodiless: dict[int, tuple[ast.Pou, ast.Pou]] = {}
        named: dict[Place, Any] = {}
        rest: list[Any] = []
        for unit in units:
            for pou in unit.pous:
                found = self._bodiless.get(id(pou)) or (pou, replace(pou, body=()))
                bodiless[id(pou)] = found
                named.setdefault((unit.file, "POU", key(pou.name)), []).append(found[1])
            for decl in unit.types:
                named.setdefault((unit.file, "TYPE", key(decl.name)), []).append(decl)
            for interface in unit.interfaces:
                place = (unit.file, "INTERFACE", key(interface.name))
                named.setdefault(place, []).append(interface)
            for number, block in enumerate(unit.globals):
                named[(unit.file, "VAR_GLOBAL", str(number))] = [block]
            rest.append((unit.file, len(unit.globals), unit.configurations, unit.addresses))
        self._bodiless = bodiless
        return _Declarations(named, tuple(rest))

    def _changed_names(
        self, old: _Declarations | None, new: _Declarations
    ) -> frozenset[str] | None:
        """The names whose meaning may have changed since the last analysis: those declared
        in a declaration that changed, and the names of every declaration that names one of
        them. None: anything may have changed."""
        if old is None or old.rest != new.rest:
            return None
        changed_places = {
            place
            for place in old.named.keys() | new.named.keys()
            if old.named.get(place) != new.named.get(place)
        }
        if not changed_places:
            return frozenset()
        self._seen = {}
        changed: set[str] = set()
        for place in changed_places:
            for item in (*old.named.get(place, []), *new.named.get(place, [])):
                changed |= _declared_by(item)
        # what names a changed name declares changed names too, through any chain
        growing = True
        while growing:
            growing = False
            for items in new.named.values():
                for item in items:
                    declared = _declared_by(item)
                    if not declared <= changed and self._strings_of(item) & changed:
                        changed |= declared
                        growing = True
        return frozenset(changed)

    def _strings_of(self, node: Any) -> frozenset[str]:
        """`_strings_in(node)`, kept by identity from the last time it was asked."""
        found = self._seen.get(id(node)) or self._strings.get(id(node))
        if found is None:
            found = (node, _strings_in(node))
        self._seen[id(node)] = found
        return found[1]


def _declared_by(item: Any) -> frozenset[str]:
    """The names a top-level declaration gives the project: a POU's, type's or interface's
    own name, the variables of a global block, and every enumeration value in it (which
    code names without its type). Members are reached through the name of their type."""
    if isinstance(item, ast.VarBlock):
        names = {key(decl.name) for decl in item.decls}
    else:
        names = {key(item.name)}
    pending = [item]
    while pending:
        node = pending.pop()
        if isinstance(node, ast.EnumSpec):
            names |= {key(value) for value, _, _ in node.values}
        if isinstance(node, tuple | list):
            pending.extend(node)
        elif is_dataclass(node) and not isinstance(node, Pos | type):
            pending.extend(getattr(node, f.name) for f in fields(node))
    return frozenset(names)


def _strings_in(value: Any) -> frozenset[str]:
    """Every name, word and text in an AST subtree, by key: all it may name, and more."""
    found: set[str] = set()
    pending = [value]
    while pending:
        item = pending.pop()
        if isinstance(item, str):
            found.add(key(item))
        elif isinstance(item, tuple | list):
            pending.extend(item)
        elif is_dataclass(item) and not isinstance(item, Pos | type):
            pending.extend(getattr(item, f.name) for f in fields(item))
    return frozenset(found)
