"""CODESYS/TwinCAT names qualified by a library's namespace or a global variable list:
`Tc2_System.T_MaxString`, `Tc2_Standard.TON`, `Tc2_Standard.LEN(s)`, `GVL_Main.nCount`.

padt has no libraries with namespaces and no names for global variable lists: a project is
one namespace. Before resolve, a qualified name whose last part the project (or padt)
declares at the top level becomes that name, with a note that the qualifier is not checked
(N0803); one it does not declare keeps its qualified spelling, so that the error says what
was written (`unknown type 'Tc2_System.T_MaxString'`). IEC wins: in an expression `a.b` is
a member access whenever `a` is declared anywhere in the project (a variable, a POU, a type,
a step, ...); only a qualifier that names nothing is read as a namespace.
"""

from __future__ import annotations

from dataclasses import dataclass, fields, is_dataclass, replace
from typing import Any

from backend.compiler import ast, builtins
from backend.compiler.ast import key
from backend.compiler.codes import Code
from backend.compiler.diagnostics import Diagnostic
from backend.compiler.qualified_enums import global_blocks
from backend.compiler.source import Pos
from backend.compiler.types import elementary

# declarations whose `name` a member access could start from
_DECLARATIONS = (
    ast.VarDecl,
    ast.Pou,
    ast.Method,
    ast.Property,
    ast.Interface,
    ast.TypeDecl,
    ast.Step,
    ast.Action,
    ast.TaskDecl,
    ast.ProgramInstanceDecl,
    ast.ResourceDecl,
    ast.Configuration,
)
# CODESYS's system interface (`INTERFACE I EXTENDS __SYSTEM.IQueryInterface`)
_QUERY_INTERFACE = "__SYSTEM.IQUERYINTERFACE"
# names the compiler knows without a declaration (THIS, SUPER, SYS, the keyword calls)
_RESERVED = {"THIS", "SUPER", "SYS", "ADR", "REF", "SIZEOF"}


def unknown_qualified(name: str, what: str) -> str:
    """Why a qualified `name` (`Tc2_System.T_MaxString`) names nothing, for the error."""
    qualifier, _, last = name.rpartition(".")
    return f"the project declares no {what} '{last}', and padt has no library '{qualifier}'"


@dataclass
class _Names:
    declared: set[str]  # every name declared anywhere: a qualifier that is one is no namespace
    # what a qualified name may name: global variables, POUs, types, interfaces
    top_level: set[str]


# the declarations of a unit
_PARTS = ("pous", "globals", "types", "configurations", "interfaces")


class QualifyMemo:
    """The work of `qualify_names` on each top-level declaration, kept by identity for the
    next run: the language services run it after each keystroke on a project whose
    declarations are, but for the one typed in, the objects they were (the AST is
    immutable). Only the last run's declarations are kept."""

    def __init__(self) -> None:
        self.declared: dict[int, tuple[Any, frozenset[str]]] = {}
        self.names: _Names | None = None
        self.rebuilt: dict[int, tuple[Any, Any, tuple[Diagnostic, ...]]] = {}


def qualify_names(
    units: list[ast.SourceUnit], memo: QualifyMemo | None = None
) -> tuple[list[ast.SourceUnit], list[Diagnostic]]:
    """The units with every qualified name resolved where it can be, and the notes."""
    memo = memo or QualifyMemo()
    names = _project_names(units, memo)
    if names != memo.names:
        memo.names, memo.rebuilt = names, {}
    kept = memo.rebuilt
    memo.rebuilt = {}
    notes: list[Diagnostic] = []

    def qualified(item: Any) -> Any:
        found = kept.get(id(item))
        if found is None:
            qualifier = _Qualifier(names)
            found = (item, qualifier.node(item), tuple(qualifier.notes))
        memo.rebuilt[id(item)] = found
        notes.extend(found[2])
        return found[1]

    result = [
        replace(
            unit,
            pous=tuple(qualified(pou) for pou in unit.pous),
            globals=tuple(qualified(block) for block in unit.globals),
            types=tuple(qualified(decl) for decl in unit.types),
            configurations=tuple(qualified(c) for c in unit.configurations),
            interfaces=tuple(qualified(i) for i in unit.interfaces),
        )
        for unit in units
    ]
    return result, notes


def _project_names(units: list[ast.SourceUnit], memo: QualifyMemo) -> _Names:
    declared: set[str] = set(_RESERVED)
    seen: dict[int, tuple[Any, frozenset[str]]] = {}
    for unit in units:
        for item in (i for part in _PARTS for i in getattr(unit, part)):
            found = memo.declared.get(id(item))
            if found is None:
                names: set[str] = set()
                _collect(item, names)
                found = (item, frozenset(names))
            seen[id(item)] = found
            declared |= found[1]
    memo.declared = seen
    top_level = {key(p.name) for unit in units for p in unit.pous}
    top_level |= {key(t.name) for unit in units for t in unit.types}
    top_level |= {key(i.name) for unit in units for i in unit.interfaces}
    blocks = [block for unit in units for block in global_blocks(unit)]
    instances = {key(d.name) for block in blocks for d in block.decls}
    return _Names(declared, top_level | instances)


