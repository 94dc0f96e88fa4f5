"""References that padt does not compile: pointers."""

from __future__ import annotations

from backend.compiler import ast
from backend.compiler.codes import Code
from backend.compiler.infer import Scope


def check_pointer(scope: Scope, expr: ast.Deref) -> None:
    scope.report(expr.pos, Code.POINTERS, "pointers are not supported")
