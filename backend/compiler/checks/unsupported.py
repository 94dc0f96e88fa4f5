"""References that padt does not compile: direct addresses in code and pointers."""

from __future__ import annotations

from backend.compiler import ast
from backend.compiler.codes import Code
from backend.compiler.infer import Scope


def check_reference(scope: Scope, expr: ast.DirectRef | ast.Deref) -> None:
    if isinstance(expr, ast.DirectRef):
        message = "direct addresses in code are not supported; declare a located variable"
        scope.report(expr.pos, Code.DIRECT_ADDRESS, message)
    else:
        scope.report(expr.pos, Code.POINTERS, "pointers are not supported")
