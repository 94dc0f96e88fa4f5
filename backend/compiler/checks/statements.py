"""Statements: conditions, loops (EXIT/CONTINUE only inside), CASE labels, FOR counters."""

from __future__ import annotations

from backend.compiler import ast
from backend.compiler.ast import key
from backend.compiler.checks.calls import check_call_statement
from backend.compiler.checks.dialects import check_expression_statement
from backend.compiler.checks.initializers import check_initializer, mismatch
from backend.compiler.checks.methods import check_attempt, check_method_call
from backend.compiler.checks.references import check_binding
from backend.compiler.checks.targets import writable_target
from backend.compiler.codes import Code
from backend.compiler.infer import Scope
from backend.compiler.source import Pos
from backend.compiler.test_functions import check_test_call
from backend.compiler.types import BOOL, ElementaryType, Type, assignable, integer_like


def check_block(scope: Scope, body: tuple[ast.Statement, ...], loop_depth: int) -> None:
    for statement in body:
        check_statement(scope, statement, loop_depth)


def check_statement(scope: Scope, statement: ast.Statement, loop_depth: int) -> None:
    match statement:
        case ast.Assign(target=target, value=value, bind=True):
            check_binding(scope, target, value)
        case ast.Assign(target=target, value=value, attempt=True):
            check_attempt(scope, target, value)
        case ast.Assign(target=target, value=value):
            target_type = writable_target(scope, target)
            if target_type is not None:
                check_initializer(scope, target_type, value)
            elif not isinstance(value, ast.ArrayInit | ast.StructInit):
                scope.type_of(value)
        case ast.CallStatement(call=call):
            method = scope.method_call(call)
            test = scope.test_call(call)
            if method is not None:
                check_method_call(scope, call, method, as_value=False)
            elif test is not None:
                check_test_call(scope, call, test)
            elif call.name == "^" and scope.called_instance(call) is None:
                check_super_call(scope, call)
            else:
                check_call_statement(scope, call)
        case ast.ExprStatement():
            check_expression_statement(scope, statement)
        case ast.If(branches=branches, orelse=orelse):
            for condition, block in branches:
                check_condition(scope, condition)
                check_block(scope, block, loop_depth)
            check_block(scope, orelse, loop_depth)
        case ast.Case():
            check_case(scope, statement, loop_depth)
        case ast.While(condition=condition, body=block):
            check_condition(scope, condition)
            check_block(scope, block, loop_depth + 1)
        case ast.Repeat(body=block, until=until):
            check_block(scope, block, loop_depth + 1)
            check_condition(scope, until)
        case ast.For():
            check_for(scope, statement, loop_depth)
        case ast.Exit(pos=pos) | ast.Continue(pos=pos):
            if loop_depth == 0:
                word = "EXIT" if isinstance(statement, ast.Exit) else "CONTINUE"
                scope.report(pos, Code.OUTSIDE_LOOP, f"{word} outside of a loop")
        case ast.Return():
            pass


def check_super_call(scope: Scope, call: ast.Call) -> None:
    """`SUPER^()`, or `x^()` of something that is no reference to a block."""
    assert call.receiver is not None
    if scope.super_body(call) is not None:
        if call.args:
            message = "SUPER^() runs the base's body: it takes no arguments"
            scope.report(call.args[0].pos, Code.THIS_SUPER, message)
        return
    target = scope.type_of(call.receiver)
    base = call.receiver.base if isinstance(call.receiver, ast.Deref) else None
    if isinstance(base, ast.NameRef) and key(base.name) in ("SUPER", "THIS"):
        if key(base.name) == "THIS":
            message = "THIS^() would run the block's body from inside it: call a method"
            scope.report(call.pos, Code.THIS_SUPER, message)
        return  # no SUPER here: the rules on names said so
    if target is not None:  # else the rules on `^` said what it is not
        message = f"r^() calls the function block r refers to, not a value of type {target.name}"
        scope.report(call.pos, Code.NOT_A_REFERENCE, message)


def check_case(scope: Scope, case: ast.Case, loop_depth: int) -> None:
    selector = scope.type_of(case.selector)
    if selector is not None and integer_like(selector) is None:
        scope.report(
            case.selector.pos,
            Code.CASE_SELECTOR_TYPE,
            f"CASE selector must be an integer or enum, not {selector.name}",
        )
    seen: dict[int, Pos] = {}
    for labels, body in case.branches:
        for label in labels:
            bounds = (label.low, label.high) if isinstance(label, ast.CaseRange) else (label,)
            values = [case_label_value(scope, bound, selector) for bound in bounds]
            low, high = values[0], values[-1]  # a single label is checked once
            if low is None or high is None:
                continue
            for value in range(low, high + 1) if high - low < 4096 else ():
                if value in seen:
                    scope.report(
                        label.pos,
                        Code.CASE_LABEL_TWICE,
                        f"CASE label {value} already used at {seen[value]}",
                    )
                    break
                seen[value] = label.pos
        check_block(scope, body, loop_depth)
    check_block(scope, case.orelse, loop_depth)


def case_label_value(scope: Scope, label: ast.Expr, selector: Type | None) -> int | None:
    scope.expect(label, selector)
    label_type = scope.type_of(label)
    if label_type is None:
        return None
    if integer_like(label_type) is None:
        scope.report(
            label.pos,
            Code.CASE_LABEL_TYPE,
            f"CASE label must be an integer or enum, not {label_type.name}",
        )
        return None
    return scope.constant_int(label)


def check_for(scope: Scope, loop: ast.For, loop_depth: int) -> None:
    counter = writable_target(scope, ast.NameRef(loop.variable, loop.pos))
    if counter is not None and not (isinstance(counter, ElementaryType) and counter.is_integer):
        scope.report(
            loop.pos, Code.FOR_COUNTER_TYPE, f"FOR counter '{loop.variable}' must be an integer"
        )
    for bound in (loop.start, loop.stop, loop.step):
        if bound is None:
            continue
        bound_type = scope.type_of(bound)
        if counter is not None and bound_type is not None and not assignable(counter, bound_type):
            scope.report(bound.pos, Code.TYPE_MISMATCH, mismatch(counter, bound_type))
    check_block(scope, loop.body, loop_depth + 1)


def check_condition(scope: Scope, condition: ast.Expr) -> None:
    condition_type = scope.type_of(condition)
    if condition_type is not None and condition_type != BOOL:
        scope.report(
            condition.pos, Code.CONDITION_TYPE, f"condition must be BOOL, not {condition_type.name}"
        )
