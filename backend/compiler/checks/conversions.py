"""Implicit conversions: where a value of one elementary type is stored in another (an
assignment, an initial value, an argument, an output connected with `=>`), IEC 61131-3
converts it only where no value is lost (its table of implicit conversions,
`types.implicit_conversion`).

Between numbers (integers, bit strings, REAL) CODESYS and TwinCAT convert anything
implicitly and Annex F and rusty's tests rely on it: padt converts too, with the
warning W0811 naming the conversion function. Anything else is an error (E0222): a REAL
literal into an integer, the date and time types into one another (DT into DATE keeps the
time of day), the string types. An in-out argument is passed by reference and must have
the parameter's type exactly (E0417)."""

from __future__ import annotations

from backend.compiler import ast
from backend.compiler.ast import key
from backend.compiler.codes import Code
from backend.compiler.infer import Scope, StandardFunction
from backend.compiler.source import Pos
from backend.compiler.types import (
    ANY_INT,
    ANY_REAL,
    LINT,
    LREAL,
    REAL,
    SINT,
    ArrayType,
    ElementaryType,
    EnumType,
    OpenArrayType,
    Type,
    common_numeric,
    implicit_conversion,
    integer_like,
)

_ARITHMETIC = ("+", "-", "*", "/", "MOD", "AND", "OR", "XOR", "&")
_ANY_INT_RESULTS = ("TRUNC", "LOWER_BOUND", "UPPER_BOUND")


def check_conversion(scope: Scope, target: Type, value: ast.Expr, value_type: Type) -> None:
    """`value` (of `value_type`, which `assignable` let into `target`) is stored in
    `target`: report a conversion that IEC makes only with a conversion function."""
    if not isinstance(target, ElementaryType) or not isinstance(value_type, ElementaryType):
        return
    if isinstance(value, ast.StringLiteral) and value.type_name is None:
        return  # a string literal is a value of the string type it is stored in
    source = source_type(scope, value)
    if source is not None:
        report_conversion(scope, value.pos, target, source, "assign")


def check_output_conversion(scope: Scope, target: Type, output: Type, pos: Pos) -> None:
    """An output of type `output` stored with `=>` in a variable of type `target`."""
    if isinstance(target, ElementaryType) and isinstance(output, ElementaryType):
        report_conversion(scope, pos, target, output, "store output")


def report_conversion(
    scope: Scope, pos: Pos, target: ElementaryType, source: ElementaryType, verb: str
) -> None:
    if implicit_conversion(target, source):
        return
    how = conversion_hint(target, source)
    if source.is_numeric and target.is_numeric and not source.is_any_literal:
        scope.report(
            pos,
            Code.IMPLICIT_NUMERIC_CONVERSION,
            f"CODESYS and TwinCAT convert {source.name} to {target.name} implicitly, "
            f"IEC 61131-3 does not: {how}",
        )
        return
    what = "a REAL literal" if source.is_any_literal else source.name
    scope.report(
        pos,
        Code.EXPLICIT_CONVERSION,
        f"cannot {verb} {what} to {target.name} implicitly: {how}",
    )


def conversion_hint(target: ElementaryType, source: ElementaryType) -> str:
    if source.is_any_literal:
        return "write an integer literal or use TO_" + target.name + "(...)"
    return f"use {source.name}_TO_{target.name}(...) or TO_{target.name}(...)"


def check_in_out_type(scope: Scope, param: Type, value: ast.Expr, value_type: Type) -> bool:
    """An in-out argument is the variable itself, not a copy converted to the parameter's
    type: the types must be the same (strings of any length). True when reported."""
    if same_for_in_out(param, value_type):
        return False
    scope.report(
        value.pos,
        Code.IN_OUT_TYPE,
        f"an in-out parameter of type {param.name} needs a variable of that type, "
        f"not {value_type.name}",
    )
    return True


def same_for_in_out(param: Type, argument: Type) -> bool:
    """Whether an in-out of type `param` can be the variable `argument`: elementary values
    (and arrays of them) must have the same type, strings any length. Blocks, interfaces and
    references have rules of their own (a derived block is passed for its base)."""
    if isinstance(param, ElementaryType) and isinstance(argument, ElementaryType):
        return param.name == argument.name  # STRING[10] for STRING
    if isinstance(param, OpenArrayType):
        return param.binds(argument)
    if isinstance(param, ArrayType) and isinstance(argument, ArrayType):
        return same_for_in_out(param.element, argument.element)
    return True


