"""What generated code may contain: the check every unit of an artifact passes before any of
its source becomes code (Python's `compile`, or C in the native tier).

An artifact comes from outside (a download, a reload, a recording, a backup), and its CRC
proves only that it was not damaged, not who wrote it. The generated source runs with
restricted builtins, but restricted builtins alone hold nothing: any attribute such as
`__globals__` of any function leads back to the full interpreter. So the source must be
code the compiler (`backend/compiler/generate.py`) could have written, and that is what
this module checks, on the syntax tree, construct by construct:

- one top-level definition, named as the compiler names units (`POU_X`, `FN_X`,
  `STRUCT_X`, `GLOBALS`); classes with `__slots__`, no bases, no decorators, and only the
  members the compiler writes (`__init__`, `__call__`, methods `M__X`, property accessors
  `GET__X` / `SET__X`, actions `_action_X`, `KIND__`);
- only the statements and expressions the compiler writes: no import, lambda, generator,
  comprehension beyond `[... for _ in range(n)]`, try, with, global, del, f-string,
  starred argument or dict literal beyond the one `_init` takes;
- every global name is one of the runtime's (`INTRINSICS`, `BUILTINS`: called, never
  passed on or changed) or a generated unit's; locals are plain ASCII identifiers;
- no attribute name with a leading `__` except the few the compiler writes, each in the
  one shape it writes it (`handle.__call__()`, `_deref(t).__class__.__name__`, ...);
  methods are called, never read as values; the system variables, `_math` and `_P` only
  with their own attributes.

Anything else is refused with the unit, the line and what is not allowed
(`GeneratedCodeError`, an `ArtifactError`): a runtime answers the load with a refusal and
keeps what it runs. `docs/artifact.md` lists the rules.
"""

from __future__ import annotations

import ast
import hashlib
import threading
from collections.abc import Iterable
from dataclasses import dataclass, field
from types import CodeType
from typing import NoReturn

from runtime.contract.artifact import Artifact, ArtifactError, PouCode
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

# the unit kinds of an artifact and the names the compiler gives their units
_UNIT_KINDS = {
    "PROGRAM": CLASS_NAME,
    "FUNCTION_BLOCK": CLASS_NAME,
    "FUNCTION": FUNCTION_NAME,
    "STRUCT": CLASS_NAME,
    "GLOBALS": CLASS_NAME,
}

_OPERATORS = (
    ast.Add, ast.Sub, ast.Mult, ast.Div, ast.FloorDiv, ast.Mod, ast.Pow, ast.LShift,
    ast.RShift, ast.BitOr, ast.BitXor, ast.BitAnd,
)  # fmt: skip
_CONSTANTS = (bool, int, float, str, type(None))
_TICK_TEST = (ast.Is, ast.IsNot)


class GeneratedCodeError(ArtifactError):
    """A unit whose source is not code the compiler generates: the unit, the line, what."""


def check_artifact_names(artifact: Artifact) -> None:
    """The names of an artifact's units and variables that the runtime and the native tier
    use as attribute names and put into C: plain identifiers, units named for their kind.
    Cheap: the sources are checked where they are compiled (`compile_unit`)."""
    for unit in artifact.units():
        _check_unit_names(unit)
    for program in artifact.programs:
        for attr in (*program.writes, *program.reads):
            if not is_data_attr(attr):
                raise GeneratedCodeError(
                    f"program {program.name!r}: the global {attr!r} is not a variable name"
                )


def _check_unit_names(unit: PouCode) -> None:
    pattern = _UNIT_KINDS.get(unit.kind)
    if pattern is None:
        raise GeneratedCodeError(f"a unit of kind {unit.kind!r} is not one an artifact has")
    if IDENTIFIER.match(unit.name) is None:
        raise GeneratedCodeError(f"the unit name {unit.name!r} is not an identifier")
    if pattern.match(unit.class_name) is None:
        raise GeneratedCodeError(
            f"{unit.kind} {unit.name}: {unit.class_name!r} is not the name of such a unit"
        )
    for variable in unit.variables:
        if not is_data_attr(variable.attr):
            raise GeneratedCodeError(
                f"{unit.kind} {unit.name}: {variable.attr!r} is not a variable name"
            )


