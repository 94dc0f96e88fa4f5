"""What may be written: constants, inputs, FB outputs, step flags and read-only system
variables are protected."""

from __future__ import annotations

from backend.compiler import ast
from backend.compiler.ast import key
from backend.compiler.codes import Code
from backend.compiler.infer import EnumValue, NonFinite, ProgramRef, PropertyAccess, Scope
from backend.compiler.resolve import Variable
from backend.compiler.test_functions import is_test_file
from backend.compiler.types import FbType, StructType, Type, is_implicit_reference, value_type
from runtime.contract.system_variables import NAMESPACE

WRITABLE_MEMBER_KINDS = ("VAR_INPUT", "VAR_IN_OUT", "MEMBER")


def writable_target(scope: Scope, target: ast.Expr) -> Type | None:
    """Type of an assignment target, reporting anything that may not be written."""
    scope.written.add(id(target))  # a property here is set, not read
    part = target.base if isinstance(target, ast.MemberRef | ast.IndexRef | ast.BitRef) else None
    while part is not None:
        if scope.property_access(part) is not None:
            message = "a property is written whole: read it, change the copy, write it back"
            scope.report(part.pos, Code.PROPERTY_ACCESSOR, message)
            return scope.type_of(target)
        part = part.base if isinstance(part, ast.MemberRef | ast.IndexRef | ast.BitRef) else None
    found = scope.property_access(target)
    if found is not None:
        check_accessor(scope, target, found, "SET")
        return scope.type_of(target)
    if isinstance(target, ast.NameRef):
        binding = scope.lookup(target.name)
        if binding is None:
            scope.type_of(target)  # the rules on names say what it is not
            return None
        if isinstance(binding, EnumValue | ProgramRef | NonFinite):
            scope.report(target.pos, Code.ASSIGN_NON_VARIABLE, f"cannot assign to '{target.name}'")
            return None
        if binding.constant:
            scope.report(
                target.pos, Code.ASSIGN_CONSTANT, f"cannot assign to constant '{binding.name}'"
            )
        elif (
            binding.kind == "VAR_INPUT"
            and scope.pou.kind != "FUNCTION"
            and not is_implicit_reference(binding.type)  # it writes the caller's variable
        ):
            # CODESYS, matiec and OSCAT write inputs inside the block; it is legal but
            # a trap (the caller's value is gone for the rest of the call): warn
            scope.report(
                target.pos,
                Code.INPUT_ASSIGNMENT,
                f"assignment to input '{binding.name}' inside its block",
            )
        if binding.kind == "VAR_IN_OUT":
            refuse_cut_instance(scope, target, binding.type)
        return value_type(binding.type)
    if isinstance(target, ast.MemberRef) and scope.system_namespace(target.base):
        refuse_system_write(scope, target)  # SYS.COLDSTART: only the runtime writes it
        return scope.type_of(target)
    if isinstance(target, ast.MemberRef):
        base_type = scope.type_of(target.base)
        scope.type_of(target)  # a member it does not have: the rules on members report it
        member = scope.member(target)
        if member is None:
            return None
        root = target.base
        while isinstance(root, ast.MemberRef | ast.IndexRef):
            root = root.base
        if isinstance(root, ast.NameRef):
            root_binding = scope.lookup(root.name)
            if isinstance(root_binding, Variable) and root_binding.kind == "STEP":
                scope.report(
                    target.pos,
                    Code.STEP_FLAG_WRITE,
                    f"step flag '{root.name}.{target.member}' is read-only",
                )
                return value_type(member.type)
        own = scope.self_deref(target.base) is not None  # THIS^.x: the block's own
        # a test writes any variable, as an online write does (docs/testing.md)
        own = own or is_test_file(scope.pou.pou.pos.file)
        if isinstance(base_type, FbType) and member.kind not in WRITABLE_MEMBER_KINDS and not own:
            scope.report(
                target.pos,
                Code.FB_MEMBER_WRITE,
                f"'{target.member}' of '{base_type.name}' cannot be written from outside",
            )
        if isinstance(base_type, StructType) and not is_lvalue(target.base):
            scope.report(
                target.pos, Code.ASSIGN_MEMBER_OF_VALUE, "cannot assign to a member of a value"
            )
        return value_type(member.type)
    if isinstance(target, ast.IndexRef | ast.BitRef):
        if isinstance(target.base, ast.NameRef | ast.MemberRef | ast.IndexRef | ast.BitRef):
            writable_target(scope, target.base)
        return scope.type_of(target)
    if isinstance(target, ast.Deref):  # `r^ := v` writes what r refers to
        written = scope.type_of(target)
        refuse_cut_instance(scope, target, written)
        return written
    scope.report(target.pos, Code.ASSIGN_EXPRESSION, "cannot assign to an expression")
    return None


def refuse_cut_instance(scope: Scope, target: ast.Expr, written: Type | None) -> None:
    """A whole instance written through an in-out or a reference (E0314): when another
    block extends its block, the place may hold an instance of the derived block, which the
    copy of a base instance would replace by a smaller one."""
    if not isinstance(written, FbType):
        return
    block = key(written.name)
    if any(pou.base == block for pou in scope.resolved.pous.values()):
        scope.report(
            target.pos,
            Code.CUT_INSTANCE,
            f"'{written.name}' is extended: written whole through an in-out or a reference, "
            "it could replace an instance of a derived block; assign its members",
        )


def check_accessor(scope: Scope, expr: ast.Expr, found: PropertyAccess, kind: str) -> None:
    """A property read (`kind` GET) or written (SET): it has that accessor, and its access
    specifier lets the code here call it."""
    prop = found.prop
    accessor = prop.getter if kind == "GET" else prop.setter
    if accessor is None:
        what = "read-only: it has no SET" if kind == "SET" else "write-only: it has no GET"
        scope.report(expr.pos, Code.PROPERTY_ACCESSOR, f"property '{prop.name}' is {what}")
        return
    if not scope.may_call(accessor):
        resolved = scope.resolved
        owner = resolved.pous.get(prop.declared_in) or resolved.interfaces[prop.declared_in]
        message = f"property '{prop.name}' of '{owner.name}' is {accessor.access}"
        scope.report(expr.pos, Code.METHOD_ACCESS, message)


def refuse_system_write(scope: Scope, target: ast.Expr) -> None:
    """Report a write to a read-only system variable (assignment, output, in-out)."""
    while isinstance(target, ast.BitRef | ast.IndexRef):
        target = target.base
    if not isinstance(target, ast.MemberRef) or not scope.system_namespace(target.base):
        return
    scope.type_of(target)  # an unknown name is reported by the rules on members
    variable = scope.resolved.system.get(key(target.member))
    if variable is not None and variable.constant:
        scope.report(
            target.pos,
            Code.SYSTEM_VARIABLE_WRITE,
            f"{NAMESPACE}.{variable.name} is a read-only system variable",
        )


def is_lvalue(expr: ast.Expr) -> bool:
    return isinstance(expr, ast.NameRef | ast.MemberRef | ast.IndexRef | ast.Deref)
