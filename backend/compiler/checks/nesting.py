"""Limits of nesting. The generated Python must compile: CPython allows 200 levels of
parentheses and 100 of indentation, and one ST level can cost up to three of the first and
two of the second. No real program comes near these limits; a generated one might."""

from __future__ import annotations

from collections.abc import Iterator

from backend.compiler import ast
from backend.compiler.codes import Code
from backend.compiler.infer import Scope

MAX_EXPRESSION_DEPTH = 60
MAX_STATEMENT_DEPTH = 40


def check_nesting(scope: Scope, body: tuple[ast.Statement, ...], depth: int = 1) -> bool:
    """Report code nested beyond the limits; True when all of `body` is within them."""
    within = True
    for statement in body:
        if depth > MAX_STATEMENT_DEPTH:
            scope.report(
                statement.pos,
                Code.STATEMENT_DEPTH,
                f"statements nested deeper than {MAX_STATEMENT_DEPTH}",
            )
            return False
        for expr in _expressions(statement):
            if expression_depth(expr) > MAX_EXPRESSION_DEPTH:
                scope.report(
                    expr.pos,
                    Code.EXPRESSION_DEPTH,
                    f"expression nested deeper than {MAX_EXPRESSION_DEPTH}",
                )
                within = False
        for inner in _bodies(statement):
            within = check_nesting(scope, inner, depth + 1) and within
    return within


def expression_depth(expr: ast.Initializer) -> int:
    match expr:
        case ast.Binary(left=left, right=right):
            return 1 + max(expression_depth(left), expression_depth(right))
        case ast.Unary(operand=inner) | ast.MemberRef(base=inner) | ast.BitRef(base=inner):
            return 1 + expression_depth(inner)
        case ast.IndexRef(base=base, indices=indices):
            return 1 + max(expression_depth(e) for e in (base, *indices))
        case ast.Call(args=args):
            values = [a.value for a in args if a.value is not None]
            return 1 + max((expression_depth(v) for v in values), default=0)
        case ast.ArrayInit(items=items):
            return 1 + max((expression_depth(v) for _, v in items), default=0)
        case ast.StructInit(members=members):
            return 1 + max((expression_depth(v) for _, v in members), default=0)
    return 1


def _expressions(statement: ast.Statement) -> Iterator[ast.Initializer]:
    match statement:
        case ast.Assign(target=target, value=value):
            yield target
            yield value
        case ast.CallStatement(call=call):
            yield call
        case ast.If(branches=branches):
            yield from (condition for condition, _ in branches)
        case ast.Case(selector=selector):
            yield selector
        case ast.While(condition=condition) | ast.Repeat(until=condition):
            yield condition
        case ast.For(start=start, stop=stop, step=step):
            yield from (e for e in (start, stop, step) if e is not None)


def _bodies(statement: ast.Statement) -> Iterator[tuple[ast.Statement, ...]]:
    match statement:
        case ast.If(branches=branches, orelse=orelse):
            yield from (body for _, body in branches)
            yield orelse
        case ast.Case(branches=branches, orelse=orelse):
            yield from (body for _, body in branches)
            yield orelse
        case ast.While(body=body) | ast.Repeat(body=body) | ast.For(body=body):
            yield body
