"""What generated code may contain: the check of every unit's typed form from outside
before the runtime prints any Python of it (python_text.py).

An artifact comes from outside (a download, a reload, a recording, a backup), and its CRC
proves only that it was not damaged, not who wrote it. `form_json.decode_unit` takes only
nodes of the form, each field of its type and every printed name an identifier; but a form
of well-made nodes can still describe code no compiler writes. The generated code runs with
restricted builtins, and restricted builtins alone hold nothing: any attribute such as
`__globals__` of any function leads back to the full interpreter. So the form must be one
the compiler (`backend/compiler/generate.py`) could have built, and that is what this module
checks, node by node, as Python will read what the printer writes of it:

- the unit is of its kind (a FUNCTION a function `FN_X`, a structure a class or an alias of
  `_SfcStep`, anything else a class `POU_X`, `STRUCT_X`, `GLOBALS`) under the unit's class
  name; a class has variable names for slots, names for kinds, and only the methods the
  compiler writes (`__call__`, methods `M__X`, property accessors `GET__X` / `SET__X`,
  actions `_action_X`, each taking its instance `s`; inherited ones from a class);
- every name read from the namespace is one of the runtime's (names.py: intrinsics called,
  never passed on; builtins called with positions alone) or a generated unit's, only
  called; the system variables, the globals and the programs only with their own
  attributes (writing only the writable system variables), `_math` only as
  `_safe_math(_math.f, x)`, `_tick` only as `t = _tick`, `t()` and `_tick is None`;
- a function reads only locals it binds (Python would read any other from the namespace:
  `__builtins__`, an intrinsic as a value) and binds none of the names it reads from the
  namespace; the values of parameters, evaluated where the unit is defined, bind nothing;
- no attribute with a leading `__` but in the shapes the compiler writes (`t.__call__()`,
  `POU_BASE.__call__(s)` for SUPER^(), `_deref(t).__class__.__name__` and
  `_deref(t).__class__.__dict__.get('KIND__', ())` for `?=`); methods are called, never
  read as values; `_init` and `_ref` take variable names only;
- a shift left is by a constant count of at most 64 or by `min(n, c)` of such a constant.

Anything else is a `FormRefused` naming the unit, where in its form and what is not
allowed: a runtime answers the load with a refusal and keeps what it runs.
`docs/artifact.md` lists the rules.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field, fields, is_dataclass
from typing import NoReturn

from runtime.contract.code.form_json import FormRefused
from runtime.contract.code.names import (
    BUILTINS,
    CALLED_INTRINSICS,
    CLASS_NAME,
    FUNCTION_NAME,
    IDENTIFIER,
    MATH_FUNCTIONS,
    METHOD_NAME,
    SYSTEM_ATTRS,
    UNIT_NAME,
    WRITABLE_SYSTEM_ATTRS,
    is_data_attr,
    is_local_name,
    is_plain_name,
    is_runtime_name,
)
from runtime.contract.code.statements import (
    Assign,
    Break,
    Continue,
    Evaluate,
    ForEach,
    If,
    Pass,
    Return,
    Stmt,
    While,
)
from runtime.contract.code.typed_form import (
    Assigned,
    Binary,
    Call,
    Chain,
    Choice,
    Const,
    Expr,
    Index,
    Logic,
    Member,
    Members,
    Named,
    Repeated,
    Sequence,
    Slice,
    This,
    Unary,
    Var,
    Wrap,
)
from runtime.contract.code.units import Alias, Class, Function, Inherited, Unit


@dataclass(frozen=True)
class UnitKind:
    """A kind of unit of an artifact: the names the compiler gives such units, their forms."""

    names: re.Pattern[str]
    forms: tuple[type, ...]


UNIT_KINDS = {
    "PROGRAM": UnitKind(CLASS_NAME, (Class,)),
    "FUNCTION_BLOCK": UnitKind(CLASS_NAME, (Class,)),
    "FUNCTION": UnitKind(FUNCTION_NAME, (Function,)),
    "STRUCT": UnitKind(CLASS_NAME, (Class, Alias)),  # the SFC step structure: an alias
    "GLOBALS": UnitKind(CLASS_NAME, (Class,)),
}
# the largest count of a shift left: the widest integer type's bits
MAX_SHIFT = 64
# the objects of the namespace a variable lives in, by `Var.where`
_ROOTS = {"globals": "_G", "system": "_SYS", "programs": "_P"}
_ROOT_NAMES = frozenset(_ROOTS.values())


def check_unit(unit: Unit, kind: str, class_name: str, what: str) -> None:
    """Nothing when `unit` is a form the compiler builds for a unit of `kind` named
    `class_name`, else FormRefused naming `what` (the form of a unit), where in the form
    and what is not allowed."""
    try:
        _Checker().unit(unit, kind, class_name)
    except _Refusal as refusal:
        where = _path(unit, refusal.node) + refusal.step
        raise FormRefused(f"{what}: {where}: {refusal.what} is not allowed") from None
    except RecursionError:  # decoded within the limit, so only in a deep stack
        raise FormRefused(f"{what}: the form is nested too deep to check") from None


class _Refusal(Exception):
    """What is not allowed, at which node of the form (and which `step` below it: a field
    that holds a name rather than a node)."""

    def __init__(self, node: object, what: str, step: str = "") -> None:
        super().__init__(what)
        self.node, self.what, self.step = node, what, step


def _refuse(node: object, what: str, step: str = "") -> NoReturn:
    raise _Refusal(node, what, step)


@dataclass
class _Scope:
    """The names of one function (or of the module or class body, for default values),
    resolved at its end as Python resolves them: a name the function binds anywhere is its
    local, any other the namespace's."""

    method: bool = False  # a method of a class: `s` is its instance
    defaults: bool = False  # default values, evaluated where the unit is defined
    bound: set[str] = field(default_factory=set)
    # bound otherwise than by `t = _tick` (a parameter, any other value)
    not_tick: set[str] = field(default_factory=set)
    # uses that hold only for a local, only for the namespace's name, only for a tick: by
    # name, the node where first met
    as_local: dict[str, object] = field(default_factory=dict)
    as_global: dict[str, object] = field(default_factory=dict)
    as_tick: dict[str, object] = field(default_factory=dict)
    # within `[... for _ in range(n)]`, whose `_` is the comprehension's own
    comprehensions: int = 0

    def bind(self, name: str, node: object, step: str = "", tick: bool = False) -> None:
        if self.defaults:  # would bind a name of the namespace or the class
            _refuse(node, f"binding {name!r} where the unit is defined", step)
        if not is_local_name(name):
            _refuse(node, f"the local name {name!r}", step)
        self.bound.add(name)
        if not tick:
            self.not_tick.add(name)

    def local(self, name: str, node: object) -> None:
        if name != "_" or not self.comprehensions:
            self.as_local.setdefault(name, node)

    def runtime(self, name: str, node: object) -> None:
        self.as_global.setdefault(name, node)

    def resolve(self) -> None:
        for name, node in self.as_global.items():
            if name in self.bound:
                _refuse(node, f"{name} as a local")
        for name, node in self.as_local.items():
            if name not in self.bound:
                _refuse(node, _value_use(name))
        for name, node in self.as_tick.items():
            if name not in self.bound or name in self.not_tick:
                _refuse(node, f"a call of {name!r}")


