"""Variable-length arrays (`ARRAY[*] OF T`): only parameters that an array is bound to at
each call may have one, the inputs, outputs and in-outs of a function (and of a method)
and the in-outs of a function block (IEC 61131-3 ed. 3, 6.5.3); a block's input or output
would have to keep an array between calls. A function's output is bound to the array the
caller connects (`=>`)."""

from __future__ import annotations

from backend.compiler import ast
from backend.compiler.ast import key
from backend.compiler.codes import Code
from backend.compiler.infer import Scope
from backend.compiler.resolve import PouSymbols, Resolved, Variable
from backend.compiler.types import OpenArrayType

ALLOWED = {
    "FUNCTION": ("VAR_INPUT", "VAR_IN_OUT", "VAR_OUTPUT"),
    "METHOD": ("VAR_INPUT", "VAR_IN_OUT", "VAR_OUTPUT"),  # called as a function is
    "FUNCTION_BLOCK": ("VAR_IN_OUT",),
}


def check_open_array_variables(scope: Scope) -> None:
    allowed = ALLOWED.get(scope.pou.kind, ())
    for variable in scope.pou.variables:
        if isinstance(variable.type, OpenArrayType) and variable.kind not in allowed:
            scope.report(variable.pos, Code.VARIABLE_LENGTH_ARRAY, _refusal(variable))


def check_open_array_data(scope: Scope, resolved: Resolved) -> None:
    """Globals and structure members hold their arrays: theirs need bounds."""
    members = [m for _, info in sorted(resolved.structs.items()) for m in info.members]
    for variable in [*resolved.globals, *members]:
        if isinstance(variable.type, OpenArrayType):
            scope.report(variable.pos, Code.VARIABLE_LENGTH_ARRAY, _refusal(variable))


def check_open_array_connections(
    scope: Scope,
    callee: PouSymbols,
    call: ast.Call,
    pairs: list[tuple[ast.Argument, Variable | None]],
) -> None:
    """A variable-length array parameter has no array of its own: each call binds one."""
    connected = {key(param.name) for arg, param in pairs if param is not None and arg.value}
    for param in callee.parameters:
        allowed = param.kind in ALLOWED.get(callee.kind, ())  # else refused where declared
        if isinstance(param.type, OpenArrayType) and allowed and key(param.name) not in connected:
            scope.report(
                call.pos,
                Code.OPEN_ARRAY_UNCONNECTED,
                f"'{callee.name}' needs an array for its parameter '{param.name}' in every call",
            )


def _refusal(variable: Variable) -> str:
    return (
        f"'{variable.name}' cannot be a variable-length array ({variable.type.name}): only "
        "a function's or method's parameters and a function block's VAR_IN_OUT can"
    )
