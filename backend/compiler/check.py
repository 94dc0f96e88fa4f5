"""Stage 3, check: every rule that can be decided before the code runs.

All problems are collected (not only the first) and returned as diagnostics.
"""

from __future__ import annotations

from backend.compiler import ast
from backend.compiler.ast import key
from backend.compiler.diagnostics import Diagnostic
from backend.compiler.infer import EnumValue, ProgramRef, Scope, is_external
from backend.compiler.resolve import PouSymbols, Resolved, Variable
from backend.compiler.types import (
    BOOL,
    ArrayType,
    ElementaryType,
    EnumType,
    FbType,
    StructType,
    Type,
    assignable,
    integer_like,
)

WRITABLE_MEMBER_KINDS = ("VAR_INPUT", "VAR_IN_OUT", "MEMBER")


def check(resolved: Resolved) -> list[Diagnostic]:
    diagnostics: list[Diagnostic] = []
    if resolved.pous:
        any_pou = resolved.sorted_pous()[0]
        global_scope = Scope(resolved, PouSymbols(any_pou.pou, [], {}))
        for variable in resolved.globals:
            check_initializer(global_scope, variable.type, variable.init)
        diagnostics.extend(global_scope.diagnostics)
    for pou in resolved.sorted_pous():
        if is_external(pou):
            continue
        scope = Scope(resolved, pou)
        for variable in pou.variables:
            if variable.kind != "VAR_GLOBAL":
                check_initializer(scope, variable.type, variable.init)
            if variable.edge is not None and (
                variable.kind != "VAR_INPUT" or variable.type != BOOL
            ):
                scope.report(variable.pos, f"{variable.edge} needs a BOOL input")
        _check_block(scope, pou.pou.body, loop_depth=0)
        if pou.pou.sfc is not None:
            _check_sfc(scope, pou.pou.sfc)
        diagnostics.extend(scope.diagnostics)
    return diagnostics


QUALIFIERS = ("N", "R", "S", "P", "P0", "P1", "L", "D", "SD", "DS", "SL")
TIMED_QUALIFIERS = ("L", "D", "SD", "DS", "SL")


def _sfc_networks(sfc: ast.Sfc) -> list[list[ast.Step]]:
    """The independent step chains of a POU (steps linked by transitions), in text order."""
    owner = {key(step.name): key(step.name) for step in sfc.steps}

    def root(name: str) -> str:
        while owner[name] != name:
            name = owner[name]
        return name

    for transition in sfc.transitions:
        names = [key(n) for n in (*transition.sources, *transition.targets) if key(n) in owner]
        for other in names[1:]:
            owner[root(other)] = root(names[0])
    networks: dict[str, list[ast.Step]] = {}
    for step in sfc.steps:
        networks.setdefault(root(key(step.name)), []).append(step)
    return list(networks.values())


def _check_sfc(scope: Scope, sfc: ast.Sfc) -> None:
    for network in _sfc_networks(sfc):
        initial = [step for step in network if step.initial]
        if len(initial) != 1:
            where = initial[1].pos if len(initial) > 1 else network[0].pos
            names = ", ".join(step.name for step in network)
            scope.report(
                where, f"the step chain {names} needs exactly one INITIAL_STEP, not {len(initial)}"
            )
    steps = {key(step.name) for step in sfc.steps}
    actions: dict[str, ast.Action] = {}
    for action in sfc.actions:
        if key(action.name) in actions:
            scope.report(action.pos, f"action '{action.name}' is declared twice")
        actions[key(action.name)] = action
        _check_block(scope, action.body, loop_depth=0)
    for step in sfc.steps:
        for association in step.associations:
            _check_association(scope, association, actions)
    for transition in sfc.transitions:
        for name in (*transition.sources, *transition.targets):
            if key(name) not in steps:
                scope.report(transition.pos, f"transition refers to '{name}', which is no step")
        _check_condition(scope, transition.condition)


def _check_association(
    scope: Scope, association: ast.ActionAssociation, actions: dict[str, ast.Action]
) -> None:
    if key(association.action) not in actions:
        variable = scope.variable(association.action)
        if variable is None or variable.type != BOOL:
            scope.report(
                association.pos,
                f"'{association.action}' is neither an ACTION nor a BOOL variable",
            )
    qualifier = association.qualifier
    if qualifier not in QUALIFIERS:
        scope.report(association.pos, f"unknown action qualifier '{qualifier}'")
        return
    if qualifier in TIMED_QUALIFIERS:
        if association.duration is None:
            scope.report(
                association.pos, f"qualifier {qualifier} needs a time: ({qualifier}, T#1s)"
            )
            return
        duration = scope.type_of(association.duration)
        if duration is not None and not (
            isinstance(duration, ElementaryType) and duration.category == "time"
        ):
            scope.report(association.pos, f"the time of {qualifier} must be a TIME")
    elif association.duration is not None:
        scope.report(association.pos, f"qualifier {qualifier} takes no time")


