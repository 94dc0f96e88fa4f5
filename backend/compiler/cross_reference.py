"""The cross-reference of a project: every variable of the user's POUs and every global,
with where it is declared, read and written (file:line:col).

Built on the resolved AST, so a name means what the compiler takes it for: a VAR_EXTERNAL
is the global it names, a local hides a global of the same name, `SYS.<NAME>` is a system
variable. A member, an element or a bit of a variable (`timer.Q`, `points[i].x`) counts as
a use of the variable; the indices are read. Calling a function block instance writes it
(its state changes), as the compiler's one-writer rule counts it; an output (`Q => v`) and
an in-out argument write the variable connected to it.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

from backend.compiler import ast
from backend.compiler.ast import key
from backend.compiler.checks.sfc import bool_actions, step_times
from backend.compiler.infer import Scope
from backend.compiler.pipeline import parse_project
from backend.compiler.resolve import PouSymbols, Resolved, Variable, resolve
from backend.compiler.source import Pos, SourceFile
from backend.compiler.types import FbType
from runtime.contract.system_variables import NAMESPACE

DECLARED, READ, WRITTEN = "declared", "read", "written"
GLOBAL_SCOPE = ""  # the scope of globals and system variables


@dataclass(frozen=True)
class Use:
    how: str  # declared | read | written
    pos: Pos
    pou: str  # the POU the use is in ("" for a global's declaration outside any POU)

    def sort_key(self) -> tuple[str, int, int, str]:
        return (self.pos.file, self.pos.line, self.pos.col, self.how)


@dataclass(frozen=True)
class VariableUses:
    scope: str  # GLOBAL_SCOPE, or the POU a local variable belongs to
    name: str  # as declared (`SYS.<NAME>` for a system variable)
    kind: str  # VAR_GLOBAL, VAR, VAR_INPUT, ..., STEP, RETURN, SYSTEM
    type: str
    uses: tuple[Use, ...]  # in file, line, column order

    @property
    def qualified(self) -> str:
        """`TankControl.pump` for a local, `level` for a global."""
        return f"{self.scope}.{self.name}" if self.scope else self.name

    def where(self, how: str) -> tuple[Use, ...]:
        return tuple(use for use in self.uses if use.how == how)


def cross_reference(sources: list[SourceFile]) -> list[VariableUses]:
    """The cross-reference of a project's sources (which must compile): globals first,
    then each POU's variables, each group by name."""
    units, _, user_pous = parse_project(sources)
    return cross_reference_of(units, user_pous)


def cross_reference_of(units: list[ast.SourceUnit], user_pous: set[str]) -> list[VariableUses]:
    """The same of a project already parsed (`parse_project`)."""
    resolved = resolve(units)
    table = _Table(resolved)
    for variable in resolved.globals:
        if not variable.pos.file.startswith("stdlib/"):
            table.add("", variable, DECLARED, variable.pos)
    for pou_key in sorted(user_pous):
        pou = resolved.pous.get(pou_key)
        if pou is not None:
            _walk_pou(table, pou)
    return table.entries()


class _Table:
    """The uses found so far, by variable."""

    def __init__(self, resolved: Resolved) -> None:
        self.resolved = resolved
        self.found: dict[tuple[str, str], tuple[Variable, list[Use]]] = {}

    def add(self, pou: str, variable: Variable, how: str, pos: Pos) -> None:
        """A use of `variable` in POU `pou` ("": a global's declaration)."""
        scope = GLOBAL_SCOPE if variable.kind in ("VAR_GLOBAL", "SYSTEM") else pou
        name = f"{NAMESPACE}.{variable.name}" if variable.kind == "SYSTEM" else variable.name
        entry = self.found.setdefault((key(scope), key(name)), (variable, []))
        entry[1].append(Use(how, pos, pou))

    def entries(self) -> list[VariableUses]:
        result = []
        for (scope_key, _), (variable, uses) in sorted(self.found.items()):
            scope = GLOBAL_SCOPE if not scope_key else self._pou_name(scope_key)
            name = variable.name
            if variable.kind == "SYSTEM":
                name = f"{NAMESPACE}.{variable.name}"
            result.append(
                VariableUses(
                    scope,
                    name,
                    variable.kind,
                    variable.type.name,
                    tuple(sorted(set(uses), key=Use.sort_key)),
                )
            )
        return result

    def _pou_name(self, pou_key: str) -> str:
        return self.resolved.pous[pou_key].name


def _walk_pou(table: _Table, pou: PouSymbols) -> None:
    walker = _Walker(table, pou)
    result = pou.by_key.get(key(pou.name))
    if result is not None and result.kind == "RETURN":  # a function's result variable
        table.add(pou.name, result, DECLARED, pou.pou.pos)
    for block in pou.pou.var_blocks:
        for decl in block.decls:
            variable = pou.by_key.get(key(decl.name))
            if variable is not None:
                table.add(pou.name, variable, DECLARED, decl.pos)
            if decl.init is not None:
                walker.expr(decl.init, write=False)
    sfc = pou.pou.sfc
    if sfc is not None:
        for step in sfc.steps:
            variable = pou.by_key.get(key(step.name))
            if variable is not None and variable.kind == "STEP":
                table.add(pou.name, variable, DECLARED, step.pos)
        for transition in sfc.transitions:
            walker.expr(transition.condition, write=False)
        for duration in step_times(sfc):
            walker.expr(duration, write=False)
        for target in bool_actions(sfc):
            walker.expr(target, write=True)
        for action in sfc.actions:
            walker.statements(action.body)
    walker.statements(pou.pou.body)
    for routine in pou.own_routines():  # a method's uses are its block's
        _Walker(table, routine).statements(routine.pou.body)