def source_type(scope: Scope, expr: ast.Expr) -> ElementaryType | None:
    """The type the value of `expr` brings to a conversion. As `scope.type_of`, except that
    an untyped integer literal takes the type of the operands it meets, as IEC types it:
    `i + 1` and `LIMIT(0, i, 9)` with `i : INT` are INTs (the compiler computes them in
    DINT, as CODESYS does, and the store wraps the result back)."""
    typed = scope.type_of(expr)
    found = integer_like(typed) if isinstance(typed, EnumType) else typed
    if not isinstance(found, ElementaryType):
        return None
    if found.category == "real":
        return _real_source(scope, expr, found)
    if not found.is_integer:
        return found
    match expr:
        case ast.Binary(op=op, left=left, right=right) if op in _ARITHMETIC:
            return _joined([source_type(scope, left), source_type(scope, right)], found)
        case ast.Unary(operand=operand):
            return source_type(scope, operand) or found
        case ast.Call():
            callee = scope.callee(expr)
            if isinstance(callee, StandardFunction):
                return _standard_result(scope, callee, expr, found)
    return found


def _real_source(scope: Scope, expr: ast.Expr, found: ElementaryType) -> ElementaryType:
    """An untyped REAL literal with an integer is a REAL where the integer fits one exactly
    (`i * 1.5` with `i : INT`; the compiler computes it in LREAL), with another REAL
    literal it is still a literal."""
    match expr:
        case ast.Binary(op=op, left=left, right=right) if op in _ARITHMETIC:
            sides = [source_type(scope, left), source_type(scope, right)]
            if ANY_REAL not in sides:
                return found
            other = sides[1] if sides[0] == ANY_REAL else sides[0]
            if other == ANY_REAL:
                return ANY_REAL
            if other is None or other == ANY_INT:
                return found  # 2.5 * 3 is computed in LREAL
            if other.category == "real":
                return other
            return REAL if implicit_conversion(REAL, other) else LREAL
        case ast.Unary(operand=operand):
            return source_type(scope, operand) or found
    return found


def _joined(operands: list[ElementaryType | None], found: ElementaryType) -> ElementaryType:
    if None in operands:
        return found
    typed = [t for t in operands if t is not None and t != ANY_INT]
    if not typed:
        return ANY_INT
    if len(typed) == 1:
        return typed[0] if typed[0].is_integer else found
    joined = common_numeric(typed[0], typed[1])
    return joined if joined is not None else found


def _standard_result(
    scope: Scope, callee: StandardFunction, call: ast.Call, found: ElementaryType
) -> ElementaryType:
    """A generic standard function (MIN, LIMIT, SEL, ADD, ...) gives its literal arguments
    the type of the others: typed again with each literal as the last typed integer. TRUNC,
    LOWER_BOUND and UPPER_BOUND give any integer type (IEC's ANY_INT), as a literal does."""
    if key(call.name) in _ANY_INT_RESULTS:
        return ANY_INT
    args = scope.builtin_arguments(callee.builtin, call)
    if not isinstance(args, list):
        return found
    types: list[Type] = []
    for arg in args:
        arg_type = scope.type_of(arg)
        if arg_type is None:
            return found
        types.append(source_type(scope, arg) or arg_type)
    retyped_nothing = all(scope.type_of(arg) == t for arg, t in zip(args, types, strict=True))
    if retyped_nothing and ANY_INT not in types:
        return found
    concrete = [t for t in types if isinstance(t, ElementaryType) and t.is_integer and t != ANY_INT]
    if not concrete:
        return ANY_INT if _generic(callee, types) else found
    retyped = callee.builtin.typing([concrete[-1] if t == ANY_INT else t for t in types])
    return retyped if isinstance(retyped, ElementaryType) else found


def _generic(callee: StandardFunction, types: list[Type]) -> bool:
    """Does the function's result type follow its (literal) arguments' type?"""
    narrow = callee.builtin.typing([SINT if t == ANY_INT else t for t in types])
    wide = callee.builtin.typing([LINT if t == ANY_INT else t for t in types])
    return narrow != wide