class _Checker:
    # ---- the unit
    def unit(self, unit: Unit, kind: str, class_name: str) -> None:
        unit_kind = UNIT_KINDS.get(kind)
        if unit_kind is None:
            _refuse(unit, f"a unit of kind {kind!r}")
        if not isinstance(unit, unit_kind.forms):
            _refuse(unit, f"{_a(unit)} for a {kind}")
        if unit_kind.names.match(unit.name) is None:
            _refuse(unit, f"{_a(unit)} named {unit.name!r}", ".name")
        if unit.name != class_name:  # the name the runtime finds the unit's class by
            _refuse(unit, f"the name {unit.name!r} for the unit {class_name!r}", ".name")
        match unit:
            case Alias(target=target):
                if target != "_SfcStep":  # SFC steps are the runtime's own class
                    _refuse(unit, f"an alias of {target!r}", ".target")
            case Function(method=method):
                if method:
                    _refuse(unit, "a function taking an instance outside a class", ".method")
                self.function(unit)
            case Class():
                self.class_(unit)

    def class_(self, unit: Class) -> None:
        for index, kind in enumerate(unit.kinds):
            if IDENTIFIER.match(kind) is None:
                _refuse(unit, f"the KIND__ entry {kind!r}", f".kinds[{index}]")
        init = _Scope(method=True)  # `__init__(s)`, which sets the slots
        init.bind("s", unit)
        for slot in unit.slots:
            if not is_data_attr(slot.name):
                _refuse(slot, f"the slot {slot.name!r}", ".name")
            self.expr(slot.initial, init)
        init.resolve()
        for function in unit.functions:
            if isinstance(function, Inherited):
                self.inherited(function)
            else:
                self.method(function)

    def inherited(self, function: Inherited) -> None:
        """`M__X = POU_BASE.M__X`: the declaring class's function."""
        if METHOD_NAME.match(function.name) is None:
            _refuse(function, f"inheriting {function.name!r}", ".name")
        if CLASS_NAME.match(function.owner) is None:
            _refuse(function, f"inheriting from {function.owner!r}", ".owner")

    def method(self, function: Function) -> None:
        name = function.name
        if name != "__call__" and METHOD_NAME.match(name) is None:
            _refuse(function, f"a method named {name!r}", ".name")
        if not function.method:
            _refuse(function, f"the method {name} without its instance `s` first", ".method")
        if name == "__call__" and function.params:
            _refuse(function, "__call__ with parameters", ".params")
        self.function(function)

    def function(self, function: Function) -> None:
        scope = _Scope(method=function.method)
        if function.method:
            scope.bind("s", function)
        defaults = _Scope(defaults=True)  # evaluated where the function is defined
        for param in function.params:
            if param.name in scope.bound:
                _refuse(param, f"a second parameter {param.name!r}", ".name")
            scope.bind(param.name, param, ".name")
            self.expr(param.default, defaults)
        defaults.resolve()
        self.block(function.body, scope, loop=False)
        scope.resolve()

    # ---- statements
    def block(self, statements: tuple[Stmt, ...], scope: _Scope, loop: bool) -> None:
        for statement in statements:
            self.statement(statement, scope, loop)

    def statement(self, node: Stmt, scope: _Scope, loop: bool) -> None:
        match node:
            case Assign(target=target, value=value, augmented=augmented):
                if _is_tick_read(node):  # `t = _tick`, read once before a loop
                    assert isinstance(target, Var)
                    scope.runtime("_tick", value)
                    scope.bind(target.name, target, ".name", tick=True)
                    return
                self.target(target, scope, whole=augmented is None)
                self.expr(value, scope)
            case Evaluate(value=value):
                self.expr(value, scope)
            case If(test=test, body=body, orelse=orelse, elifs=elifs):
                self.expr(test, scope)
                self.block(body, scope, loop)
                for branch in elifs:
                    self.expr(branch.test, scope)
                    self.block(branch.body, scope, loop)
                self.block(orelse, scope, loop)
            case While(test=test, body=body):
                self.expr(test, scope)
                self.block(body, scope, loop=True)
            case ForEach(name=name, numbers=numbers, body=body, orelse=orelse):
                scope.bind(name, node, ".name")
                self.expr(numbers, scope)
                self.block(body, scope, loop=True)
                self.block(orelse, scope, loop)
            case Break() | Continue():
                if not loop:
                    _refuse(node, f"{_a(node)} outside a loop")
            case Return(value=value):
                if value is not None:
                    self.expr(value, scope)
            case Pass():
                pass
            case _:  # a kind of statement this check has not decided on
                _refuse(node, _a(node))

    def target(self, node: Expr, scope: _Scope, whole: bool) -> None:
        """What an assignment writes (`whole`: not an augmented one): a local, a variable
        of an object, an item of a list, a tuple of them."""
        match node:
            case Var(name=name, where="local"):
                scope.bind(name, node, ".name")
            case Var(name=name, where="instance"):
                if not is_data_attr(name):
                    _refuse(node, f"an assignment to the attribute {name!r}")
                scope.local("s", node)
            case Var(name=name, where=where):
                self.root_attribute(_ROOTS[where], name, node, scope, write=True)
            case Member(base=Named(name=root), name=name) if root in _ROOT_NAMES:
                self.root_attribute(root, name, node, scope, write=True)
            case Member(base=base, name=name):
                if not is_data_attr(name):
                    _refuse(node, f"an assignment to the attribute {name!r}")
                self.expr(base, scope)
            case Index(base=base, offset=offset):
                self.expr(base, scope)
                self.expr(offset, scope)
            case Slice(value=value):
                self.expr(value, scope)
            case Sequence(items=items, as_tuple=True) if whole:
                for item in items:
                    self.target(item, scope, whole)
            case _:
                _refuse(node, f"an assignment to {_a(node)}")

    # ---- expressions
    def expr(self, node: Expr, scope: _Scope) -> None:
        match node:
            case Var(name=name, where=where):
                if where == "local":
                    scope.local(name, node)
                elif where == "instance":
                    if not is_data_attr(name):
                        _refuse(node, f"the attribute {name!r}")
                    scope.local("s", node)
                else:
                    self.root_attribute(_ROOTS[where], name, node, scope, write=False)
            case Const(value=value):
                if type(value) is float and not math.isfinite(value):
                    scope.runtime("float", node)  # printed `float('inf')`
            case Member():
                self.member(node, scope)
            case Call():
                self.call(node, scope)
            case Wrap(value=value) | Unary(operand=value) | Slice(value=value):
                self.expr(value, scope)
            case Binary(left=left, right=right):
                if _is_tick_test(node):  # `_tick is None`: whether a slice is metered
                    scope.runtime("_tick", left)
                    return
                if node.op == "<<" and not _is_shift_count(right):
                    # Python makes the whole shifted number before anything masks it:
                    # `1 << 2**33` is a GiB in one operation no watchdog interrupts
                    _refuse(node, f"a shift left by more than {MAX_SHIFT} or by an unbounded count")
                self.expr(left, scope)
                self.expr(right, scope)
            case Index(base=base, offset=offset):
                self.expr(base, scope)
                self.expr(offset, scope)
            case Chain(values=values) | Logic(values=values) | Sequence(items=values):
                for value in values:
                    self.expr(value, scope)
            case Choice(test=test, then=then, orelse=orelse):
                self.expr(test, scope)
                self.expr(then, scope)
                self.expr(orelse, scope)
            case Assigned(name=name, value=value):
                scope.bind(name, node, ".name")
                self.expr(value, scope)
            case This():
                scope.local("s", node)
            case Repeated(item=item, each_new=each_new):
                if not each_new:
                    self.expr(item, scope)
                    return
                scope.runtime("range", node)  # `[item for _ in range(n)]`
                scope.comprehensions += 1
                self.expr(item, scope)
                scope.comprehensions -= 1
            case Named(name=name):
                _refuse(node, _value_use(name))
            case Members():
                _refuse(node, "a dict other than the members of _init")
            case _:  # a kind of node this check has not decided on
                _refuse(node, _a(node))

    def root_attribute(self, root: str, name: str, node: Expr, scope: _Scope, write: bool) -> None:
        """`_G.x`, `_SYS.X`, `_P.POU_X`: a variable of the globals, a system variable, a
        program instance (read only); written, `_SYS.X` only where X is writable."""
        scope.runtime(root, node)
        if root == "_G":
            allowed = is_data_attr(name)
        elif root == "_SYS":
            allowed = name in (WRITABLE_SYSTEM_ATTRS if write else SYSTEM_ATTRS)
        else:
            allowed = not write and CLASS_NAME.match(name) is not None
        if not allowed:
            _refuse(node, f"{'an assignment to' if write else 'the attribute'} {root}.{name}")

    def member(self, node: Member, scope: _Scope) -> None:
        """A member read as a value."""
        base, name = node.base, node.name
        if type(base) is Named and base.name in _ROOT_NAMES:
            self.root_attribute(base.name, name, node, scope, write=False)
        elif name == "__name__" and self.class_of_deref(base, scope):
            return  # `_deref(t).__class__.__name__` (`?=`): the name of an instance's class
        elif not is_data_attr(name):
            _refuse(node, f"the attribute {name!r}")
        else:
            self.expr(base, scope)

    def class_of_deref(self, node: Expr, scope: _Scope) -> bool:
        """`_deref(t).__class__`, t a local (checked here when it is)."""
        match node:
            case Member(
                base=Call(callee="_deref", args=(Var(where="local") as held,), keywords=()) as call,
                name="__class__",
            ):  # fmt: skip
                scope.runtime("_deref", call)
                scope.local(held.name, held)
                return True
        return False

    def kind_lookup(self, node: Call, scope: _Scope) -> bool:
        """`_deref(t).__class__.__dict__.get('KIND__', ())`: the kinds an instance's class
        conforms to (t a local, checked here when it is)."""
        match node:
            case Call(
                callee=Member(base=Member(base=kind, name="__dict__")),
                args=(Const(value="KIND__"), Sequence(items=(), as_tuple=True)),
                keywords=(),
            ):
                return self.class_of_deref(kind, scope)
        return False

    # ---- calls
    def call(self, node: Call, scope: _Scope) -> None:
        for index, (keyword, _) in enumerate(node.keywords):
            if not is_plain_name(keyword):
                _refuse(node, f"the keyword {keyword!r}", f".keywords[{index}]")
        if isinstance(node.callee, str):
            self.call_name(node, node.callee, scope)
        else:
            self.call_value(node, node.callee, scope)

    def arguments(self, node: Call, scope: _Scope) -> None:
        for argument in node.args:
            self.expr(argument, scope)
        for _, value in node.keywords:
            self.expr(value, scope)

    def call_name(self, node: Call, name: str, scope: _Scope) -> None:
        """A call of a name of the namespace: the runtime's function, a builtin, a unit."""
        unit = UNIT_NAME.match(name) is not None
        if not (unit or name in CALLED_INTRINSICS or name in BUILTINS):
            _refuse(node, f"a call of {name!r}", ".callee")
        scope.runtime(name, node)
        if node.keywords and not unit:
            # the runtime's functions take positions only (`max(..., key=f)` would call f)
            _refuse(node, f"{name}() with keywords", ".keywords")
        if name in ("max", "min") and len(node.args) < 2:
            # of one value, max iterates over it: over `range(10**18)` in one call of C,
            # which holds the interpreter and which no watchdog interrupts
            _refuse(node, f"{name}() of fewer than two values", ".args")
        if name == "_safe_math":
            self.safe_math(node, scope)
        elif name == "_init":
            self.structure_init(node, scope)
        elif name == "_ref":
            self.reference(node, scope)
        else:
            self.arguments(node, scope)

    def safe_math(self, node: Call, scope: _Scope) -> None:
        """`_safe_math(_math.sqrt, x)`: the one place a function is passed as a value."""
        match node.args:
            case (Named(name=function) as named, value) if (
                function.startswith("_math.") and function[6:] in MATH_FUNCTIONS
            ):
                scope.runtime("_math", named)
                self.expr(value, scope)
            case _:
                _refuse(node, "_safe_math of anything but a function of _math")

    def structure_init(self, node: Call, scope: _Scope) -> None:
        """`_init(STRUCT_X(), {'a': 1})`: members set by name, each a variable's."""
        match node.args:
            case (target, Members(items=items) as members):
                self.expr(target, scope)
                for index, (name, value) in enumerate(items):
                    if not is_data_attr(name):
                        what = f"_init of the member {name!r}"
                        _refuse(members, what, f".items[{index}]")
                    self.expr(value, scope)
            case _:
                _refuse(node, "_init of anything but an object and the members to set")

    def reference(self, node: Call, scope: _Scope) -> None:
        """`_ref(root, ('a', offset), label, whole)`: REF(x); the steps are variable names
        or list offsets (the runtime refuses any other step when the code runs)."""
        match node.args:
            case (root, Sequence(items=steps, as_tuple=True), *rest) if len(rest) <= 2:
                if type(root) is Named and root.name == "_G":  # a global's root
                    scope.runtime("_G", root)
                else:
                    self.expr(root, scope)
                for step in steps:
                    if type(step) is Const and type(step.value) is str:
                        if not is_data_attr(step.value):
                            _refuse(step, f"a reference through {step.value!r}")
                    else:
                        self.expr(step, scope)
                for other in rest:
                    self.expr(other, scope)
            case _:
                _refuse(node, "_ref of anything but a root, a tuple of steps and a label")

    def call_value(self, node: Call, callee: Expr, scope: _Scope) -> None:
        """A call of a value: the tick, a block instance, a method, an action's control."""
        match callee:
            case Var(name=name, where="local") if not node.args and not node.keywords:
                scope.as_tick.setdefault(name, callee)  # `t()`: the tick
            case Var(name=name, where="local"):
                _refuse(node, f"a call of {name!r} with arguments")
            case Member(base=base, name="__call__"):
                self.block_call(node, base, scope)
            case Member(base=base, name=name) if METHOD_NAME.match(name):
                # `s.M__X(...)`: a method, a property's GET or SET, an action;
                # `POU_BASE.M__X(s, ...)`: a method of a base, SUPER^.X()
                if type(base) is Named and CLASS_NAME.match(base.name):
                    scope.runtime(base.name, base)
                else:
                    self.expr(base, scope)
                self.arguments(node, scope)
            case Member(base=base, name="update") if _is_action_control(base):
                # `s._ac_X.update(now, N=...)`: an SFC action's control block
                self.expr(base, scope)
                self.arguments(node, scope)
            case Member(name="get") if self.kind_lookup(node, scope):
                pass  # `_deref(t).__class__.__dict__.get('KIND__', ())` (`?=`)
            case Member(name=name):
                _refuse(node, f"a call of the attribute {name!r}")
            case _:
                _refuse(node, f"a call of {_a(callee)}")

    def block_call(self, node: Call, base: Expr, scope: _Scope) -> None:
        match base, node.args, node.keywords:
            case Var(name=name, where="local"), (), ():
                scope.local(name, base)  # `t.__call__()`: a block instance runs
            case Named(name=owner), (This() as instance,), () if (
                CLASS_NAME.match(owner) and scope.method
            ):  # `POU_BASE.__call__(s)`: SUPER^()
                scope.runtime(owner, base)
                scope.local("s", instance)
            case _:
                _refuse(node, "__call__ other than of a block instance or SUPER^()")


