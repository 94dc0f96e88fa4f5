"""Names and members that must exist: declared names, members of structures and function
blocks (those visible from outside), system variables."""

from __future__ import annotations

from backend.compiler import ast
from backend.compiler.ast import key
from backend.compiler.codes import Code
from backend.compiler.infer import SELF_NAMES, Scope
from backend.compiler.qualified_names import unknown_qualified
from backend.compiler.types import FbType, StructType, Type
from runtime.contract.system_variables import NAMESPACE


def check_name(scope: Scope, name: ast.NameRef, name_type: Type | None) -> None:
    if name_type is not None or key(name.name) in SELF_NAMES:  # THIS, SUPER: checks.methods
        return
    if scope.system_namespace(name):
        spelled = name.name
        message = f"{spelled} holds the system variables; name one, as in {spelled}.COLDSTART"
        scope.report(name.pos, Code.SYSTEM_NAMESPACE, message)
    elif name.name.startswith("%"):
        # resolve declares every address no declaration locates: this one is another POU's
        message = (
            f"{name.name} is located in a variable of another POU; declare it in a "
            "VAR_GLOBAL to use it here"
        )
        scope.report(name.pos, Code.DIRECT_ADDRESS, message)
    elif "." in name.name:  # `Tc2_System.PI`: qualified_names found no 'PI'
        message = f"'{name.name}' is not declared: {unknown_qualified(name.name, 'global')}"
        scope.report(name.pos, Code.UNDECLARED, message)
    else:
        scope.report(name.pos, Code.UNDECLARED, f"'{name.name}' is not declared")


def check_member(scope: Scope, member: ast.MemberRef, member_type: Type | None) -> None:
    if member_type is not None:
        return
    if scope.system_namespace(member.base):
        scope.report(
            member.pos,
            Code.UNKNOWN_SYSTEM_VARIABLE,
            f"{NAMESPACE} has no system variable '{member.member}'",
        )
        return
    base_type = scope.type_of(member.base)
    if base_type is None:
        return  # reported where the base is
    # a structure or function block is named in quotes, as where it is declared
    owner = f"'{base_type.name}'" if isinstance(base_type, FbType | StructType) else base_type.name
    scope.report(member.pos, Code.NO_MEMBER, f"{owner} has no member '{member.member}'")
