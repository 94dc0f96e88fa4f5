"""Methods and inheritance (IEC 61131-3 ed. 3): who may call a method (its access
specifier), THIS and SUPER, and what EXTENDS, ABSTRACT, FINAL and OVERRIDE demand of the
blocks that declare them."""

from __future__ import annotations

from backend.compiler import ast
from backend.compiler.ast import key
from backend.compiler.checks.calls import check_connection
from backend.compiler.checks.functions import check_argument
from backend.compiler.checks.open_arrays import check_open_array_connections
from backend.compiler.checks.targets import check_accessor, is_lvalue, writable_target
from backend.compiler.codes import Code
from backend.compiler.infer import SELF_NAMES, MethodCall, Scope
from backend.compiler.resolve import PouSymbols, Resolved, Variable
from backend.compiler.types import ArrayType, FbType, InterfaceType, RefType, StructType, Type


def check_method_call(scope: Scope, call: ast.Call, target: MethodCall, as_value: bool) -> None:
    method = target.method
    if as_value and method.return_type is None:
        message = f"method '{method.name}' has no result; call it as a statement"
        scope.report(call.pos, Code.METHOD_VALUE, message)
    if not scope.may_call(method):
        where = scope.resolved.pous[method.declared_in].name
        message = f"method '{method.name}' of '{where}' is {method.access}"
        if method.method is not None and method.method.access is None:
            message += (
                " (IEC 61131-3 makes a method without access specifier PROTECTED; "
                "declare it METHOD PUBLIC to call it from outside)"
            )
        scope.report(call.pos, Code.METHOD_ACCESS, message)
    if target.static is not None and "ABSTRACT" in _modifiers(method):
        message = f"SUPER^.{method.name}() calls an ABSTRACT method, which has no body"
        scope.report(call.pos, Code.ABSTRACT_METHOD, message)
    pairs = scope.connect_arguments(method, call)
    check_connection(scope, method, call, pairs)
    check_open_array_connections(scope, method, call, pairs)
    for arg, param in pairs:
        if param is not None:
            check_argument(scope, arg, param)


def check_property_read(scope: Scope, expr: ast.Expr) -> None:
    """A property read (not an assignment's target): it has a GET the code may call."""
    found = scope.property_access(expr)
    if found is None or id(expr) in scope.written:
        return
    check_accessor(scope, expr, found, "GET")


def check_self_name(scope: Scope, name: ast.NameRef, dereferenced: bool) -> None:
    """THIS and SUPER: only inside a block (SUPER in one that extends another); SUPER
    only followed by `^` (THIS alone is a REF_TO the block)."""
    if key(name.name) not in SELF_NAMES:
        return
    found = scope.variable(name.name)
    if found is None and scope.lookup(name.name) is None:
        where = "in a block that extends another" if key(name.name) == "SUPER" else "in a block"
        message = f"{name.name} exists only {where} and its methods"
        scope.report(name.pos, Code.THIS_SUPER, message)
    elif found is not None and found.kind == "SUPER" and not dereferenced:
        message = "SUPER is used with ^: SUPER^.M(), SUPER^()"
        scope.report(name.pos, Code.THIS_SUPER, message)


def _modifiers(method: PouSymbols) -> tuple[str, ...]:
    return method.method.modifiers if method.method is not None else ()


def _signature(method: PouSymbols) -> tuple[object, ...]:
    return (
        method.return_type,
        tuple((v.kind, key(v.name), v.type) for v in method.parameters),
    )


# the methods CODESYS calls without a call in the code, by key, with when it calls them
IMPLICIT_METHODS = {
    "FB_INIT": "when an instance is made, before the first cycle",
    "FB_REINIT": "after an instance is copied by an online change",
    "FB_EXIT": "before an instance is removed",
}


def check_block_declaration(scope: Scope, pou: PouSymbols) -> None:
    """The methods a block declares, against its kind and its base's methods."""
    abstract_block = "ABSTRACT" in pou.pou.modifiers
    base = scope.resolved.pous[pou.base] if pou.base is not None else None
    if base is not None and "FINAL" in base.pou.modifiers:
        message = f"'{pou.name}' cannot extend '{base.name}', which is FINAL"
        scope.report(pou.pou.pos, Code.FINAL_OVERRIDE, message)
    for name, method in sorted(pou.methods.items()):
        modifiers = _modifiers(method)
        if method.declared_in != key(pou.name):  # inherited, not overridden
            if "ABSTRACT" in modifiers and not abstract_block:
                message = (
                    f"'{pou.name}' does not implement the ABSTRACT method '{method.name}' of "
                    f"'{scope.resolved.pous[method.declared_in].name}'; implement it or "
                    "declare the block ABSTRACT"
                )
                scope.report(pou.pou.pos, Code.ABSTRACT_METHOD, message)
            continue
        assert method.method is not None
        if name in IMPLICIT_METHODS:
            message = (
                f"'{method.name}' is a method CODESYS calls by itself ({IMPLICIT_METHODS[name]}); "
                "padt runs code only in a cycle, under the watchdog, and calls no method by "
                "itself: give the variables initial values, or call a method of another name "
                "from the body when SYS.START_CYCLE is TRUE"
            )
            scope.report(method.pou.pos, Code.IMPLICIT_METHOD, message)
        if "ABSTRACT" in modifiers and (method.method.body or not abstract_block):
            message = (
                f"ABSTRACT method '{method.name}' has no body, and only an ABSTRACT block "
                "declares one"
            )
            scope.report(method.pou.pos, Code.ABSTRACT_METHOD, message)
        overridden = base.methods.get(name) if base is not None else None
        if overridden is None:
            continue
        if "FINAL" in _modifiers(overridden):
            message = f"method '{method.name}' of '{base.name if base else ''}' is FINAL"
            scope.report(method.pou.pos, Code.FINAL_OVERRIDE, message)
        if _signature(overridden) != _signature(method):
            message = (
                f"method '{method.name}' overrides the one of "
                f"'{scope.resolved.pous[overridden.declared_in].name}' with other parameters "
                "or another result type"
            )
            scope.report(method.pou.pos, Code.OVERRIDE_SIGNATURE, message)


