"""Calls of function blocks and programs as statements: arguments and their kinds; and the
arguments of any call of a user POU, which must name its parameters and not be too many."""

from __future__ import annotations

from backend.compiler import ast
from backend.compiler.checks.actions import check_action_call
from backend.compiler.checks.conversions import (
    check_conversion,
    check_in_out_type,
    check_output_conversion,
)
from backend.compiler.checks.initializers import (
    bool_literal,
    mismatch,
    takes_argument,
    takes_in_out,
)
from backend.compiler.checks.open_arrays import check_open_array_connections
from backend.compiler.checks.references import check_reference_argument
from backend.compiler.checks.targets import is_lvalue, refuse_system_write, writable_target
from backend.compiler.codes import Code
from backend.compiler.infer import Scope, binds_reference
from backend.compiler.resolve import PouSymbols, Variable
from backend.compiler.types import assignable


def check_call_statement(scope: Scope, call: ast.Call) -> None:
    action = scope.action_call(call)
    if action is not None:
        check_action_call(scope, call, action)
        return
    callee = scope.called_instance(call)
    if callee is None:  # `fbs[i](...)`, `s.fb(...)`: an instance given by an expression
        called = scope.expression_instance(call)
        callee = scope.fb_symbols(called[1]) if called is not None else None
    if callee is None:
        scope.type_of(call)  # a function called as a statement
        return
    pairs = scope.connect_arguments(callee, call)
    check_connection(scope, callee, call, pairs)
    check_open_array_connections(scope, callee, call, pairs)
    for arg, param in pairs:
        if param is None:
            if arg.value is not None:
                scope.type_of(arg.value)
            continue
        if arg.is_output and param.kind == "VAR_INPUT":
            scope.report(
                arg.pos,
                Code.INPUT_AS_OUTPUT,
                f"'{param.name}' of '{callee.name}' is an input, not an output",
            )
            continue
        check_fb_argument(scope, callee, arg, param)


def check_connection(
    scope: Scope,
    callee: PouSymbols,
    call: ast.Call,
    pairs: list[tuple[ast.Argument, Variable | None]],
) -> None:
    """`pairs`: the arguments of `call` as `Scope.connect_arguments` paired them."""
    for arg, param in pairs:
        if param is None:
            scope.report(
                arg.pos, Code.NO_PARAMETER, f"'{callee.name}' has no parameter '{arg.name}'"
            )
    positional = [arg for arg in call.args if arg.name is None]
    if len(positional) > sum(1 for arg, _ in pairs if arg.name is None):
        count = len(callee.parameters)
        scope.report(
            call.pos,
            Code.TOO_MANY_ARGUMENTS,
            f"'{callee.name}' takes {count} arguments, not {len(call.args)}",
        )


def check_fb_argument(scope: Scope, fb: PouSymbols, arg: ast.Argument, param: Variable) -> None:
    if arg.value is None:
        return
    if binds_reference(param, arg):
        check_reference_argument(scope, param, arg.value)
        return
    if arg.is_output or param.kind == "VAR_OUTPUT":
        target_type = writable_target(scope, arg.value)
        fits = target_type is None or assignable(target_type, param.type)
        if target_type is not None and not (fits or scope.conforms(target_type, param.type)):
            scope.report(arg.value.pos, Code.OUTPUT_TYPE, mismatch(target_type, param.type))
        elif target_type is not None:
            check_output_conversion(scope, target_type, param.type, arg.value.pos)
        return
    if param.kind == "VAR_IN_OUT" and not is_lvalue(arg.value):
        scope.report(arg.value.pos, Code.IN_OUT_VARIABLE, f"in-out '{param.name}' needs a variable")
    elif param.kind == "VAR_IN_OUT":
        refuse_system_write(scope, arg.value)
    value_type = scope.type_of(arg.value)
    if value_type is None:
        return
    takes_it = takes_in_out if param.kind == "VAR_IN_OUT" else takes_argument
    if not takes_it(param.type, arg.value, value_type, scope):
        scope.report(arg.value.pos, Code.ARGUMENT_TYPE, mismatch(param.type, value_type))
    elif param.kind == "VAR_IN_OUT":
        check_in_out_type(scope, param.type, arg.value, value_type)
    elif not bool_literal(param.type, arg.value):
        check_conversion(scope, param.type, arg.value, value_type)