def compile_unit(source: str, filename: str) -> CodeType:
    """The code of one unit's generated source, checked first (`check_source`);
    `filename` (`<PROGRAM Main>`) names the unit in tracebacks and refusals. Compiled from
    the source, not the checked tree: the same parser makes the same tree of it, and
    compiling a tree takes five times as long."""
    check_source(source, filename)
    return compile(source, filename, "exec", dont_inherit=True)


def check_source(source: str, unit: str) -> None:
    """Nothing when a unit's source is code the compiler generates, else
    GeneratedCodeError naming `unit` (its file name, `<PROGRAM Main>`), the line and what
    is not allowed. A source that passed is not checked again (a cold start, a reload
    preview and the reload compile the same units)."""
    digest = hashlib.sha256(source.encode("utf-8", "surrogatepass")).digest()
    if digest in _PASSED:
        return
    try:
        tree = ast.parse(source, unit)
    except SyntaxError as exc:
        raise GeneratedCodeError(f"{_unit(unit)}, line {exc.lineno}: {exc.msg}") from None
    except (ValueError, MemoryError, RecursionError) as exc:
        raise GeneratedCodeError(f"{_unit(unit)}: the source does not parse ({exc})") from None
    try:
        _Checker(unit).module(tree)
    except RecursionError:
        raise GeneratedCodeError(f"{_unit(unit)}: expressions nested too deep") from None
    with _PASSED_LOCK:
        _PASSED[digest] = None
        while len(_PASSED) > MAX_PASSED:
            del _PASSED[next(iter(_PASSED))]


# the digests of the sources that passed, oldest first
MAX_PASSED = 4096
_PASSED: dict[bytes, None] = {}
_PASSED_LOCK = threading.Lock()


def _unit(filename: str) -> str:
    return f"generated code of {filename.strip('<>')}"


@dataclass
class _Scope:
    """The names of one function (or of the module, for default values), resolved at its
    end as Python resolves them: a name the function binds anywhere is its local."""

    method: bool = False  # a method of a class: `s` is its instance
    bound: set[str] = field(default_factory=set)
    # bound otherwise than by `t = _tick` (a parameter, any other value)
    not_tick: set[str] = field(default_factory=set)
    # uses that hold only for a local, only for the runtime's name, only for a tick: by
    # name, where first met
    as_local: dict[str, ast.AST] = field(default_factory=dict)
    as_global: dict[str, ast.AST] = field(default_factory=dict)
    as_tick: dict[str, ast.AST] = field(default_factory=dict)

    def bind(self, name: str, tick: bool = False) -> None:
        self.bound.add(name)
        if not tick:
            self.not_tick.add(name)

    def local(self, name: str, node: ast.AST) -> None:
        self.as_local.setdefault(name, node)

    def runtime(self, name: str, node: ast.AST) -> None:
        self.as_global.setdefault(name, node)