def check_initializer(scope: Scope, target: Type, init: ast.Initializer | None) -> None:
    if init is None:
        return
    if isinstance(init, ast.ArrayInit):
        if not isinstance(target, ArrayType):
            scope.report(init.pos, f"an array initializer cannot initialise {target.name}")
            return
        count = 0
        for repeat, value in init.items:
            times = 1
            if repeat is not None:
                if not isinstance(repeat, ast.IntLiteral):
                    scope.report(repeat.pos, "repetition count must be an integer literal")
                else:
                    times = repeat.value
            element_target: Type = target.element
            if isinstance(value, ast.ArrayInit) and not isinstance(target.element, ArrayType):
                for _, inner in value.items:  # a repeated group `n(a, b)`
                    check_initializer(scope, element_target, inner)
                count += times * len(value.items)
                continue
            check_initializer(scope, element_target, value)
            count += times
        if count > target.size:
            scope.report(init.pos, f"{count} initial values for {target.size} elements")
        return
    if isinstance(init, ast.StructInit):
        if not isinstance(target, StructType | FbType):
            scope.report(init.pos, f"a structure initializer cannot initialise {target.name}")
            return
        members = (
            scope.struct(target).by_key
            if isinstance(target, StructType)
            else scope.fb_symbols(target).by_key
        )
        for name, value in init.members:
            member = members.get(key(name))
            if member is None:
                scope.report(init.pos, f"'{target.name}' has no member '{name}'")
                continue
            check_initializer(scope, member.type, value)
        return
    _check_value(scope, target, init)


def _check_value(scope: Scope, target: Type, value: ast.Expr) -> None:
    scope.expect(value, target)
    value_type = scope.type_of(value)
    if value_type is None:
        return
    if not assignable(target, value_type):
        scope.report(value.pos, _mismatch(target, value_type))
    elif isinstance(value, ast.IntLiteral) and value.type_name is None:
        _check_range(scope, target, value)


def literal_fits(target: ElementaryType, literal: ast.IntLiteral) -> bool:
    """A decimal literal must lie in the range; a based one (16#FFFF) is a bit pattern and
    only has to fit the width."""
    if literal.based and 0 <= literal.value < 1 << target.bits:
        return True
    return target.min <= literal.value <= target.max


def _check_block(scope: Scope, body: tuple[ast.Statement, ...], loop_depth: int) -> None:
    for statement in body:
        _check_statement(scope, statement, loop_depth)


def _check_statement(scope: Scope, statement: ast.Statement, loop_depth: int) -> None:
    match statement:
        case ast.Assign(target=target, value=value):
            target_type = _writable_target(scope, target)
            if target_type is not None:
                check_initializer(scope, target_type, value)
            elif not isinstance(value, ast.ArrayInit | ast.StructInit):
                scope.type_of(value)
        case ast.CallStatement(call=call):
            _check_call_statement(scope, call)
        case ast.If(branches=branches, orelse=orelse):
            for condition, block in branches:
                _check_condition(scope, condition)
                _check_block(scope, block, loop_depth)
            _check_block(scope, orelse, loop_depth)
        case ast.Case():
            _check_case(scope, statement, loop_depth)
        case ast.While(condition=condition, body=block):
            _check_condition(scope, condition)
            _check_block(scope, block, loop_depth + 1)
        case ast.Repeat(body=block, until=until):
            _check_block(scope, block, loop_depth + 1)
            _check_condition(scope, until)
        case ast.For():
            _check_for(scope, statement, loop_depth)
        case ast.Exit(pos=pos) | ast.Continue(pos=pos):
            if loop_depth == 0:
                word = "EXIT" if isinstance(statement, ast.Exit) else "CONTINUE"
                scope.report(pos, f"{word} outside of a loop")
        case ast.Return():
            pass


def _check_case(scope: Scope, case: ast.Case, loop_depth: int) -> None:
    selector = scope.type_of(case.selector)
    if selector is not None and integer_like(selector) is None:
        scope.report(
            case.selector.pos, f"CASE selector must be an integer or enum, not {selector.name}"
        )
    seen: dict[int, ast.Pos] = {}
    for labels, body in case.branches:
        for label in labels:
            bounds = (label.low, label.high) if isinstance(label, ast.CaseRange) else (label, label)
            values = [_case_label_value(scope, bound, selector) for bound in bounds]
            if values[0] is None or values[1] is None:
                continue
            for value in range(values[0], values[1] + 1) if values[1] - values[0] < 4096 else ():
                if value in seen:
                    scope.report(label.pos, f"CASE label {value} already used at {seen[value]}")
                    break
                seen[value] = label.pos
        _check_block(scope, body, loop_depth)
    _check_block(scope, case.orelse, loop_depth)


