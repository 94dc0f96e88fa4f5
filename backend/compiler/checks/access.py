"""Access to parts of a value: array elements (integer indices, as many as the array has
dimensions, constant ones within the bounds) and bits of integers and bit strings."""

from __future__ import annotations

from backend.compiler import ast
from backend.compiler.codes import Code
from backend.compiler.infer import Scope
from backend.compiler.types import ArrayType, OpenArrayType, integer_like


def check_index(scope: Scope, expr: ast.IndexRef) -> None:
    for index in expr.indices:
        index_type = scope.type_of(index)
        if index_type is not None and integer_like(index_type) is None:
            scope.report(
                index.pos, Code.INDEX_TYPE, f"array index must be an integer, not {index_type.name}"
            )
    base_type = scope.type_of(expr.base)
    if base_type is None:
        return
    if isinstance(base_type, OpenArrayType):  # its bounds are checked as it runs
        if len(expr.indices) != base_type.rank:
            message = f"{base_type.name} needs {base_type.rank} indices"
            scope.report(expr.pos, Code.INDEX_COUNT, message)
        return
    if not isinstance(base_type, ArrayType):
        scope.report(expr.pos, Code.NOT_AN_ARRAY, f"{base_type.name} is not an array")
        return
    if len(expr.indices) != len(base_type.dims):
        scope.report(
            expr.pos, Code.INDEX_COUNT, f"{base_type.name} needs {len(base_type.dims)} indices"
        )
        return
    for index, (low, high) in zip(expr.indices, base_type.dims, strict=True):
        constant = scope.constant_int(index)
        if constant is not None and not low <= constant <= high:
            scope.report(
                index.pos,
                Code.INDEX_OUT_OF_BOUNDS,
                f"index {constant} is outside the bounds {low}..{high}",
            )


def check_bit_access(scope: Scope, expr: ast.BitRef) -> None:
    base_type = scope.type_of(expr.base)
    if base_type is None:
        return
    integer = integer_like(base_type)
    if integer is None:
        message = f"bit access needs an integer or bit string, not {base_type.name}"
        scope.report(expr.pos, Code.BIT_ACCESS_TYPE, message)
    elif (expr.bit + 1) * expr.width > integer.bits:
        scope.report(
            expr.pos, Code.BIT_OUT_OF_RANGE, f"part {expr.bit} is out of range for {integer.name}"
        )