def _collect(value: Any, declared: set[str]) -> None:
    """Every declared name under `value`, and the values of every enumeration."""
    if isinstance(value, tuple):
        for item in value:
            _collect(item, declared)
        return
    if not is_dataclass(value) or isinstance(value, Pos | type):
        return
    if isinstance(value, _DECLARATIONS) and isinstance(value.name, str):
        declared.add(key(value.name))
    if isinstance(value, ast.EnumSpec):
        declared |= {key(name) for name, _, _ in value.values}
    if isinstance(value, ast.Expr | ast.Statement):
        return  # declares nothing
    for item in fields(value):
        _collect(getattr(value, item.name), declared)


class _Qualifier:
    """Rebuilds a subtree with its qualified names resolved; a node without one is returned
    as it is (the AST is immutable, so sharing it is safe)."""

    def __init__(self, names: _Names) -> None:
        self.names = names
        self.notes: list[Diagnostic] = []  # and the errors of names a local hides
        self.locals: set[str] = set()  # the variables of the POU being rebuilt, with its methods

    def node(self, value: Any) -> Any:
        return ast.rebuilt(value, self._left, self._entered)

    def _entered(self, value: Any) -> None:
        if isinstance(value, ast.Pou):
            self.locals = set()
            _collect(value.var_blocks, self.locals)
            _collect(value.methods, self.locals)
            _collect(value.properties, self.locals)

    def _left(self, value: Any) -> Any:
        if isinstance(value, ast.Pou):
            self.locals = set()
        return self._resolved(value)

    def _resolved(self, value: Any) -> Any:
        match value:
            case ast.NamedType(name=name, pos=pos) if "." in name:
                return replace(value, name=self._type_name(name, pos))
            case ast.Pou() | ast.Interface() if any("." in n for n in value.extends):
                value = replace(value, extends=self._interfaces(value.extends, value.pos))
        match value:
            case ast.Pou() if any("." in n for n in value.implements):
                return replace(value, implements=self._interfaces(value.implements, value.pos))
            case ast.MemberRef(base=ast.NameRef(name=qualifier), member=member, pos=pos):
                if not self._namespace(qualifier):
                    return value
                known = key(member) in self.names.top_level
                if known and key(member) in self.locals:
                    message = (
                        f"'{qualifier}.{member}' names the global '{member}', which a variable "
                        "of the same name hides here; padt has no names of global lists to "
                        "reach it: rename one"
                    )
                    self.notes.append(Diagnostic.at(pos, Code.UNDECLARED, message))
                    return ast.NameRef(member, pos)
                return ast.NameRef(self._name(qualifier, member, known, pos), pos)
            case ast.Call(receiver=ast.NameRef(name=qualifier), name=member, pos=pos):
                if "." in qualifier or not self._namespace(qualifier):  # `A.B.M()`, B unknown
                    return value
                known = key(member) in self.names.top_level or builtins.lookup(member) is not None
                return replace(value, name=self._name(qualifier, member, known, pos), receiver=None)
        return value

    def _interfaces(self, names: tuple[str, ...], pos: Pos) -> tuple[str, ...]:
        """The names of EXTENDS or IMPLEMENTS, without CODESYS's system interface: every
        interface may extend `__SYSTEM.IQueryInterface` to have the operator
        __QUERYINTERFACE, which padt does not have; it declares nothing else."""
        kept = []
        for name in names:
            declared = "IQUERYINTERFACE" in self.names.top_level  # the project's own wins
            if key(name) == _QUERY_INTERFACE and not declared:
                message = (
                    f"'{name}' left out: padt has no __QUERYINTERFACE, and the system "
                    "interface declares nothing else"
                )
                self.notes.append(Diagnostic.at(pos, Code.QUALIFIED_NAME, message))
                continue
            kept.append(self._type_name(name, pos) if "." in name else name)
        return tuple(kept)

    def _namespace(self, qualifier: str) -> bool:
        return key(qualifier) not in self.names.declared and elementary(qualifier) is None

    def _type_name(self, name: str, pos: Pos) -> str:
        qualifier, _, last = name.rpartition(".")
        known = key(last) in self.names.top_level or elementary(last) is not None
        return self._name(qualifier, last, known, pos)

    def _name(self, qualifier: str, last: str, known: bool, pos: Pos) -> str:
        """`last` when the project declares it (noted), else the qualified spelling."""
        if not known:
            return f"{qualifier}.{last}"
        message = (
            f"'{qualifier}.{last}' read as '{last}': padt has no library namespaces or names "
            f"of global lists, so the qualifier '{qualifier}' is not checked"
        )
        self.notes.append(Diagnostic.at(pos, Code.QUALIFIED_NAME, message))
        return last
