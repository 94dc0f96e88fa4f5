"""Extensions of CODESYS and TwinCAT that padt accepts, each with a warning that names the
dialect (W08xx): what IEC 61131-3 writes otherwise, or does not have."""

from __future__ import annotations

from backend.compiler import ast
from backend.compiler.codes import Code
from backend.compiler.infer import NonFinite, Scope
from backend.compiler.types import FbType

DIALECT_STATEMENT = "an expression as a statement is CODESYS/TwinCAT, not IEC 61131-3"


def check_qualified_enum(scope: Scope, literal: ast.EnumLiteral) -> None:
    if literal.qualified:
        message = (
            f"'{literal.type_name}.{literal.value}' is CODESYS/TwinCAT; "
            f"IEC 61131-3 writes '{literal.type_name}#{literal.value}'"
        )
        scope.report(literal.pos, Code.QUALIFIED_ENUM, message)


def check_size_of(scope: Scope, call: ast.Call) -> None:
    """SIZEOF(x): one variable or expression whose size CODESYS defines."""
    arguments = call.args
    if len(arguments) != 1 or arguments[0].name is not None or arguments[0].value is None:
        message = "SIZEOF takes one variable or expression, unnamed"
        scope.report(call.pos, Code.SIZEOF_ARGUMENT, message)
        return
    argument_type = scope.type_of(arguments[0].value)
    if argument_type is None:
        return  # reported where the argument is typed
    if scope.size_of(call) is None:
        why = " (a function block instance)" if isinstance(argument_type, FbType) else ""
        message = f"SIZEOF of a {argument_type.name}{why}: padt knows no CODESYS size of it"
        scope.report(call.pos, Code.SIZEOF_ARGUMENT, message)
        return
    message = "SIZEOF is CODESYS/TwinCAT, not IEC 61131-3 (sizes as CODESYS counts them)"
    scope.report(call.pos, Code.SIZEOF, message)


def check_expression_statement(scope: Scope, statement: ast.ExprStatement) -> None:
    """CODESYS accepts any expression as a statement and warns that it does nothing; what
    such a statement likely meant is said where it can be told: `x = 5;` is an assignment
    with a typo, `fb;` a call without its parentheses."""
    expr = statement.expr
    found = scope.type_of(expr)
    if isinstance(expr, ast.Binary) and expr.op == "=" and _is_variable(expr.left):
        target = ast.spelling(expr.left)
        problem = f"'{target} = ...' compares and drops the result: did you mean '{target} := ...'?"
    elif isinstance(found, FbType):
        name = ast.spelling(expr)
        problem = f"'{name}' alone does nothing: did you mean to call it, '{name}();'?"
    else:
        problem = "the value of this expression is dropped: it does nothing"
    scope.report(statement.pos, Code.EXPRESSION_STATEMENT, f"{problem} ({DIALECT_STATEMENT})")


def _is_variable(expr: ast.Expr) -> bool:
    return isinstance(expr, ast.NameRef | ast.MemberRef | ast.IndexRef | ast.BitRef | ast.Deref)


def check_non_finite(scope: Scope, name: ast.NameRef) -> None:
    constant = scope.lookup(name.name)
    if isinstance(constant, NonFinite):
        meaning = "infinity" if constant.name.startswith("INF") else "NaN"
        message = (
            f"'{name.name}', the {constant.type.name} {meaning}, is a constant of rusty; "
            "IEC 61131-3 has no way to write it"
        )
        scope.report(name.pos, Code.NON_FINITE_CONSTANT, message)
