"""ACTIONs called as statements: `act();` inside their POU, `inst.act();` and `Prog.act();`
from outside. An action has no parameters and no value, and its name must not be taken by a
variable of its POU (the call would be ambiguous)."""

from __future__ import annotations

from backend.compiler import ast
from backend.compiler.ast import key
from backend.compiler.codes import Code
from backend.compiler.infer import ActionCall, Scope


def check_action_call(scope: Scope, call: ast.Call, target: ActionCall) -> None:
    for arg in call.args:
        if arg.value is not None:
            scope.type_of(arg.value)
    if call.args:
        scope.report(
            call.args[0].pos,
            Code.ACTION_CALL_ARGUMENTS,
            f"action '{target.action.name}' of '{target.owner.name}' takes no arguments",
        )


def check_action_names(scope: Scope, sfc: ast.Sfc) -> None:
    for action in sfc.actions:
        variable = scope.pou.by_key.get(key(action.name))
        if variable is not None:
            scope.report(
                action.pos,
                Code.ACTION_NAME,
                f"action '{action.name}' has the name of the variable declared at {variable.pos}",
            )
