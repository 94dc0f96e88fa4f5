"""Initial values and assigned values: type compatibility and literal ranges."""

from __future__ import annotations

from collections.abc import Callable

from backend.compiler import ast
from backend.compiler.ast import key
from backend.compiler.checks.conversions import check_conversion
from backend.compiler.codes import Code
from backend.compiler.infer import EnumValue, NonFinite, Scope
from backend.compiler.resolve import Variable
from backend.compiler.types import (
    BOOL,
    ArrayType,
    ElementaryType,
    EnumType,
    FbType,
    InterfaceType,
    OpenArrayType,
    RefType,
    StructType,
    Type,
    assignable,
)


def check_initializer(scope: Scope, target: Type, init: ast.Initializer | None) -> None:
    if init is None:
        return
    if isinstance(init, ast.ArrayInit):
        if not isinstance(target, ArrayType):
            scope.report(
                init.pos,
                Code.ARRAY_INITIALIZER,
                f"an array initializer cannot initialise {target.name}",
            )
            return
        count = 0
        for repeat, value in init.items:
            times = 1
            if repeat is not None:
                if not isinstance(repeat, ast.IntLiteral):
                    scope.report(
                        repeat.pos,
                        Code.REPETITION_COUNT,
                        "repetition count must be an integer literal",
                    )
                else:
                    times = repeat.value
            element_target: Type = target.element
            if isinstance(value, ast.ArrayInit) and not isinstance(target.element, ArrayType):
                for _, inner in value.items:  # a repeated group `n(a, b)`
                    check_initializer(scope, element_target, inner)
                count += times * len(value.items)
                continue
            check_initializer(scope, element_target, value)
            count += times
        if count > target.size:
            scope.report(
                init.pos,
                Code.TOO_MANY_INITIAL_VALUES,
                f"{count} initial values for {target.size} elements",
            )
        return
    if isinstance(init, ast.StructInit):
        if not isinstance(target, StructType | FbType):
            scope.report(
                init.pos,
                Code.STRUCT_INITIALIZER,
                f"a structure initializer cannot initialise {target.name}",
            )
            return
        members = (
            scope.struct(target).by_key
            if isinstance(target, StructType)
            else scope.fb_symbols(target).by_key
        )
        for name, value in init.members:
            member = members.get(key(name))
            if member is None:
                scope.report(init.pos, Code.NO_MEMBER, f"'{target.name}' has no member '{name}'")
                continue
            check_initializer(scope, member.type, value)
        return
    check_value(scope, target, init)


def check_value(scope: Scope, target: Type, value: ast.Expr) -> None:
    scope.expect(value, target)
    value_type = scope.type_of(value)
    if value_type is None:
        return
    if not takes(target, value, value_type, scope):
        scope.report(value.pos, Code.TYPE_MISMATCH, mismatch(target, value_type))
        return
    if isinstance(value, ast.IntLiteral) and value.type_name is None:
        check_range(scope, target, value)
    if not bool_literal(target, value):
        check_conversion(scope, target, value, value_type)


def takes(target: Type, value: ast.Expr, value_type: Type, scope: Scope) -> bool:
    """Can `value` (of `value_type`) be stored in `target`? The types must be assignable
    (or conform, for instances and interfaces); besides, the plain literals 0 and 1 are
    BOOL values (IEC 61131-3 boolean literals)."""
    return (
        assignable(target, value_type)
        or bool_literal(target, value)
        or scope.conforms(target, value_type)
    )


def takes_argument(param: Type, value: ast.Expr, value_type: Type, scope: Scope) -> bool:
    """Can `value` be passed for a parameter of type `param`? As stored, or bound to it
    when the parameter is a variable-length array."""
    if isinstance(param, OpenArrayType):
        return param.binds(value_type)
    return takes(param, value, value_type, scope)


def takes_in_out(param: Type, value: ast.Expr, value_type: Type, scope: Scope) -> bool:
    """Can `value` be an in-out of type `param`? As an argument, or an instance of a block
    derived from the parameter's: the in-out is that instance itself (edition 3, CODESYS),
    whose methods run as its own block has them. An in-out reference or interface is the
    caller's variable, which the callee may set: of the same type only (a REF_TO Base would
    let it store a base instance where the caller holds a REF_TO Derived)."""
    if isinstance(param, FbType) and isinstance(value_type, FbType):
        return scope.resolved.conforms(key(value_type.name), key(param.name))
    if isinstance(param, RefType | InterfaceType):
        return param == value_type
    return takes_argument(param, value, value_type, scope)


def bool_literal(target: Type, value: ast.Expr) -> bool:
    return (
        target == BOOL
        and isinstance(value, ast.IntLiteral)
        and value.type_name is None
        and not value.based
        and value.value in (0, 1)
    )


