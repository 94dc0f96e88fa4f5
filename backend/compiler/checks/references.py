"""References (IEC 61131-3 ed. 3): what `^` and REF() may apply to."""

from __future__ import annotations

from backend.compiler import ast
from backend.compiler.codes import Code
from backend.compiler.infer import EnumValue, ProgramRef, Scope
from backend.compiler.resolve import Variable
from backend.compiler.types import RefType


def check_deref(scope: Scope, expr: ast.Deref) -> None:
    base_type = scope.type_of(expr.base)
    if base_type is not None and not isinstance(base_type, RefType):
        message = f"'^' needs a reference, not a value of type {base_type.name}"
        scope.report(expr.pos, Code.NOT_A_REFERENCE, message)


def check_ref(scope: Scope, call: ast.Call, pointer: bool = False) -> None:
    """REF(x): x is a variable that lives as long as its instance, so that the reference
    stays good between calls: no function's variable, no VAR_TEMP, no in-out (its place
    is the caller's), no constant, no single bit, no system variable."""
    name = "ADR" if pointer else "REF"
    referenced = scope.referenced(call)
    if referenced is None:
        scope.report(call.pos, Code.REFERENCE_TARGET, f"{name} takes one variable, unnamed")
        return
    if scope.type_of(referenced) is None:
        return  # reported where the argument is
    problem = _unreferenceable(scope, referenced)
    if problem is not None:
        scope.report(call.pos, Code.REFERENCE_TARGET, f"{name} of {problem}")
    elif pointer:
        message = "ADR is CODESYS/TwinCAT; IEC 61131-3 writes REF (no address arithmetic)"
        scope.report(call.pos, Code.POINTER, message)


def _unreferenceable(scope: Scope, expr: ast.Expr) -> str | None:
    match expr:
        case ast.NameRef(name=name):
            binding = scope.lookup(name)
            if isinstance(binding, EnumValue | ProgramRef) or binding is None:
                return f"'{name}', which is no variable"
            return _lasting(scope, binding)
        case ast.MemberRef(base=base):
            if scope.system_namespace(base):
                return "a system variable"
            return _unreferenceable(scope, base)
        case ast.IndexRef(base=base):
            return _unreferenceable(scope, base)
        case ast.Deref():
            return None  # what a reference refers to lasts by construction
        case ast.BitRef():
            return "a single bit"
    return "an expression; it needs a variable"


def _lasting(scope: Scope, variable: Variable) -> str | None:
    if variable.constant:
        return f"constant '{variable.name}'"
    if scope.pou.kind == "FUNCTION" and variable.kind != "VAR_GLOBAL":
        return f"'{variable.name}', a variable of a function (it is gone when the call ends)"
    if variable.kind == "VAR_TEMP":
        return f"'{variable.name}', a VAR_TEMP (it is gone when the call ends)"
    if variable.kind == "VAR_IN_OUT":
        return f"'{variable.name}', an in-out (its place belongs to the caller)"
    if variable.kind in ("SYSTEM", "STEP"):
        return f"'{variable.name}', which the runtime keeps"
    return None
