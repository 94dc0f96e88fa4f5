"""Calls that give a value: only functions do, user ones with arguments that fit their
parameters, standard ones with arguments their typing accepts."""

from __future__ import annotations

from backend.compiler import ast
from backend.compiler.builtins import Builtin
from backend.compiler.checks.calls import check_connection
from backend.compiler.checks.targets import refuse_system_write
from backend.compiler.infer import Misfit, Scope, StandardFunction, UserFunction
from backend.compiler.resolve import PouSymbols, Variable
from backend.compiler.types import assignable


def check_function_call(scope: Scope, call: ast.Call) -> None:
    name = call.name
    match scope.callee(call):
        case UserFunction(pou=pou):
            check_user_call(scope, pou, call)
        case StandardFunction(builtin=builtin):
            misfit = scope.standard_call(builtin, call)
            if isinstance(misfit, Misfit):
                scope.report(misfit.pos, f"'{name}' {_misfit(misfit, builtin)}")
        case "method":
            scope.report(call.pos, "methods are not supported")
        case "instance":
            scope.report(call.pos, f"function block instance '{name}' has no value")
        case "program":
            scope.report(call.pos, f"program '{name}' has no value; call it as a statement")
        case "external":
            scope.report(call.pos, f"external function '{name}' is not available")
        case "pointer":
            scope.report(call.pos, "pointers are not supported (REF and ADR only inside printf)")
        case "unknown":
            scope.report(call.pos, f"'{name}' is not a function")


def _misfit(misfit: Misfit, builtin: Builtin) -> str:
    match misfit.kind:
        case "no parameter":
            return f"has no parameter '{misfit.detail}'"
        case "too many":
            return f"takes {len(builtin.params or ())} arguments"
        case "missing":
            return f"needs {', '.join(builtin.params or ())}"
        case "too few":
            return f"needs at least {builtin.min_args} arguments"
        case "types":
            return misfit.detail  # what the function's typing says


def check_user_call(scope: Scope, pou: PouSymbols, call: ast.Call) -> None:
    pairs = scope.connect_arguments(pou, call)
    check_connection(scope, pou, call, pairs)
    for arg, param in pairs:
        if param is not None:
            check_argument(scope, arg, param)


def check_argument(scope: Scope, arg: ast.Argument, param: Variable) -> None:
    if arg.value is None:
        return
    if param.kind in ("VAR_OUTPUT", "VAR_IN_OUT") or arg.is_output:
        refuse_system_write(scope, arg.value)
    value_type = scope.type_of(arg.value)
    if value_type is None:
        return
    if param.kind == "VAR_OUTPUT" or arg.is_output:
        if not assignable(value_type, param.type):
            message = f"cannot store {param.type.name} output in {value_type.name}"
            scope.report(arg.value.pos, message)
        return
    if not assignable(param.type, value_type):
        message = f"type mismatch: cannot pass {value_type.name} as {param.type.name}"
        scope.report(arg.value.pos, message)
