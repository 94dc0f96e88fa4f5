"""Operators and their operands: each operator applies to some types only, and a comparison
needs two values that compare."""

from __future__ import annotations

from backend.compiler import ast
from backend.compiler.codes import Code
from backend.compiler.constants import is_zero_literal
from backend.compiler.infer import COMPARISONS, Scope
from backend.compiler.types import (
    BOOL,
    NULL_TYPE,
    ElementaryType,
    EnumType,
    InterfaceType,
    RefType,
    StructType,
    Type,
    common_numeric,
    integer_like,
)


def check_unary(scope: Scope, expr: ast.Unary, expr_type: Type | None) -> None:
    operand = scope.type_of(expr.operand)
    if operand is not None and expr_type is None:
        scope.report(
            expr.pos, Code.OPERATOR_TYPES, f"'{expr.op}' cannot be applied to {operand.name}"
        )


def check_binary(scope: Scope, expr: ast.Binary, expr_type: Type | None) -> None:
    left, right = scope.type_of(expr.left), scope.type_of(expr.right)
    if left is None or right is None:
        return  # reported where the operand is
    # a comparison is BOOL whatever it compares; any other operation has a type only when
    # the operator applies to its operands
    if expr.op not in COMPARISONS and RefType in (type(left), type(right)):
        message = (
            f"'{expr.op}' on a reference or pointer: padt has no pointer arithmetic; index an "
            "array, or make a reference to the element (REF(a[i]), ADR(a[i]))"
        )
        scope.report(expr.pos, Code.POINTERS, message)
        return
    fits = comparable(expr.op, left, right) if expr.op in COMPARISONS else expr_type is not None
    fits = fits or (expr.op in ("=", "<>") and zero_pointer(expr, left, right))
    if not fits:
        message = f"'{expr.op}' cannot be applied to {left.name} and {right.name}"
        scope.report(expr.pos, Code.OPERATOR_TYPES, message)


def zero_pointer(expr: ast.Binary, left: Type, right: Type) -> bool:
    """CODESYS `p <> 0`: a POINTER compared with the literal 0, which is NULL there."""
    return (isinstance(left, RefType) and left.pointer and is_zero_literal(expr.right)) or (
        isinstance(right, RefType) and right.pointer and is_zero_literal(expr.left)
    )


def comparable(op: str, left_type: Type, right_type: Type) -> bool:
    """Values of the two types can be compared with `op`: enums and structures with = and <>
    when of the same type (an enum with an integer too); numbers with numbers, values of
    one category with each other, BOOL with integers."""
    if isinstance(left_type, RefType | InterfaceType) or isinstance(
        right_type, RefType | InterfaceType
    ):
        # references (and interfaces, which refer to an instance) compare with = and <>
        # when they may refer to the same: same type, or NULL
        return (
            op in ("=", "<>")
            and isinstance(left_type, RefType | InterfaceType)
            and isinstance(right_type, RefType | InterfaceType)
            and (left_type == right_type or NULL_TYPE in (left_type, right_type))
        )
    if op in ("=", "<>") and isinstance(left_type, EnumType | StructType):
        return left_type == right_type or (
            isinstance(left_type, EnumType) and integer_like(right_type) is not None
        )
    left, right = integer_like(left_type) or left_type, integer_like(right_type) or right_type
    if not isinstance(left, ElementaryType) or not isinstance(right, ElementaryType):
        return False
    return (
        common_numeric(left, right) is not None
        or left.category == right.category
        or (left == BOOL and right.is_integer)
        or (right == BOOL and left.is_integer)
    )