def check_implementations(scope: Scope, pou: PouSymbols) -> None:
    """A block that is not ABSTRACT implements every method of the interfaces it names,
    PUBLIC and with the prototype's parameters and result type."""
    if "ABSTRACT" in pou.pou.modifiers:
        return
    for interface_key in pou.interfaces:
        interface = scope.resolved.interfaces[interface_key]
        for name, prototype in sorted(interface.methods.items()):
            if prototype.declared_in != interface_key:
                continue  # checked with the interface that declares it
            method = pou.methods.get(name)
            problem = None
            if method is None:
                problem = "does not implement it"
            elif _signature(method) != _signature(prototype):
                problem = "implements it with other parameters or another result type"
            elif method.access not in ("PUBLIC", "INTERNAL"):
                problem = f"implements it {method.access}; an interface's methods are PUBLIC"
            if problem is not None:
                message = (
                    f"method '{prototype.name}' of interface '{interface.name}': "
                    f"'{pou.name}' {problem}"
                )
                scope.report(pou.pou.pos, Code.INTERFACE_METHOD, message)
        for name, wanted in sorted(interface.properties.items()):
            if wanted.declared_in != interface_key:
                continue
            prop = pou.properties.get(name)
            problem = None
            if prop is None:
                problem = "does not implement it"
            elif prop.type != wanted.type:
                problem = f"implements it of type {prop.type.name}, not {wanted.type.name}"
            elif (wanted.getter and not prop.getter) or (wanted.setter and not prop.setter):
                problem = "implements it without the GET or SET the interface declares"
            elif prop.access not in ("PUBLIC", "INTERNAL"):
                problem = f"implements it {prop.access}; an interface's properties are PUBLIC"
            if problem is not None:
                message = (
                    f"property '{wanted.name}' of interface '{interface.name}': "
                    f"'{pou.name}' {problem}"
                )
                scope.report(pou.pou.pos, Code.INTERFACE_METHOD, message)


def check_interface(scope: Scope, interface_key: str) -> None:
    """An interface declares prototypes only: methods and property accessors without a
    body."""
    decl = scope.resolved.interfaces[interface_key].decl
    for prototype in decl.methods:
        if prototype.body:
            message = f"method '{prototype.name}' of an interface has no body"
            scope.report(prototype.pos, Code.INTERFACE_METHOD, message)
    for prop in decl.properties:
        for accessor in prop.accessors:
            if accessor.body:
                message = f"{accessor.kind} of property '{prop.name}' of an interface has no body"
                scope.report(accessor.pos, Code.INTERFACE_METHOD, message)


def check_attempt(scope: Scope, target: ast.Expr, value: ast.Initializer) -> None:
    """`t ?= x`: t an interface or a REF_TO a function block; x an instance, an interface,
    or a reference to an instance."""
    target_type = writable_target(scope, target)
    source = scope.type_of(value) if isinstance(value, ast.Expr) else None
    if target_type is None or (source is None and isinstance(value, ast.Expr)):
        return
    takes = isinstance(target_type, InterfaceType) or (
        isinstance(target_type, RefType) and isinstance(target_type.target, FbType)
    )
    gives = (
        isinstance(source, InterfaceType)
        or (isinstance(source, FbType) and isinstance(value, ast.Expr) and is_lvalue(value))
        or (isinstance(source, RefType) and isinstance(source.target, FbType))
    )
    if not (takes and gives):
        message = (
            "?= assigns an instance, an interface or a reference to an instance to an "
            "interface or a REF_TO a function block"
        )
        scope.report(target.pos, Code.TYPE_MISMATCH, message)


def check_abstract_instance(scope: Scope, variable: Variable) -> None:
    """No instance of an ABSTRACT block (a reference to one is fine)."""
    abstract = _abstract_in(scope.resolved, variable.type)
    if abstract is not None:
        message = f"'{variable.name}': '{abstract}' is ABSTRACT and has no instances"
        scope.report(variable.pos, Code.ABSTRACT_INSTANCE, message)


def _abstract_in(resolved: Resolved, t: Type) -> str | None:
    if isinstance(t, FbType):
        pou = resolved.pous.get(key(t.name))
        return t.name if pou is not None and "ABSTRACT" in pou.pou.modifiers else None
    if isinstance(t, ArrayType):
        return _abstract_in(resolved, t.element)
    if isinstance(t, StructType):
        for member in resolved.structs[key(t.name)].members:
            found = _abstract_in(resolved, member.type)
            if found is not None:
                return found
    return None
