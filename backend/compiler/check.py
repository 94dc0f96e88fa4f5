"""Stage 3, check: every rule that can be decided before the code runs.

All problems are collected (not only the first) and returned as diagnostics.
"""

from __future__ import annotations

from backend.compiler import ast
from backend.compiler.ast import key
from backend.compiler.diagnostics import Diagnostic
from backend.compiler.infer import Scope
from backend.compiler.resolve import PouSymbols, Resolved, Variable
from backend.compiler.types import BOOL, ElementaryType, FbType, Type, assignable

WRITABLE_MEMBER_KINDS = ("VAR_INPUT", "VAR_IN_OUT")


def check(resolved: Resolved) -> list[Diagnostic]:
    diagnostics: list[Diagnostic] = []
    for pou in resolved.sorted_pous():
        scope = Scope(resolved, pou)
        _check_declarations(scope, pou)
        _check_block(scope, pou.pou.body, loop_depth=0)
        diagnostics.extend(scope.diagnostics)
    return diagnostics


def _check_declarations(scope: Scope, pou: PouSymbols) -> None:
    for variable in pou.variables:
        if variable.init is None:
            continue
        init_type = scope.type_of(variable.init)
        if init_type is not None and not assignable(variable.type, init_type):
            scope.report(variable.init.pos, _mismatch(variable.type, init_type))
        elif isinstance(init_type, ElementaryType) and isinstance(variable.init, ast.IntLiteral):
            _check_range(scope, variable.type, variable.init)
    if pou.kind == "FUNCTION":
        # The thin path compiles PROGRAMs and FUNCTION_BLOCKs; functions follow in full ST.
        scope.report(pou.pou.pos, f"FUNCTION '{pou.name}' is not supported yet")


def _check_block(scope: Scope, body: tuple[ast.Statement, ...], loop_depth: int) -> None:
    for statement in body:
        _check_statement(scope, statement, loop_depth)


def _check_statement(scope: Scope, statement: ast.Statement, loop_depth: int) -> None:
    match statement:
        case ast.Assign(target=target, value=value):
            target_type = _writable_target(scope, target)
            value_type = scope.type_of(value)
            if target_type is not None and value_type is not None:
                if not assignable(target_type, value_type):
                    scope.report(value.pos, _mismatch(target_type, value_type))
                elif isinstance(value, ast.IntLiteral):
                    _check_range(scope, target_type, value)
        case ast.CallStatement(call=call):
            _check_call_statement(scope, call)
        case ast.If(branches=branches, orelse=orelse):
            for condition, block in branches:
                _check_condition(scope, condition)
                _check_block(scope, block, loop_depth)
            _check_block(scope, orelse, loop_depth)
        case ast.While(condition=condition, body=block):
            _check_condition(scope, condition)
            _check_block(scope, block, loop_depth + 1)
        case ast.Repeat(body=block, until=until):
            _check_block(scope, block, loop_depth + 1)
            _check_condition(scope, until)
        case ast.For():
            _check_for(scope, statement, loop_depth)
        case ast.Exit(pos=pos):
            if loop_depth == 0:
                scope.report(pos, "EXIT outside of a loop")
        case ast.Return():
            pass


def _check_for(scope: Scope, loop: ast.For, loop_depth: int) -> None:
    counter = _writable_target(scope, ast.NameRef(loop.variable, loop.pos))
    if counter is not None and not (
        isinstance(counter, ElementaryType) and counter.category == "int"
    ):
        scope.report(loop.pos, f"FOR counter '{loop.variable}' must be an integer")
    for bound in (loop.start, loop.stop, loop.step):
        if bound is None:
            continue
        bound_type = scope.type_of(bound)
        if counter is not None and bound_type is not None and not assignable(counter, bound_type):
            scope.report(bound.pos, _mismatch(counter, bound_type))
    _check_block(scope, loop.body, loop_depth + 1)


def _check_condition(scope: Scope, condition: ast.Expr) -> None:
    condition_type = scope.type_of(condition)
    if condition_type is not None and condition_type != BOOL:
        scope.report(condition.pos, f"condition must be BOOL, not {condition_type.name}")


def _writable_target(scope: Scope, target: ast.Expr) -> Type | None:
    """Type of an assignment target, reporting anything that may not be written."""
    if isinstance(target, ast.NameRef):
        variable = scope.variable(target.name)
        if variable is None:
            scope.report(target.pos, f"'{target.name}' is not declared")
            return None
        _check_own_variable_writable(scope, variable, target.pos)
        return variable.type
    if isinstance(target, ast.MemberRef):
        member = scope.member(target)
        if member is None:
            return None
        if member.kind not in WRITABLE_MEMBER_KINDS:
            scope.report(target.pos, f"output '{target.member}' cannot be written from outside")
        return member.type
    scope.report(target.pos, "cannot assign to an expression")
    return None


def _check_own_variable_writable(scope: Scope, variable: Variable, pos: ast.Pos) -> None:
    if variable.constant:
        scope.report(pos, f"cannot assign to constant '{variable.name}'")
    elif variable.kind == "VAR_INPUT":
        scope.report(pos, f"cannot assign to input '{variable.name}'")


def _check_call_statement(scope: Scope, call: ast.Call) -> None:
    instance = scope.variable(call.name)
    if instance is None or not isinstance(instance.type, FbType):
        scope.type_of(call)  # a function called as a statement: type it for its diagnostics
        return
    fb = scope.fb_symbols(instance.type)
    for arg in call.args:
        if arg.name is None:
            scope.report(arg.pos, "function block arguments must be named (NAME := value)")
            scope.type_of(arg.value)
            continue
        param = fb.by_key.get(key(arg.name))
        wanted = ("VAR_OUTPUT",) if arg.is_output else WRITABLE_MEMBER_KINDS
        if param is None or param.kind not in wanted:
            role = "output" if arg.is_output else "input"
            scope.report(arg.pos, f"'{fb.name}' has no {role} '{arg.name}'")
            scope.type_of(arg.value)
            continue
        if arg.is_output:
            target_type = _writable_target(scope, arg.value)
            if target_type is not None and not assignable(target_type, param.type):
                scope.report(arg.value.pos, _mismatch(target_type, param.type))
        else:
            value_type = scope.type_of(arg.value)
            if value_type is not None and not assignable(param.type, value_type):
                scope.report(arg.value.pos, _mismatch(param.type, value_type))


def _check_range(scope: Scope, target: Type, literal: ast.IntLiteral) -> None:
    if not (isinstance(target, ElementaryType) and target.is_integer):
        return
    if not target.min <= literal.value <= target.max:
        scope.report(literal.pos, f"{literal.value} is out of range for {target.name}")


def _mismatch(target: Type, source: Type) -> str:
    return f"type mismatch: cannot assign {source.name} to {target.name}"