class _Checker:
    def __init__(self, unit: str) -> None:
        self.unit = unit

    def refuse(self, node: ast.AST, what: str) -> NoReturn:
        line = getattr(node, "lineno", 0)
        raise GeneratedCodeError(f"{_unit(self.unit)}, line {line}: {what} is not allowed")

    # ---- the unit: one definition
    def module(self, tree: ast.Module) -> None:
        if len(tree.body) != 1:
            self.refuse(tree.body[1] if tree.body else tree, "a second top-level statement")
        node = tree.body[0]
        if isinstance(node, ast.ClassDef):
            if CLASS_NAME.match(node.name) is None:
                self.refuse(node, f"a class named {node.name!r}")
            self.class_def(node)
        elif isinstance(node, ast.FunctionDef):
            if FUNCTION_NAME.match(node.name) is None:
                self.refuse(node, f"a function named {node.name!r}")
            self.function_def(node, method=False)
        elif not (
            isinstance(node, ast.Assign)
            and len(node.targets) == 1
            and isinstance(node.targets[0], ast.Name)
            and CLASS_NAME.match(node.targets[0].id)
            and isinstance(node.value, ast.Name)
            and node.value.id == "_SfcStep"
        ):  # `STRUCT_SFC_STEP = _SfcStep`: steps are the runtime's own class
            self.refuse(node, f"{_a(node)} at the top level")

    def class_def(self, node: ast.ClassDef) -> None:
        if node.bases or node.keywords or node.decorator_list or _type_params(node):
            self.refuse(node, "a class with bases, keywords or decorators")
        if not node.body or not _assigns(node.body[0], "__slots__"):
            self.refuse(node, "a class without __slots__ first")
        for item in node.body:
            if isinstance(item, ast.FunctionDef):
                if item.name not in ("__init__", "__call__") and not METHOD_NAME.match(item.name):
                    self.refuse(item, f"a method named {item.name!r}")
                self.function_def(item, method=True)
            elif isinstance(item, ast.Assign) and (
                _assigns(item, "__slots__") or _assigns(item, "KIND__")
            ):
                self.names_tuple(item.value, slots=_assigns(item, "__slots__"))
            elif isinstance(item, ast.Assign):
                self.method_alias(item)
            else:
                self.refuse(item, f"{_a(item)} in a class body")

    def names_tuple(self, value: ast.expr, slots: bool) -> None:
        """`__slots__ = ('a', 'b')`: variable names; `KIND__ = ('FB', 'ITF')`: ST keys."""
        if not isinstance(value, ast.Tuple):
            self.refuse(value, "a __slots__ or KIND__ that is not a tuple of names")
        for item in value.elts:
            if not (isinstance(item, ast.Constant) and type(item.value) is str):
                self.refuse(item, "a __slots__ or KIND__ entry that is not a name")
            if slots and not is_data_attr(item.value):
                self.refuse(item, f"the slot {item.value!r}")
            if not slots and IDENTIFIER.match(item.value) is None:
                self.refuse(item, f"the KIND__ entry {item.value!r}")

    def method_alias(self, node: ast.Assign) -> None:
        """`M__X = POU_BASE.M__X`: an inherited method, the declaring class's function."""
        match node:
            case ast.Assign(
                targets=[ast.Name(id=name)],
                value=ast.Attribute(value=ast.Name(id=owner), attr=attr),
            ) if METHOD_NAME.match(name) and attr == name and CLASS_NAME.match(owner):
                return
        self.refuse(node, "an assignment in a class body other than an inherited method")

    def function_def(self, node: ast.FunctionDef, method: bool) -> None:
        args = node.args
        if (
            node.decorator_list
            or node.returns is not None
            or _type_params(node)
            or args.vararg
            or args.kwarg
            or args.kwonlyargs
            or args.posonlyargs
            or any(a.annotation is not None for a in args.args)
        ):
            self.refuse(node, f"{node.name}: decorators, annotations, *args or **kwargs")
        names = [a.arg for a in args.args]
        if method and names[:1] != ["s"]:
            self.refuse(node, f"the method {node.name} without `s` first")
        if node.name in ("__init__", "__call__") and names != ["s"]:
            self.refuse(node, f"{node.name} with parameters")
        outer = _Scope()  # default values: evaluated where the class or function is made
        for default in args.defaults:
            self.expr(default, outer)
        self.resolve(outer, node)
        scope = _Scope(method)
        for name in names:
            if not is_local_name(name):
                self.refuse(node, f"the parameter {name!r}")
            scope.bind(name)
        self.block(node.body, scope)
        self.resolve(scope, node)

    def resolve(self, scope: _Scope, where: ast.AST) -> None:
        """Each use of a name as Python resolves it: a name the function binds is local in
        all of it, any other the namespace's."""
        for name, node in scope.as_global.items():
            if name in scope.bound:
                self.refuse(node, f"{name} as a local")
        for name, node in scope.as_local.items():
            if name not in scope.bound:
                self.refuse(node, _global_use(name))
        for name, node in scope.as_tick.items():
            if name not in scope.bound or name in scope.not_tick:
                self.refuse(node, f"a call of {name!r}")

    # ---- statements
    def block(self, statements: list[ast.stmt], scope: _Scope) -> None:
        for statement in statements:
            self.statement(statement, scope)

    def statement(self, node: ast.stmt, scope: _Scope) -> None:
        kind = type(node)
        if kind is ast.Assign:
            assert isinstance(node, ast.Assign)
            if len(node.targets) != 1:
                self.refuse(node, "a chained assignment")
            target, value = node.targets[0], node.value
            if type(value) is ast.Name and value.id == "_tick" and type(target) is ast.Name:
                scope.runtime("_tick", value)  # `t = _tick`, read once before a loop
                self.local_target(target, scope, tick=True)
                return
            self.target(target, scope)
            self.expr(value, scope)
        elif kind is ast.Expr:
            assert isinstance(node, ast.Expr)
            self.expr(node.value, scope)
        elif kind is ast.If:
            assert isinstance(node, ast.If)
            self.expr(node.test, scope)
            self.block(node.body, scope)
            self.block(node.orelse, scope)
        elif kind is ast.AugAssign:
            assert isinstance(node, ast.AugAssign)
            if not isinstance(node.op, _OPERATORS):
                self.refuse(node, f"the operator {type(node.op).__name__}")
            self.target(node.target, scope)
            self.expr(node.value, scope)
        elif kind is ast.While:
            assert isinstance(node, ast.While)
            if node.orelse:
                self.refuse(node, "while ... else")
            self.expr(node.test, scope)
            self.block(node.body, scope)
        elif kind is ast.For:
            assert isinstance(node, ast.For)
            if type(node.target) is not ast.Name or node.type_comment is not None:
                self.refuse(node, "a for loop over anything but one local")
            self.target(node.target, scope)
            self.expr(node.iter, scope)
            self.block(node.body, scope)
            self.block(node.orelse, scope)
        elif kind is ast.Return:
            assert isinstance(node, ast.Return)
            if node.value is not None:
                self.expr(node.value, scope)
        elif kind not in (ast.Break, ast.Continue, ast.Pass):
            self.refuse(node, _a(node))

    def local_target(self, node: ast.Name, scope: _Scope, tick: bool = False) -> None:
        if not is_local_name(node.id):
            self.refuse(node, f"an assignment to {node.id!r}")
        scope.bind(node.id, tick)

    def target(self, node: ast.expr, scope: _Scope) -> None:
        """What an assignment writes: a local, an attribute or an item of an object."""
        kind = type(node)
        if kind is ast.Name:
            assert isinstance(node, ast.Name)
            self.local_target(node, scope)
        elif kind is ast.Attribute:
            assert isinstance(node, ast.Attribute)
            owner, attr = node.value, node.attr
            if type(owner) is ast.Name and owner.id in ("_SYS", "_G"):
                assert isinstance(owner, ast.Name)
                scope.runtime(owner.id, owner)
                writable = WRITABLE_SYSTEM_ATTRS if owner.id == "_SYS" else ()
                if attr not in writable and not (owner.id == "_G" and is_data_attr(attr)):
                    self.refuse(node, f"an assignment to {owner.id}.{attr}")
                return
            if not is_data_attr(attr):
                self.refuse(node, f"an assignment to the attribute {attr!r}")
            self.expr(owner, scope)
        elif kind is ast.Subscript:
            assert isinstance(node, ast.Subscript)
            self.expr(node.value, scope)
            self.subscript_index(node.slice, scope)
        elif kind is ast.Tuple:
            assert isinstance(node, ast.Tuple)
            for element in node.elts:
                self.target(element, scope)
        else:
            self.refuse(node, f"an assignment to {_a(node)}")

    # ---- expressions
    def expr(self, node: ast.expr, scope: _Scope) -> None:
        kind = type(node)
        if kind is ast.Constant:
            assert isinstance(node, ast.Constant)
            if type(node.value) not in _CONSTANTS:
                self.refuse(node, f"a constant of type {type(node.value).__name__}")
        elif kind is ast.Name:
            assert isinstance(node, ast.Name)
            scope.local(node.id, node)  # the runtime's names are never values
        elif kind is ast.Attribute:
            assert isinstance(node, ast.Attribute)
            self.attribute(node, scope)
        elif kind is ast.Call:
            assert isinstance(node, ast.Call)
            self.call(node, scope)
        elif kind is ast.BinOp:
            assert isinstance(node, ast.BinOp)
            if not isinstance(node.op, _OPERATORS):
                self.refuse(node, f"the operator {type(node.op).__name__}")
            self.expr(node.left, scope)
            self.expr(node.right, scope)
        elif kind is ast.Compare:
            assert isinstance(node, ast.Compare)
            self.compare(node, scope)
        elif kind is ast.IfExp:
            assert isinstance(node, ast.IfExp)
            self.expr(node.test, scope)
            self.expr(node.body, scope)
            self.expr(node.orelse, scope)
        elif kind is ast.UnaryOp:
            assert isinstance(node, ast.UnaryOp)
            self.expr(node.operand, scope)
        elif kind is ast.NamedExpr:
            assert isinstance(node, ast.NamedExpr)
            self.local_target(node.target, scope)
            self.expr(node.value, scope)
        elif kind is ast.Subscript:
            assert isinstance(node, ast.Subscript)
            self.expr(node.value, scope)
            self.subscript_index(node.slice, scope)
        elif kind is ast.BoolOp:
            assert isinstance(node, ast.BoolOp)
            for value in node.values:
                self.expr(value, scope)
        elif kind is ast.Tuple or kind is ast.List:
            assert isinstance(node, ast.Tuple | ast.List)
            for element in node.elts:
                self.expr(element, scope)
        elif kind is ast.ListComp:
            assert isinstance(node, ast.ListComp)
            self.list_comprehension(node, scope)
        else:
            self.refuse(node, _a(node))

    def subscript_index(self, node: ast.expr, scope: _Scope) -> None:
        if type(node) is ast.Slice:
            assert isinstance(node, ast.Slice)
            for part in (node.lower, node.upper, node.step):
                if part is not None:
                    self.expr(part, scope)
        else:
            self.expr(node, scope)

    def list_comprehension(self, node: ast.ListComp, scope: _Scope) -> None:
        """`[STRUCT_X() for _ in range(n)]`: an array of instances, each its own."""
        match node.generators:
            case [ast.comprehension(target=ast.Name(id="_") as target, ifs=[], is_async=0)]:
                self.expr(node.generators[0].iter, scope)
                self.local_target(target, scope)
                self.expr(node.elt, scope)
            case _:
                self.refuse(node, "a comprehension other than `[... for _ in range(n)]`")

    def compare(self, node: ast.Compare, scope: _Scope) -> None:
        match node:
            case ast.Compare(
                left=ast.Name(id="_tick") as tick, ops=[ast.Is() | ast.IsNot()],
                comparators=[ast.Constant(value=None)],
            ):  # fmt: skip
                scope.runtime("_tick", tick)  # `_tick is None`: whether a slice is metered
                return
        self.expr(node.left, scope)
        for operand in node.comparators:
            self.expr(operand, scope)

    def attribute(self, node: ast.Attribute, scope: _Scope) -> None:
        """An attribute read as a value."""
        owner, attr = node.value, node.attr
        if type(owner) is ast.Name:
            assert isinstance(owner, ast.Name)
            name = owner.id
            if name in ("_SYS", "_G", "_P"):
                scope.runtime(name, owner)
                if not (
                    (name == "_SYS" and attr in SYSTEM_ATTRS)
                    or (name == "_G" and is_data_attr(attr))
                    or (name == "_P" and CLASS_NAME.match(attr))
                ):
                    self.refuse(node, f"the attribute {name}.{attr}")
                return
        if attr == "__name__" and self.class_of_deref(owner, scope):
            return  # `_deref(t).__class__.__name__` (`?=`): the name of an instance's class
        if not is_data_attr(attr):
            self.refuse(node, f"the attribute {attr!r}")
        self.expr(owner, scope)

    def class_of_deref(self, node: ast.expr, scope: _Scope) -> bool:
        """`_deref(t).__class__`, t a local (checked here when it is)."""
        match node:
            case ast.Attribute(
                value=ast.Call(func=ast.Name(id="_deref") as func, args=[ast.Name() as held],
                               keywords=[]),
                attr="__class__",
            ):  # fmt: skip
                scope.runtime("_deref", func)
                scope.local(held.id, held)
                return True
        return False

    # ---- calls
    def call(self, node: ast.Call, scope: _Scope) -> None:
        func = node.func
        for keyword in node.keywords:
            if keyword.arg is None or not is_plain_name(keyword.arg):
                self.refuse(node, "a ** argument or a keyword that is not a plain name")
        if type(func) is ast.Name:
            assert isinstance(func, ast.Name)
            self.call_name(node, func, scope)
        elif type(func) is ast.Attribute:
            assert isinstance(func, ast.Attribute)
            self.call_attribute(node, func, scope)
        else:
            self.refuse(node, f"a call of {_a(func)}")

    def arguments(self, node: ast.Call, scope: _Scope) -> None:
        for argument in node.args:
            if type(argument) is ast.Starred:
                self.refuse(argument, "a starred argument")
            self.expr(argument, scope)
        for keyword in node.keywords:
            self.expr(keyword.value, scope)

    def call_name(self, node: ast.Call, func: ast.Name, scope: _Scope) -> None:
        name = func.id
        if name in CALLED_INTRINSICS or name in BUILTINS or UNIT_NAME.match(name):
            scope.runtime(name, func)
        else:  # a local: only the tick, read into it before a loop (`t()`)
            if node.args or node.keywords:
                self.refuse(node, f"a call of {name!r}")
            scope.as_tick.setdefault(name, func)
            return
        if node.keywords and UNIT_NAME.match(name) is None:
            # the runtime's functions take positions only (`max(..., key=f)` would call f)
            self.refuse(node, f"{name}() with keywords")
        if name == "_safe_math":
            self.safe_math(node, scope)
        elif name == "_init":
            self.structure_init(node, scope)
        elif name == "_ref":
            self.reference(node, scope)
        else:
            self.arguments(node, scope)

    def safe_math(self, node: ast.Call, scope: _Scope) -> None:
        """`_safe_math(_math.sqrt, x)`: the one place a function is passed as a value."""
        match node:
            case ast.Call(
                args=[ast.Attribute(value=ast.Name(id="_math") as module, attr=function), value],
                keywords=[],
            ) if function in MATH_FUNCTIONS:  # fmt: skip
                scope.runtime("_math", module)
                self.expr(value, scope)
            case _:
                self.refuse(node, "_safe_math of anything but a function of _math")

    def structure_init(self, node: ast.Call, scope: _Scope) -> None:
        """`_init(STRUCT_X(), {'a': 1})`: members set by name, each a variable's."""
        match node:
            case ast.Call(args=[target, ast.Dict(keys=keys, values=values)], keywords=[]):
                self.expr(target, scope)
                for key, value in zip(keys, values, strict=True):
                    if not (
                        isinstance(key, ast.Constant)
                        and type(key.value) is str
                        and is_data_attr(key.value)
                    ):
                        self.refuse(node, "_init of a member that is not a variable name")
                    self.expr(value, scope)
            case _:
                self.refuse(node, "_init of anything but an object and a dict of members")

    def reference(self, node: ast.Call, scope: _Scope) -> None:
        """`_ref(root, ('a', offset), label, whole)`: REF(x); the steps are variable names
        or list offsets (the runtime refuses any other step when the code runs)."""
        match node:
            case ast.Call(args=[root, ast.Tuple(elts=steps), *rest], keywords=[]) if len(rest) <= 2:
                if type(root) is ast.Name and root.id == "_G":  # a global's root
                    scope.runtime("_G", root)
                else:
                    self.expr(root, scope)
                for step in steps:
                    if isinstance(step, ast.Constant) and type(step.value) is str:
                        if not is_data_attr(step.value):
                            self.refuse(step, f"a reference through {step.value!r}")
                    else:
                        self.expr(step, scope)
                for other in rest:
                    self.expr(other, scope)
            case _:
                self.refuse(node, "_ref of anything but a root, a tuple of steps and a label")

    def call_attribute(self, node: ast.Call, func: ast.Attribute, scope: _Scope) -> None:
        owner, attr = func.value, func.attr
        owner_name = owner.id if type(owner) is ast.Name else None
        if attr == "__call__":
            if owner_name is not None and not node.args and not node.keywords:
                scope.local(owner_name, owner)  # `t.__call__()`: a block instance runs
                return
            if (
                owner_name is not None
                and CLASS_NAME.match(owner_name)
                and scope.method
                and [_name_of(a) for a in node.args] == ["s"]
                and not node.keywords
            ):  # `POU_BASE.__call__(s)`: SUPER^()
                scope.runtime(owner_name, owner)
                scope.local("s", node.args[0])
                return
            self.refuse(node, "__call__ other than of a block instance or SUPER^()")
        if METHOD_NAME.match(attr):
            # `s.M__X(...)`, `POU_BASE.M__X(s, ...)`: a method, a property's GET or SET, an
            # action
            if owner_name is not None and CLASS_NAME.match(owner_name):
                scope.runtime(owner_name, owner)
            else:
                self.expr(owner, scope)
            self.arguments(node, scope)
            return
        if attr == "update" and _is_action_control(owner):
            # `s._ac_X.update(now, N=...)`: an SFC action's control block
            self.expr(owner, scope)
            self.arguments(node, scope)
            return
        match node:
            case ast.Call(
                func=ast.Attribute(value=ast.Attribute(value=kind, attr="__dict__"), attr="get"),
                args=[ast.Constant(value="KIND__"), ast.Tuple(elts=[])],
                keywords=[],
            ) if self.class_of_deref(kind, scope):  # fmt: skip
                return  # `_deref(t).__class__.__dict__.get('KIND__', ())` (`?=`)
        self.refuse(node, f"a call of the attribute {attr!r}")