def _is_tick_read(node: Assign) -> bool:
    value, target = node.value, node.target
    return (
        node.augmented is None
        and type(value) is Named
        and value.name == "_tick"
        and type(target) is Var
        and target.where == "local"
    )


def _is_tick_test(node: Binary) -> bool:
    match node:
        case Binary(op="is" | "is not", left=Named(name="_tick"), right=Const(value=None)):
            return True
    return False


def _is_shift_count(node: Expr) -> bool:
    """A count of at most MAX_SHIFT: a constant, or `min(n, c)` of a constant (SHL's count,
    backend/compiler/builtins.py); a negative one is Python's error."""
    match node:
        case Const(value=int() as count) if type(count) is int:
            return count <= MAX_SHIFT
        case Call(callee="min", args=(_, Const(value=int() as bound)), keywords=()):
            return type(bound) is int and bound <= MAX_SHIFT
    return False


def _is_action_control(node: Expr) -> bool:
    """`s._ac_X`: the control block of an SFC action, a slot of the instance."""
    match node:
        case Member(base=This(), name=name) | Var(name=name, where="instance"):
            return name.startswith("_ac_") and is_plain_name(name)
    return False


def _value_use(name: str) -> str:
    if is_runtime_name(name.partition(".")[0]):
        return f"{name} other than called or with its attributes"
    return f"the name {name!r}"


