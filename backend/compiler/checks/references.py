"""References (IEC 61131-3 ed. 3): what `^` and REF() may apply to."""

from __future__ import annotations

from backend.compiler import ast
from backend.compiler.codes import Code
from backend.compiler.infer import EnumValue, NonFinite, ProgramRef, Scope
from backend.compiler.resolve import Variable
from backend.compiler.types import RefType, Type, is_implicit_reference


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
    problem = None if _holds_reference(scope, referenced) else _unreferenceable(scope, referenced)
    if problem is not None:
        scope.report(call.pos, Code.REFERENCE_TARGET, f"{name} of {problem}")
    elif pointer:
        message = "ADR is CODESYS/TwinCAT; IEC 61131-3 writes REF (no address arithmetic)"
        scope.report(call.pos, Code.POINTER, message)


def check_is_valid_ref(scope: Scope, call: ast.Call) -> None:
    """CODESYS __ISVALIDREF(r): r names a REFERENCE TO (W0806)."""
    referenced = scope.referenced(call)
    if referenced is None:
        message = "__ISVALIDREF takes one REFERENCE TO, unnamed"
        scope.report(call.pos, Code.REFERENCE_BINDING, message)
        return
    if scope.type_of(referenced) is None:
        return  # reported where the argument is
    if not _holds_reference(scope, referenced):
        message = "__ISVALIDREF needs a REFERENCE TO; compare a REF_TO or POINTER TO with NULL"
        scope.report(call.pos, Code.REFERENCE_BINDING, message)
        return
    message = "__ISVALIDREF is CODESYS/TwinCAT; IEC 61131-3 writes r <> NULL with r : REF_TO"
    scope.report(call.pos, Code.IMPLICIT_REFERENCE, message)


def _holds_reference(scope: Scope, expr: ast.Expr) -> bool:
    """Does `expr` name a REFERENCE TO variable (whose REF is the reference it holds, bound
    by a checked REF= or call, so it lasts)?"""
    declared = _declared_type(scope, expr)
    return declared is not None and is_implicit_reference(declared)


def _unreferenceable(scope: Scope, expr: ast.Expr) -> str | None:
    match expr:
        case ast.NameRef(name=name):
            binding = scope.lookup(name)
            if isinstance(binding, EnumValue | ProgramRef | NonFinite) or binding is None:
                return f"'{name}', which is no variable"
            return _lasting(scope, binding)
        case ast.MemberRef(base=base):
            if scope.system_namespace(base):
                return "a system variable"
            if scope.property_access(expr) is not None:
                return "a property, which is no variable"
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
    if scope.pou.kind == "METHOD" and any(v is variable for v in scope.pou.by_key.values()):
        return f"'{variable.name}', a variable of a method (it is gone when the call ends)"
    if variable.kind == "VAR_TEMP":
        return f"'{variable.name}', a VAR_TEMP (it is gone when the call ends)"
    if variable.kind == "VAR_IN_OUT":
        return f"'{variable.name}', an in-out (its place belongs to the caller)"
    if variable.kind in ("THIS", "SUPER"):
        return f"{variable.name}, which is a reference already"
    if variable.kind in ("SYSTEM", "STEP"):
        return f"'{variable.name}', which the runtime keeps"
    return None


def check_binding(scope: Scope, target: ast.Expr, value: ast.Initializer) -> None:
    """CODESYS `r REF= x;` (held as r := REF(x), `bind`): r is a REFERENCE TO of x's type,
    and x a variable REF accepts."""
    declared = _declared_type(scope, target)
    referenced = scope.type_of(value) if isinstance(value, ast.Call) else None
    if declared is None:
        scope.type_of(target)  # the rules on names say what it is not
        return
    if not is_implicit_reference(declared):
        message = f"REF= needs a REFERENCE TO on its left, not a variable of type {declared.name}"
        scope.report(target.pos, Code.REFERENCE_BINDING, message)
        return
    message = "REF= is CODESYS/TwinCAT; IEC 61131-3 writes r := REF(x) with r : REF_TO"
    scope.report(target.pos, Code.IMPLICIT_REFERENCE, message)
    assert isinstance(declared, RefType)
    if isinstance(referenced, RefType) and referenced.target != declared.target:
        assert referenced.target is not None
        message = f"type mismatch: {declared.name} cannot refer to a {referenced.target.name}"
        scope.report(target.pos, Code.TYPE_MISMATCH, message)


def _declared_type(scope: Scope, target: ast.Expr) -> Type | None:
    """The type `target` is declared with (a REFERENCE TO is not yet what it refers to)."""
    if isinstance(target, ast.NameRef):
        binding = scope.lookup(target.name)
        return binding.type if isinstance(binding, Variable) else None
    if isinstance(target, ast.MemberRef):
        scope.type_of(target.base)
        member = scope.member(target)
        return member.type if member is not None else None
    return None


def check_reference_parameter(scope: Scope, variable: Variable) -> None:
    """A REFERENCE TO as an output or in-out: padt passes values there; an in-out of the
    type it refers to does what is meant. As an input the call binds it (below)."""
    if is_implicit_reference(variable.type) and variable.kind in ("VAR_OUTPUT", "VAR_IN_OUT"):
        message = (
            f"'{variable.name}': a REFERENCE TO cannot be a {variable.kind} in padt; "
            "declare it VAR_IN_OUT of the type it refers to"
        )
        scope.report(variable.pos, Code.REFERENCE_BINDING, message)


def check_reference_argument(scope: Scope, param: Variable, value: ast.Expr) -> None:
    """The argument of a REFERENCE TO input: a variable REF accepts (it must outlast the
    call, since an instance keeps the binding), of the type the input refers to."""
    value_type = scope.type_of(value)
    if value_type is None:
        return
    if not _holds_reference(scope, value):
        problem = _unreferenceable(scope, value)
        if problem is not None:
            message = f"REFERENCE TO input '{param.name}' binds to a variable, not to {problem}"
            scope.report(value.pos, Code.REFERENCE_BINDING, message)
            return
    assert isinstance(param.type, RefType) and param.type.target is not None
    target = param.type.target
    if value_type != target and not scope.conforms(param.type, RefType(value_type, implicit=True)):
        message = f"type mismatch: {param.type.name} cannot refer to a {value_type.name}"
        scope.report(value.pos, Code.ARGUMENT_TYPE, message)