def literal_fits(target: ElementaryType, literal: ast.IntLiteral) -> bool:
    """A decimal literal must lie in the range; a based one (16#FFFF) is a bit pattern and
    only has to fit the width."""
    if literal.based and 0 <= literal.value < 1 << target.bits:
        return True
    return target.min <= literal.value <= target.max


def check_range(scope: Scope, target: Type, literal: ast.IntLiteral) -> None:
    integer = target.base if isinstance(target, EnumType) else target
    if not (isinstance(integer, ElementaryType) and integer.is_integer):
        return
    if not literal_fits(integer, literal):
        scope.report(
            literal.pos, Code.OUT_OF_RANGE, f"{literal.value} is out of range for {integer.name}"
        )


def mismatch(target: Type, source: Type) -> str:
    return f"type mismatch: cannot assign {source.name} to {target.name}"


def declaration_order(storage: list[Variable]) -> dict[int, int]:
    """The place of each variable (by id) of one storage: a POU, or the globals."""
    return {id(v): i for i, v in enumerate(storage)}


def check_constant_initializer(scope: Scope, variable: Variable, order: dict[int, int]) -> None:
    """An initial value is computed once, before anything runs: IEC allows only constant
    expressions (literals, constants, enum values, standard functions of those). A constant
    of the same storage (the same POU, or the globals; `order` is its declaration order)
    must be declared before it, since initial values are set in declaration order."""
    if variable.init is None:
        return
    place = order.get(id(variable), len(order))

    def set_before(binding: Variable) -> bool:
        return order.get(id(binding), -1) < place

    for expr in _values(variable.init):
        if isinstance(expr, ast.NullLiteral):
            continue
        referenced = _referenced(expr)
        if referenced is not None:
            check_initial_reference(scope, variable, expr, referenced)
        elif not is_constant(scope, expr, set_before):
            scope.report(
                expr.pos,
                Code.NOT_CONSTANT_INITIAL,
                f"initial value of '{variable.name}' must be a constant expression",
            )


def _values(init: ast.Initializer) -> list[ast.Expr]:
    if isinstance(init, ast.ArrayInit):
        return [e for _, value in init.items for e in _values(value)]
    if isinstance(init, ast.StructInit):
        return [e for _, value in init.members for e in _values(value)]
    return [init]


def is_constant(scope: Scope, expr: ast.Expr, set_before: Callable[[Variable], bool]) -> bool:
    """`set_before`: whether a variable's initial value is set before this one's."""
    match expr:
        case (
            ast.IntLiteral() | ast.RealLiteral() | ast.BoolLiteral() | ast.TimeLiteral()
            | ast.StringLiteral() | ast.EnumLiteral()
        ):  # fmt: skip
            return True
        case ast.NameRef(name=name):
            binding = scope.enum_hint(expr) or scope.lookup(name)
            if isinstance(binding, EnumValue | NonFinite):
                return True
            return (
                isinstance(binding, Variable)
                and binding.constant
                and binding.kind != "STEP"
                and set_before(binding)
            )
        case ast.Unary(operand=operand):
            return is_constant(scope, operand, set_before)
        case ast.Binary(left=left, right=right):
            return is_constant(scope, left, set_before) and is_constant(scope, right, set_before)
        case ast.Call(name=name, args=args):
            user_function = key(name) in scope.resolved.pous
            return not user_function and all(
                arg.value is not None and is_constant(scope, arg.value, set_before) for arg in args
            )
    return False


def _referenced(expr: ast.Expr) -> ast.NameRef | None:
    """x of an initial value `REF(x)`."""
    match expr:
        case ast.Call(name=name, args=[ast.Argument(name=None, value=ast.NameRef() as target)]):
            return target if key(name) == "REF" else None
    return None


def check_initial_reference(
    scope: Scope, variable: Variable, expr: ast.Expr, target: ast.NameRef
) -> None:
    """REF(x) as an initial value: x a variable of the instance being set up (made with it,
    and followed anew at each use, so the order of the declarations does not matter), or,
    for a global, another global. A POU's reference to a global is set in its body: a
    program reads the globals through a view of its own, which a reload may replace
    (docs/language.md, References). What REF refuses anywhere (E0219: a VAR_TEMP, an
    in-out, a constant) is reported by its own check."""
    binding = scope.lookup(target.name)
    if not isinstance(binding, Variable):
        return  # reported by REF's own check
    if binding.kind == "VAR_GLOBAL" and variable.kind != "VAR_GLOBAL":
        scope.report(
            expr.pos,
            Code.NOT_CONSTANT_INITIAL,
            f"initial value of '{variable.name}': a POU's reference can start as a reference "
            f"to a variable of its own instance only; set it to REF({target.name}) in the body",
        )