def _case_label_value(scope: Scope, label: ast.Expr, selector: Type | None) -> int | None:
    scope.expect(label, selector)
    label_type = scope.type_of(label)
    if label_type is None:
        return None
    if integer_like(label_type) is None:
        scope.report(label.pos, f"CASE label must be an integer or enum, not {label_type.name}")
        return None
    return scope.constant_int(label)


def _check_for(scope: Scope, loop: ast.For, loop_depth: int) -> None:
    counter = _writable_target(scope, ast.NameRef(loop.variable, loop.pos))
    if counter is not None and not (isinstance(counter, ElementaryType) and counter.is_integer):
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
        binding = scope.lookup(target.name)
        if binding is None:
            scope.report(target.pos, f"'{target.name}' is not declared")
            return None
        if isinstance(binding, EnumValue | ProgramRef):
            scope.report(target.pos, f"cannot assign to '{target.name}'")
            return None
        if binding.constant:
            scope.report(target.pos, f"cannot assign to constant '{binding.name}'")
        elif binding.kind == "VAR_INPUT" and scope.pou.kind != "FUNCTION":
            # CODESYS, matiec and OSCAT write inputs inside the block; it is legal but
            # a trap (the caller's value is gone for the rest of the call): warn
            scope.warn(target.pos, f"assignment to input '{binding.name}' inside its block")
        return binding.type
    if isinstance(target, ast.MemberRef):
        base_type = scope.type_of(target.base)
        member = scope.member(target)
        if member is None:
            return None
        root = target.base
        while isinstance(root, ast.MemberRef | ast.IndexRef):
            root = root.base
        if isinstance(root, ast.NameRef):
            root_binding = scope.lookup(root.name)
            if isinstance(root_binding, Variable) and root_binding.kind == "STEP":
                scope.report(target.pos, f"step flag '{root.name}.{target.member}' is read-only")
                return member.type
        if isinstance(base_type, FbType) and member.kind not in WRITABLE_MEMBER_KINDS:
            scope.report(
                target.pos,
                f"'{target.member}' of '{base_type.name}' cannot be written from outside",
            )
        if isinstance(base_type, StructType) and not _is_lvalue(target.base):
            scope.report(target.pos, "cannot assign to a member of a value")
        return member.type
    if isinstance(target, ast.IndexRef | ast.BitRef):
        if isinstance(target.base, ast.NameRef | ast.MemberRef | ast.IndexRef | ast.BitRef):
            _writable_target(scope, target.base)
        return scope.type_of(target)
    scope.report(target.pos, "cannot assign to an expression")
    return None


def _is_lvalue(expr: ast.Expr) -> bool:
    return isinstance(expr, ast.NameRef | ast.MemberRef | ast.IndexRef)


def _check_call_statement(scope: Scope, call: ast.Call) -> None:
    binding = scope.lookup(call.name) if call.receiver is None else None
    if isinstance(binding, ProgramRef):
        callee = binding.pou
    elif isinstance(binding, Variable) and isinstance(binding.type, FbType):
        callee = scope.fb_symbols(binding.type)
    else:
        scope.type_of(call)  # a function called as a statement
        return
    for arg, param in scope.connect_arguments(callee, call):
        if param is None:
            if arg.value is not None:
                scope.type_of(arg.value)
            continue
        if arg.is_output and param.kind == "VAR_INPUT":
            scope.report(arg.pos, f"'{param.name}' of '{callee.name}' is an input, not an output")
            continue
        _check_fb_argument(scope, callee, arg, param)


def _check_fb_argument(scope: Scope, fb: PouSymbols, arg: ast.Argument, param: Variable) -> None:
    if arg.value is None:
        return
    if arg.is_output or param.kind == "VAR_OUTPUT":
        target_type = _writable_target(scope, arg.value)
        if target_type is not None and not assignable(target_type, param.type):
            scope.report(arg.value.pos, _mismatch(target_type, param.type))
        return
    if param.kind == "VAR_IN_OUT" and not _is_lvalue(arg.value):
        scope.report(arg.value.pos, f"in-out '{param.name}' needs a variable")
    value_type = scope.type_of(arg.value)
    if value_type is not None and not assignable(param.type, value_type):
        scope.report(arg.value.pos, _mismatch(param.type, value_type))


def _check_range(scope: Scope, target: Type, literal: ast.IntLiteral) -> None:
    integer = target.base if isinstance(target, EnumType) else target
    if not (isinstance(integer, ElementaryType) and integer.is_integer):
        return
    if not literal_fits(integer, literal):
        scope.report(literal.pos, f"{literal.value} is out of range for {integer.name}")


def _mismatch(target: Type, source: Type) -> str:
    return f"type mismatch: cannot assign {source.name} to {target.name}"