def _global_use(name: str) -> str:
    if is_runtime_name(name):
        return f"{name} other than called or with its attributes"
    return f"the name {name!r}"


def _is_action_control(node: ast.expr) -> bool:
    return (
        isinstance(node, ast.Attribute)
        and node.attr.startswith("_ac_")
        and is_plain_name(node.attr)
        and _name_of(node.value) == "s"
    )


def _name_of(node: ast.expr) -> str | None:
    return node.id if isinstance(node, ast.Name) else None


def _assigns(node: ast.stmt, name: str) -> bool:
    return (
        isinstance(node, ast.Assign)
        and len(node.targets) == 1
        and isinstance(node.targets[0], ast.Name)
        and node.targets[0].id == name
    )


def _targets(node: ast.stmt) -> Iterable[ast.expr]:
    if isinstance(node, ast.Assign):
        for target in node.targets:
            yield from _flat(target)
    elif isinstance(node, ast.AnnAssign | ast.AugAssign | ast.For):
        yield from _flat(node.target)


def _flat(target: ast.expr) -> Iterable[ast.expr]:
    if isinstance(target, ast.Tuple | ast.List):
        for element in target.elts:
            yield from _flat(element)
    else:
        yield target


def _type_params(node: ast.AST) -> bool:
    return bool(getattr(node, "type_params", None))


def _a(node: ast.AST) -> str:
    """A construct as a reader of the refusal knows it, with its article."""
    names = {
        "Import": "import", "ImportFrom": "import", "Lambda": "lambda",
        "GeneratorExp": "generator expression", "Yield": "yield", "YieldFrom": "yield",
        "Await": "await", "Try": "try", "TryStar": "try", "With": "with", "Global": "global",
        "Nonlocal": "nonlocal", "Delete": "del", "JoinedStr": "f-string",
        "Starred": "starred expression", "Dict": "dict", "Set": "set", "SetComp": "set",
        "DictComp": "dict comprehension", "Raise": "raise", "Assert": "assert",
        "ClassDef": "class definition", "FunctionDef": "function definition",
        "AsyncFunctionDef": "async function", "Match": "match", "Assign": "assignment",
        "AnnAssign": "annotated assignment", "Expr": "expression statement",
    }  # fmt: skip
    noun = names.get(type(node).__name__, type(node).__name__)
    return f"{'an' if noun[0] in 'aeiouAEIOU' or noun == 'f-string' else 'a'} {noun}"
