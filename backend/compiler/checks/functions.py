"""Calls that give a value: only functions do, user ones with arguments that fit their
parameters, standard ones with arguments their typing accepts."""

from __future__ import annotations

from backend.compiler import ast
from backend.compiler.ast import key
from backend.compiler.builtins import Builtin
from backend.compiler.checks.calls import check_connection
from backend.compiler.checks.conversions import (
    check_conversion,
    check_in_out_type,
    check_output_conversion,
)
from backend.compiler.checks.dialects import check_size_of
from backend.compiler.checks.initializers import bool_literal, takes_argument, takes_in_out
from backend.compiler.checks.open_arrays import check_open_array_connections
from backend.compiler.checks.references import (
    check_is_valid_ref,
    check_ref,
    check_reference_argument,
)
from backend.compiler.checks.targets import refuse_system_write
from backend.compiler.codes import Code
from backend.compiler.infer import (
    IMPLICIT_PARAMETERS,
    IsValidRef,
    MethodCall,
    Misfit,
    NoValue,
    RefOf,
    Scope,
    SizeOf,
    StandardFunction,
    TestCall,
    UserFunction,
    binds_reference,
    is_en_eno,
)
from backend.compiler.qualified_names import unknown_qualified
from backend.compiler.resolve import PouSymbols, Variable
from backend.compiler.test_functions import check_test_call
from backend.compiler.types import OpenArrayType, assignable

# why a call in an expression gives no value, by what it calls
NO_VALUE: dict[NoValue, tuple[Code, str]] = {
    "method": (Code.NO_METHOD, "'{name}' is no method of what it is called on"),
    "super": (Code.THIS_SUPER, "SUPER^() calls the base's body: call it as a statement"),
    "action": (Code.ACTION_VALUE, "action '{name}' has no value; call it as a statement"),
    "instance": (Code.INSTANCE_VALUE, "function block instance '{name}' has no value"),
    "program": (Code.PROGRAM_VALUE, "program '{name}' has no value; call it as a statement"),
    "external": (Code.EXTERNAL_FUNCTION, "external function '{name}' is not available"),
    "unknown": (Code.NOT_A_FUNCTION, "'{name}' is not a function"),
}


def check_function_call(scope: Scope, call: ast.Call) -> None:
    match scope.callee(call):
        case UserFunction(pou=pou):
            check_user_call(scope, pou, call)
        case SizeOf():
            check_size_of(scope, call)
        case RefOf(pointer=pointer):
            check_ref(scope, call, pointer)
        case IsValidRef():
            check_is_valid_ref(scope, call)
        case MethodCall():
            pass  # checks.methods (check_method_call), which needs to know how it is used
        case TestCall(function=function):
            # as a statement, checks.statements takes it before it is typed as a value
            if function.gives is None:
                message = f"{function.name} gives no value: call it as a statement"
                scope.report(call.pos, Code.TEST_VALUE, message)
            else:
                check_test_call(scope, call, function)
        case StandardFunction(builtin=builtin):
            check_standard_enable(scope, call)
            misfit = scope.standard_call(builtin, call)
            if isinstance(misfit, Misfit):
                code, problem = _misfit(misfit, builtin)
                scope.report(misfit.pos, code, f"'{call.name}' {problem}")
        case no_value:
            if call.instance is not None and scope.type_of(call.instance) is None:
                return  # reported where the instance is named
            code, message = NO_VALUE[no_value]
            message = message.format(name=call.name)
            qualified = call.instance is None and call.receiver is None and "." in call.name
            if no_value == "unknown" and qualified:  # `Tc2_System.F()`: qualified_names
                message += f": {unknown_qualified(call.name, 'function')}"
            scope.report(call.pos, code, message)


def _misfit(misfit: Misfit, builtin: Builtin) -> tuple[Code, str]:
    match misfit.kind:
        case "no parameter":
            return Code.NO_PARAMETER, f"has no parameter '{misfit.detail}'"
        case "too many":
            return Code.TOO_MANY_ARGUMENTS, f"takes {len(builtin.params or ())} arguments"
        case "missing":
            return Code.MISSING_ARGUMENTS, f"needs {', '.join(builtin.params or ())}"
        case "too few":
            return Code.MISSING_ARGUMENTS, f"needs at least {builtin.min_args} arguments"
        case "types":
            return Code.STANDARD_ARGUMENTS, misfit.detail  # what the function's typing says


def check_standard_enable(scope: Scope, call: ast.Call) -> None:
    """EN (a BOOL input) and ENO (a BOOL output) of a standard function's call."""
    for arg in call.args:
        if not is_en_eno(arg):
            continue
        param = IMPLICIT_PARAMETERS[key(arg.name or "")]
        if arg.is_output and param.kind == "VAR_INPUT":
            message = f"'{param.name}' of '{call.name}' is an input, not an output"
            scope.report(arg.pos, Code.INPUT_AS_OUTPUT, message)
            continue
        check_argument(scope, arg, param)


def check_user_call(scope: Scope, pou: PouSymbols, call: ast.Call) -> None:
    pairs = scope.connect_arguments(pou, call)
    check_connection(scope, pou, call, pairs)
    check_open_array_connections(scope, pou, call, pairs)
    for arg, param in pairs:
        if param is not None:
            check_argument(scope, arg, param)


def check_argument(scope: Scope, arg: ast.Argument, param: Variable) -> None:
    if arg.value is None:
        return
    if binds_reference(param, arg):
        check_reference_argument(scope, param, arg.value)
        return
    if param.kind in ("VAR_OUTPUT", "VAR_IN_OUT") or arg.is_output:
        refuse_system_write(scope, arg.value)
    value_type = scope.type_of(arg.value)
    if value_type is None:
        return
    if param.kind == "VAR_OUTPUT" or arg.is_output:
        if isinstance(param.type, OpenArrayType):
            fits = param.type.binds(value_type)  # bound to the array connected
        else:
            fits = assignable(value_type, param.type) or scope.conforms(value_type, param.type)
        if not fits:
            message = f"cannot store {param.type.name} output in {value_type.name}"
            scope.report(arg.value.pos, Code.OUTPUT_TYPE, message)
        else:
            check_output_conversion(scope, value_type, param.type, arg.value.pos)
        return
    takes_it = takes_in_out if param.kind == "VAR_IN_OUT" else takes_argument
    if not takes_it(param.type, arg.value, value_type, scope):
        message = f"type mismatch: cannot pass {value_type.name} as {param.type.name}"
        scope.report(arg.value.pos, Code.ARGUMENT_TYPE, message)
    elif param.kind == "VAR_IN_OUT":
        check_in_out_type(scope, param.type, arg.value, value_type)
    elif not bool_literal(param.type, arg.value):
        check_conversion(scope, param.type, arg.value, value_type)