class _Walker:
    """Records every variable a POU's statements and expressions name, read or written."""

    def __init__(self, table: _Table, pou: PouSymbols) -> None:
        self.table = table
        self.pou = pou

    def variable(self, name: str) -> Variable | None:
        """The variable a name means; in a method its block's (its own are temporaries)."""
        pou = self.pou
        if pou.outer is not None:
            if key(name) in pou.by_key:
                return None
            pou = pou.outer
        return pou.by_key.get(key(name)) or self.table.resolved.globals_by_key.get(key(name))

    @property
    def owner(self) -> str:
        return self.pou.outer.name if self.pou.outer is not None else self.pou.name

    def name(self, name: str, pos: Pos, how: str) -> None:
        variable = self.variable(name)
        if variable is not None:
            self.table.add(self.owner, variable, how, pos)

    def statements(self, body: tuple[ast.Statement, ...]) -> None:
        for statement in body:
            self.statement(statement)

    def statement(self, statement: ast.Statement) -> None:
        match statement:
            case ast.Assign(target=target, value=value):
                self.expr(value, write=False)
                self.expr(target, write=True)
            case ast.CallStatement(call=call):
                self.call(call)
            case ast.ExprStatement(expr=expr):
                self.expr(expr, write=False)
            case ast.If(branches=branches, orelse=orelse):
                for condition, body in branches:
                    self.expr(condition, write=False)
                    self.statements(body)
                self.statements(orelse)
            case ast.Case(selector=selector, branches=branches, orelse=orelse):
                self.expr(selector, write=False)
                for labels, body in branches:
                    for label in labels:
                        parts = (
                            [label.low, label.high] if isinstance(label, ast.CaseRange) else [label]
                        )
                        for part in parts:
                            self.expr(part, write=False)
                    self.statements(body)
                self.statements(orelse)
            case ast.While(condition=condition, body=body):
                self.expr(condition, write=False)
                self.statements(body)
            case ast.Repeat(body=body, until=until):
                self.statements(body)
                self.expr(until, write=False)
            case ast.For(variable=name, start=start, stop=stop, step=step, body=body, pos=pos):
                self.name(name, pos, WRITTEN)
                for bound in (start, stop, step):
                    if bound is not None:
                        self.expr(bound, write=False)
                self.statements(body)

    def call(self, call: ast.Call) -> None:
        if call.receiver is not None:
            self.expr(call.receiver, write=True)
        if call.instance is not None:  # `fbs[i](...)` changes fbs, reads i
            self.expr(call.instance, write=True)
        instance = self.variable(call.name) if call.receiver is None else None
        if instance is not None:
            self.name(call.name, call.pos, WRITTEN)
        in_outs = set(self._in_out_parameters(call, instance))
        for arg in call.args:
            if arg.value is None:
                continue
            if arg.is_output:
                self.expr(arg.value, write=True)
            elif arg.name is not None and key(arg.name) in in_outs:
                self.expr(arg.value, write=False)
                self.expr(arg.value, write=True)
            else:
                self.expr(arg.value, write=False)

    def _in_out_parameters(self, call: ast.Call, instance: Variable | None) -> Iterator[str]:
        if instance is not None and isinstance(instance.type, FbType):
            callee = self.table.resolved.pous.get(key(instance.type.name))
        elif call.instance is not None or call.receiver is not None:  # `fbs[i](...)`, `s.fb()`
            called = Scope(self.table.resolved, self.pou).expression_instance(call)
            callee = self.table.resolved.pous.get(key(called[1].name)) if called else None
        else:
            callee = self.table.resolved.pous.get(key(call.name))
        if callee is not None:
            yield from (key(v.name) for v in callee.parameters if v.kind == "VAR_IN_OUT")

    def expr(self, node: ast.Initializer, *, write: bool) -> None:
        how = WRITTEN if write else READ
        match node:
            case ast.NameRef(name=name, pos=pos):
                self.name(name, pos, how)
            case ast.MemberRef(base=ast.NameRef(name=base), member=member, pos=pos) if (
                key(base) == NAMESPACE and self.variable(base) is None
            ):
                system = self.table.resolved.system.get(key(member))
                if system is not None:
                    self.table.add(self.owner, system, how, pos)
            case ast.MemberRef(base=base) | ast.BitRef(base=base) | ast.Deref(base=base):
                self.expr(base, write=write)
            case ast.IndexRef(base=base, indices=indices):
                self.expr(base, write=write)
                for index in indices:
                    self.expr(index, write=False)
            case ast.Unary(operand=operand):
                self.expr(operand, write=False)
            case ast.Binary(left=left, right=right):
                self.expr(left, write=False)
                self.expr(right, write=False)
            case ast.Call():
                self.call(node)
            case ast.ArrayInit(items=items):
                for count, value in items:
                    if count is not None:
                        self.expr(count, write=False)
                    self.expr(value, write=False)
            case ast.StructInit(members=members):
                for _, value in members:
                    self.expr(value, write=False)
