"""Typed literals: `INT#5` names a known elementary type of the literal's kind; `Color#Red`
names an enum and one of its values."""

from __future__ import annotations

from backend.compiler import ast
from backend.compiler.ast import key
from backend.compiler.codes import Code
from backend.compiler.infer import Scope
from backend.compiler.types import Type, elementary

TypedLiteral = ast.IntLiteral | ast.RealLiteral | ast.BoolLiteral | ast.StringLiteral


def check_typed_literal(scope: Scope, literal: TypedLiteral, literal_type: Type | None) -> None:
    type_name = literal.type_name
    if literal_type is not None or type_name is None:
        return
    if elementary(type_name) is None:
        scope.report(
            literal.pos, Code.UNKNOWN_LITERAL_TYPE, f"unknown type '{type_name}' in typed literal"
        )
    else:
        scope.report(literal.pos, Code.LITERAL_KIND, f"{type_name}# cannot be given this literal")


def check_enum_literal(scope: Scope, literal: ast.EnumLiteral, literal_type: Type | None) -> None:
    if literal_type is not None:
        return
    if key(literal.type_name) not in scope.resolved.enums:
        scope.report(literal.pos, Code.NOT_AN_ENUM, f"'{literal.type_name}' is not an enum type")
    else:
        message = f"enum '{literal.type_name}' has no value '{literal.value}'"
        scope.report(literal.pos, Code.NO_ENUM_VALUE, message)