def _a(node: object) -> str:
    """A kind of node, with its article."""
    noun = type(node).__name__
    return f"{'an' if noun[0] in 'AEIOU' else 'a'} {noun}"


def _path(root: object, target: object) -> str:
    """Where `target` is in the form `root`, as form_json names it
    (`Class.functions[0].body[3].value`); the first place it is when it is in several (a
    form decoded has each node once)."""
    # each node reached, as the index of its parent here and its step from it
    steps: list[tuple[int, str]] = [(-1, type(root).__name__)]
    pending: list[tuple[object, int]] = [(root, 0)]
    while pending:
        node, at = pending.pop()
        if node is target:
            return _steps_to(steps, at)
        if isinstance(node, tuple):
            children = [(f"[{index}]", item) for index, item in enumerate(node)]
        elif is_dataclass(node):
            children = [(f".{f.name}", getattr(node, f.name)) for f in fields(node)]
        else:
            continue
        for step, child in reversed(children):
            if isinstance(child, tuple) or is_dataclass(child):
                steps.append((at, step))
                pending.append((child, len(steps) - 1))
    return type(root).__name__


def _steps_to(steps: list[tuple[int, str]], at: int) -> str:
    path = []
    while at >= 0:
        at, step = steps[at]
        path.append(step)
    return "".join(reversed(path))
