"""The rules on single expressions. `Scope` runs `check_expression` on each node once, when
it has typed the node (its operands are typed by then)."""

from __future__ import annotations

from backend.compiler import ast
from backend.compiler.checks.access import check_bit_access, check_index
from backend.compiler.checks.dialects import check_non_finite, check_qualified_enum
from backend.compiler.checks.functions import check_function_call
from backend.compiler.checks.literals import check_enum_literal, check_typed_literal
from backend.compiler.checks.methods import (
    check_method_call,
    check_property_read,
    check_self_name,
)
from backend.compiler.checks.names import check_member, check_name
from backend.compiler.checks.operators import check_binary, check_unary
from backend.compiler.checks.references import check_deref
from backend.compiler.infer import MethodCall, Scope
from backend.compiler.types import Type


def check_expression(scope: Scope, expr: ast.Expr, expr_type: Type | None) -> None:
    match expr:
        case ast.IntLiteral() | ast.RealLiteral() | ast.BoolLiteral() | ast.StringLiteral():
            check_typed_literal(scope, expr, expr_type)
        case ast.EnumLiteral():
            check_enum_literal(scope, expr, expr_type)
            check_qualified_enum(scope, expr)
        case ast.NameRef():
            check_name(scope, expr, expr_type)
            check_non_finite(scope, expr)
            check_self_name(scope, expr, scope.dereferenced(expr))
            check_property_read(scope, expr)
        case ast.MemberRef():
            check_member(scope, expr, expr_type)
            check_property_read(scope, expr)
        case ast.IndexRef():
            check_index(scope, expr)
        case ast.BitRef():
            check_bit_access(scope, expr)
        case ast.Deref():
            check_deref(scope, expr)
        case ast.Unary():
            check_unary(scope, expr, expr_type)
        case ast.Binary():
            check_binary(scope, expr, expr_type)
        case ast.Call():
            callee = scope.callee(expr)
            if isinstance(callee, MethodCall):
                check_method_call(scope, expr, callee, as_value=True)
            else:
                check_function_call(scope, expr)
