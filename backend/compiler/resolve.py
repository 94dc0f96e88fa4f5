"""Stage 2, resolve: bind every declaration to a type and build the symbol tables.

The result, `Resolved`, is what check and generate work on. Everything here is sorted by
name so that later stages never depend on the order of files or of hash tables.
"""

from __future__ import annotations

import keyword
from dataclasses import dataclass, field

from backend.compiler import ast
from backend.compiler.ast import key
from backend.compiler.diagnostics import Diagnostic, error
from backend.compiler.types import ELEMENTARY, FbType, Type

INSTANCE_KINDS = ("PROGRAM", "FUNCTION_BLOCK")


@dataclass(frozen=True)
class Variable:
    name: str
    kind: str  # VAR, VAR_INPUT, VAR_OUTPUT, VAR_IN_OUT, VAR_TEMP, VAR_EXTERNAL, VAR_GLOBAL
    type: Type
    init: ast.Expr | None
    constant: bool
    retain: bool
    location: str | None
    attr: str  # the Python attribute name in generated code
    pos: ast.Pos


@dataclass
class PouSymbols:
    pou: ast.Pou
    variables: list[Variable]
    by_key: dict[str, Variable]
    return_type: Type | None = None

    @property
    def name(self) -> str:
        return self.pou.name

    @property
    def kind(self) -> str:
        return self.pou.kind


@dataclass
class Resolved:
    pous: dict[str, PouSymbols] = field(default_factory=dict)  # by key(name)
    diagnostics: list[Diagnostic] = field(default_factory=list)

    def sorted_pous(self) -> list[PouSymbols]:
        return [self.pous[k] for k in sorted(self.pous)]


def python_attr(name: str) -> str:
    """A Python-safe attribute name for an ST identifier (ST allows Python keywords)."""
    return f"{name}_" if keyword.iskeyword(name) or name in ("None", "True", "False") else name


def resolve_type(ref: ast.TypeRef, pou_names: dict[str, ast.Pou]) -> Type | None:
    if isinstance(ref, ast.StringType):
        return ELEMENTARY["WSTRING" if ref.wide else "STRING"]
    elementary = ELEMENTARY.get(key(ref.name))
    if elementary is not None:
        return elementary
    pou = pou_names.get(key(ref.name))
    if pou is not None and pou.kind == "FUNCTION_BLOCK":
        return FbType(pou.name)
    return None


def resolve(units: list[ast.SourceUnit]) -> Resolved:
    result = Resolved()
    pou_names: dict[str, ast.Pou] = {}
    for unit in units:
        for pou in unit.pous:
            previous = pou_names.get(key(pou.name))
            if previous is not None:
                result.diagnostics.append(
                    error(pou.pos, f"'{pou.name}' is already declared at {previous.pos}")
                )
                continue
            pou_names[key(pou.name)] = pou
    for name in sorted(pou_names):
        result.pous[name] = _resolve_pou(pou_names[name], pou_names, result.diagnostics)
    return result


def _resolve_pou(
    pou: ast.Pou, pou_names: dict[str, ast.Pou], diagnostics: list[Diagnostic]
) -> PouSymbols:
    symbols = PouSymbols(pou, [], {})
    if pou.return_type is not None:
        symbols.return_type = resolve_type(pou.return_type, pou_names)
        if symbols.return_type is None:
            diagnostics.append(error(pou.return_type.pos, f"unknown type '{_type_name(pou)}'"))
    for block in pou.var_blocks:
        for decl in block.decls:
            var_type = resolve_type(decl.type, pou_names)
            if var_type is None:
                name = decl.type.name if isinstance(decl.type, ast.NamedType) else "?"
                diagnostics.append(error(decl.type.pos, f"unknown type '{name}'"))
                continue
            if key(decl.name) in symbols.by_key:
                first = symbols.by_key[key(decl.name)]
                diagnostics.append(
                    error(decl.pos, f"'{decl.name}' is already declared at {first.pos}")
                )
                continue
            variable = Variable(
                name=decl.name,
                kind=block.kind,
                type=var_type,
                init=decl.init,
                constant="CONSTANT" in block.qualifiers,
                retain="RETAIN" in block.qualifiers,
                location=decl.location,
                attr=python_attr(decl.name),
                pos=decl.pos,
            )
            symbols.variables.append(variable)
            symbols.by_key[key(decl.name)] = variable
    return symbols


def _type_name(pou: ast.Pou) -> str:
    ref = pou.return_type
    return ref.name if isinstance(ref, ast.NamedType) else "?"
