"""Checks on the user programs of a resource (not on single POUs): the program list itself,
and the rule that global data has one writer.

A global written by two user programs would make the result depend on their order and
slicing; HIMA forbids it, and so do we: each global may be written by at most one program
(through any FB or function it calls).
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence

from backend.compiler import ast
from backend.compiler.ast import key
from backend.compiler.checks.data import resource_data
from backend.compiler.checks.sfc import bool_actions, step_times
from backend.compiler.codes import Code
from backend.compiler.diagnostics import Diagnostic
from backend.compiler.infer import Scope
from backend.compiler.resolve import PouSymbols, Resolved, Variable, visible
from backend.compiler.source import Pos
from backend.compiler.types import FbType
from runtime.contract.artifact import ProgramConfig, ResourceConfig

MAX_PROGRAMS = 32


def check_programs(
    resolved: Resolved,
    resource: ResourceConfig,
    programs: list[ProgramConfig],
    config_file: str,
    positions: dict[str, Pos] | None = None,
) -> list[Diagnostic]:
    """`positions`: where a CONFIGURATION in the sources declares each program; programs
    from padt.toml are reported at that file."""
    default = Pos(config_file, 1, 1)
    diagnostics: list[Diagnostic] = []
    seen_ids: dict[int, str] = {}
    for program in programs:
        where = (positions or {}).get(program.name, default)
        pou = resolved.pous.get(key(program.pou))
        if pou is None or pou.kind != "PROGRAM":
            message = f"user program '{program.name}': no PROGRAM '{program.pou}'"
            diagnostics.append(Diagnostic.at(where, Code.PROGRAM_POU, message))
        if not 1 <= program.program_id <= MAX_PROGRAMS:
            message = f"program ID {program.program_id} of '{program.name}' is not in 1..32"
            diagnostics.append(Diagnostic.at(where, Code.PROGRAM_ID_RANGE, message))
        if program.program_id in seen_ids:
            other = seen_ids[program.program_id]
            message = f"program ID {program.program_id} of '{program.name}' is used by '{other}'"
            diagnostics.append(Diagnostic.at(where, Code.PROGRAM_ID_TAKEN, message))
        seen_ids[program.program_id] = program.name
    if len(programs) > MAX_PROGRAMS:
        diagnostics.append(
            Diagnostic.at(
                default,
                Code.TOO_MANY_PROGRAMS,
                f"{len(programs)} user programs; at most {MAX_PROGRAMS}",
            )
        )
    sliced = sum(p.max_duration_us for p in programs)
    if sliced > resource.watchdog_ms * 1000:
        message = (
            f"the programs' Max. Duration for Each Cycle add up to {sliced} us, more than "
            f"the watchdog time ({resource.watchdog_ms} ms)"
        )
        diagnostics.append(Diagnostic.at(default, Code.SLICES_EXCEED_WATCHDOG, message))
    if len(programs) <= MAX_PROGRAMS:  # beyond, one writer per global is beside the point
        diagnostics.extend(_check_single_writer(resolved, programs))
    diagnostics.extend(resource_data(resolved, len(programs)))
    return diagnostics


def _check_single_writer(resolved: Resolved, programs: list[ProgramConfig]) -> list[Diagnostic]:
    writers: dict[str, list[str]] = {}
    first_write: dict[str, Pos] = {}
    for program in programs:
        if key(program.pou) not in resolved.pous:
            continue
        for name, pos in sorted(globals_written(resolved, key(program.pou)).items()):
            writers.setdefault(name, []).append(program.name)
            first_write.setdefault(name, pos)
    diagnostics = []
    for name, names in sorted(writers.items()):
        if len(names) > 1:
            spelled = resolved.globals_by_key[name].name
            message = (
                f"global '{spelled}' is written by the user programs {', '.join(names)}; "
                "global data must have one writer"
            )
            diagnostics.append(Diagnostic.at(first_write[name], Code.SECOND_WRITER, message))
    return diagnostics


def globals_written(resolved: Resolved, pou_key: str) -> dict[str, Pos]:
    """The globals (by key) a POU writes, itself or through the POUs it calls."""
    written: dict[str, Pos] = {}
    for pou in _reachable(resolved, pou_key):
        for target in _write_targets(resolved, pou):
            root = _root_name(target)
            variable = _global(resolved, pou, root.name) if root is not None else None
            if root is not None and variable is not None:
                written.setdefault(key(variable.name), root.pos)
    return written


def globals_read(resolved: Resolved, pou_key: str) -> list[str]:
    """The globals (by key, sorted) a POU or anything it calls names anywhere: what a user
    program must see as they were at the start of its program cycle."""
    found: set[str] = set()
    for pou in _reachable(resolved, pou_key):
        names = [n for s in _statements(pou) for n in _expressions_in(s)]
        if pou.pou.sfc is not None:
            names.extend(n for t in pou.pou.sfc.transitions for n in _nodes(t.condition))
            names.extend(n for d in step_times(pou.pou.sfc) for n in _nodes(d))
        names.extend(ast.NameRef(name, p) for name, p in _for_variables(pou))
        for node in names:
            if isinstance(node, ast.NameRef | ast.Call):  # a call may name a global FB
                variable = _global(resolved, pou, node.name)
                if variable is not None:
                    found.add(key(variable.name))
    return sorted(found)


def _reachable(resolved: Resolved, pou_key: str) -> Iterator[PouSymbols]:
    """A POU and every POU it may run (its FBs, the functions and programs it calls, its
    base block and the methods of each)."""
    visited: set[str] = set()
    pending = [pou_key]
    while pending:
        current = pending.pop()
        if current in visited or current not in resolved.pous:
            continue
        visited.add(current)
        pou = resolved.pous[current]
        yield pou
        pending.extend(sorted(_callees(resolved, pou)))
        if pou.base is not None:  # its body and methods may run on the instance
            pending.append(pou.base)
        for routine in pou.own_routines():  # the inherited ones come with their base
            yield routine
            pending.extend(sorted(_callees(resolved, routine)))


def _global(resolved: Resolved, pou: PouSymbols, name: str) -> Variable | None:
    """The global variable a name in a POU stands for (through VAR_EXTERNAL or not)."""
    variable = visible(resolved, pou, name)
    return variable if variable is not None and variable.kind == "VAR_GLOBAL" else None


def _for_variables(pou: PouSymbols) -> Iterator[tuple[str, Pos]]:
    for statement in _statements(pou):
        if isinstance(statement, ast.For):
            yield statement.variable, statement.pos


def _statements(pou: PouSymbols) -> Iterator[ast.Statement]:
    bodies = [pou.pou.body]
    if pou.pou.sfc is not None:
        bodies.extend(action.body for action in pou.pou.sfc.actions)
    stack = [s for body in bodies for s in body]
    while stack:
        statement = stack.pop()
        yield statement
        match statement:
            case ast.If(branches=branches, orelse=orelse):
                stack.extend(s for _, body in branches for s in body)
                stack.extend(orelse)
            case ast.Case(branches=branches, orelse=orelse):
                stack.extend(s for _, body in branches for s in body)
                stack.extend(orelse)
            case ast.While(body=body) | ast.Repeat(body=body) | ast.For(body=body):
                stack.extend(body)


def _write_targets(resolved: Resolved, pou: PouSymbols) -> Iterator[ast.Expr]:
    if pou.pou.sfc is not None:
        yield from bool_actions(pou.pou.sfc)
    scope = Scope(resolved, pou)
    for statement in _statements(pou):
        for call in _calls_in(statement):  # a call in an expression too: `y := f(g)`
            yield from _in_out_arguments(resolved, scope, call)
        match statement:
            case ast.Assign(target=target):
                yield target
            case ast.For(variable=name, pos=pos):
                yield ast.NameRef(name, pos)
            case ast.CallStatement(call=call):
                for arg in call.args:
                    if arg.is_output and arg.value is not None:
                        yield arg.value
                # calling an FB instance changes it
                yield call.instance or call.receiver or ast.NameRef(call.name, call.pos)


def _in_out_arguments(resolved: Resolved, scope: Scope, call: ast.Call) -> Iterator[ast.Expr]:
    """What a call of an FB instance or a function binds to its VAR_IN_OUT parameters, by
    name or by position: the callee may write it."""
    called = scope.expression_instance(call)
    if called is not None:  # `fbs[1](...)`, `s.fb(...)`
        callee = resolved.pous.get(key(called[1].name))
    elif call.receiver is None and call.instance is None:
        variable = scope.variable(call.name)
        if variable is None:  # a function
            callee = resolved.pous.get(key(call.name))
        elif isinstance(variable.type, FbType):
            callee = resolved.pous.get(key(variable.type.name))
        else:
            callee = None
    else:  # a method or an action: not followed here
        callee = None
    if callee is None:
        return
    parameters = callee.parameters
    for index, arg in enumerate(call.args):
        if arg.value is None or arg.is_output:
            continue
        if arg.name is not None:
            parameter = callee.by_key.get(key(arg.name))
        else:  # positional arguments come first, in the order of the parameters
            parameter = parameters[index] if index < len(parameters) else None
        if parameter is not None and parameter.kind == "VAR_IN_OUT":
            yield arg.value


def _root_name(expr: ast.Expr) -> ast.NameRef | None:
    while isinstance(expr, ast.MemberRef | ast.IndexRef | ast.BitRef):
        expr = expr.base
    return expr if isinstance(expr, ast.NameRef) else None


def _callees(resolved: Resolved, pou: PouSymbols) -> set[str]:
    """POUs this one may run: its FB instances' types, every function or program named
    in a call (or whose method or action it calls), and the type of every instance a call
    gives by an expression (`fbs[i]()`, `s.fb()`)."""
    found = {key(v.type.name) for v in pou.variables if isinstance(v.type, FbType)}
    scope = Scope(resolved, pou)
    for statement in _statements(pou):
        for call in _calls_in(statement):
            # `b()` of an instance named like a POU `B` calls the instance, not `B`
            if key(call.name) in resolved.pous and not _names_variable(scope, call):
                found.add(key(call.name))
            called = scope.expression_instance(call)
            if called is not None:
                found.add(key(called[1].name))
            receiver = call.receiver
            if isinstance(receiver, ast.NameRef) and key(receiver.name) in resolved.pous:
                found.add(key(receiver.name))  # `Prog.Method()`, `Prog.Action()`
    return found


def _names_variable(scope: Scope, call: ast.Call) -> bool:
    return call.receiver is None and call.instance is None and scope.variable(call.name) is not None


def _expressions_in(statement: ast.Statement) -> Iterator[ast.Initializer]:
    """Every node of a statement's own expressions (nested statements are walked apart)."""
    match statement:
        case ast.Assign(target=target, value=value):
            roots: Sequence[ast.Initializer] = [target, value]
        case ast.CallStatement(call=call):
            roots = [call]
        case ast.ExprStatement(expr=expr):
            roots = [expr]
        case ast.If(branches=branches):
            roots = [condition for condition, _ in branches]
        case ast.Case(selector=selector):
            roots = [selector]
        case ast.While(condition=condition) | ast.Repeat(until=condition):
            roots = [condition]
        case ast.For(start=start, stop=stop, step=step):
            roots = [start, stop, *([step] if step is not None else [])]
        case _:
            roots = []
    for root in roots:
        yield from _nodes(root)


def _calls_in(statement: ast.Statement) -> Iterator[ast.Call]:
    return (node for node in _expressions_in(statement) if isinstance(node, ast.Call))


def _nodes(expr: ast.Initializer) -> Iterator[ast.Initializer]:
    yield expr
    match expr:
        case ast.Call(args=args, instance=instance):
            if instance is not None:
                yield from _nodes(instance)
            for arg in args:
                if arg.value is not None:
                    yield from _nodes(arg.value)
        case ast.Unary(operand=operand):
            yield from _nodes(operand)
        case ast.Binary(left=left, right=right):
            yield from _nodes(left)
            yield from _nodes(right)
        case ast.MemberRef(base=base) | ast.BitRef(base=base) | ast.Deref(base=base):
            yield from _nodes(base)
        case ast.IndexRef(base=base, indices=indices):
            yield from _nodes(base)
            for index in indices:
                yield from _nodes(index)
        case ast.ArrayInit(items=items):
            for _, value in items:
                yield from _nodes(value)
        case ast.StructInit(members=members):
            for _, value in members:
                yield from _nodes(value)
