"""Generated Python to C: the bodies (`__call__`) of the generated classes of one unit of an
artifact, as one C module that `runtime/code/native/tier.py` loads and binds.

The Python code is the reference. A body is translated only when every construct in it is
one the translator knows and every integer it computes provably fits the C type it is
computed in (`runtime/code/native/kinds.py`); anything else leaves the body to Python, with
the reason. The C code works on the same objects as the Python code (slots of the
generated classes), so both tiers can run side by side and every service of the runtime
sees one kind of data.
"""

from __future__ import annotations

import ast
import contextlib
import hashlib
import itertools
import math
import re
from collections.abc import Iterator
from dataclasses import dataclass, field, replace
from typing import NoReturn

from runtime.code.fault_location import code_filename
from runtime.code.native.kinds import (
    EXACT_IN_DOUBLE,
    FROM_REAL,
    FULL64,
    INT64_MAX,
    INT64_MIN,
    STAND_IN_FROM,
    SYSTEM_BOOLS,
    SYSTEM_INTS,
    Array,
    Bool,
    ClassInfo,
    Float,
    FunctionInfo,
    Hook,
    Instance,
    Int,
    Kind,
    Range,
    System,
    join,
)
from runtime.contract.artifact import PouCode
from runtime.contract.intrinsic_table import F32, FDIV, IDIV, IMOD, IX, ROUND, TICK

NAME_PLACEHOLDER = "padt_unit"
WIDEN_AFTER = 3  # passes over a body before a growing local takes the whole 64-bit range
_RELATIONS = {
    ast.Eq: "==", ast.NotEq: "!=", ast.Lt: "<", ast.LtE: "<=", ast.Gt: ">", ast.GtE: ">=",
}  # fmt: skip


class NotTranslated(Exception):
    """A body the tier leaves to Python; the message says why."""

    def __init__(self, reason: str, node: ast.AST | None = None) -> None:
        line = getattr(node, "lineno", 0)
        super().__init__(f"{reason} (generated line {line})" if line else reason)


def _refuse(reason: str, node: ast.AST | None = None) -> NoReturn:
    raise NotTranslated(reason, node)


@dataclass(frozen=True)
class Translated:
    """The C module of a unit; `bodies` ("CLASS.__call__") it binds, `left` the bodies left
    to Python with the reason. `source` is empty when no body was translated."""

    unit: str
    module: str  # the module name (its init function is PyInit_<module>)
    source: str
    bodies: tuple[str, ...]
    left: tuple[tuple[str, str], ...]


@dataclass(frozen=True)
class V:
    """A value: its kind, and a C expression without side effects that yields it."""

    kind: Kind
    c: str


def c_int(value: int) -> str:
    """An integer literal of C (128-bit ones built from two halves)."""
    if INT64_MIN < value <= INT64_MAX:
        return f"{value}LL" if abs(value) > 2**31 else str(value)
    if value == INT64_MIN:
        return "(-9223372036854775807LL - 1)"
    bits = value & ((1 << 128) - 1)
    high, low = bits >> 64, bits & ((1 << 64) - 1)
    return f"((padt_i128)(((unsigned __int128){high}ULL << 64) | {low}ULL))"


def c_string(text: str) -> str:
    """A C string literal; only printable ASCII passes unescaped."""
    out = []
    for ch in text:
        if ch in '"\\?':
            out.append("\\" + ch)
        elif " " <= ch <= "~":
            out.append(ch)
        else:
            out.append("".join(f"\\{b:03o}" for b in ch.encode()))
    return '"' + "".join(out) + '"'


def c_comment(text: str) -> str:
    """A C comment of `text`, which cannot end it early (names are checked before they get
    here, runtime/contract/generated_code.py; this holds whatever a name holds)."""
    return "/* " + text.replace("*/", "* /") + " */"


def _identifier(text: str) -> str:
    return "".join(ch if ch.isalnum() else "_" for ch in text if ch.isascii())


# ---- module: the statics one unit's bodies share ---------------------------------------------


@dataclass
class _Module:
    classes: dict[str, ClassInfo]
    filename: str
    types: dict[str, str] = field(default_factory=dict)  # class name -> C static
    offsets: dict[tuple[str, str], str] = field(default_factory=dict)
    keys: dict[str, str] = field(default_factory=dict)  # interned strings
    sites: int = 0
    globals_class: str | None = None
    functions: dict[str, FunctionInfo] = field(default_factory=dict)
    kwnames: dict[tuple[str, ...], str] = field(default_factory=dict)  # -> C static tuple

    def type_ref(self, cls: str) -> str:
        return self.types.setdefault(cls, f"T{len(self.types)}")

    def offset(self, cls: str, attr: str) -> str:
        self.type_ref(cls)
        return self.offsets.setdefault((cls, attr), f"O{len(self.offsets)}")

    def key(self, text: str) -> str:
        return self.keys.setdefault(text, f"K{len(self.keys)}")

    def names(self, keywords: tuple[str, ...]) -> str:
        """The tuple of keyword names of a vectorcall."""
        for keyword in keywords:
            self.key(keyword)
        return self.kwnames.setdefault(keywords, f"KW{len(self.kwnames)}")

    def site(self) -> str:
        self.sites += 1
        return f"S{self.sites - 1}"

    def statics(self) -> list[str]:
        lines = [f"static PyObject *{ref}; {c_comment(cls)}" for cls, ref in self.types.items()]
        lines += [
            f"static Py_ssize_t {ref}; {c_comment(f'{cls}.{attr}')}"
            for (cls, attr), ref in self.offsets.items()
        ]
        lines += [
            f"static PyObject *{ref}; {c_comment(repr(text))}" for text, ref in self.keys.items()
        ]
        lines += [
            f"static PyObject *{ref}; {c_comment(repr(names))}"
            for names, ref in self.kwnames.items()
        ]
        lines += [f"static padt_site S{n};" for n in range(self.sites)]
        return lines

    def binding(self) -> list[str]:
        """The lines of `bind` that resolve the statics (NULL return on failure)."""
        lines = []
        for cls, ref in self.types.items():
            lines.append(f"    if (({ref} = padt_class({c_string(cls)})) == NULL) return NULL;")
        for (cls, attr), ref in self.offsets.items():
            lines.append(
                f"    if (({ref} = padt_offset({self.types[cls]}, {c_string(attr)})) < 0)"
                " return NULL;"
            )
        for text, ref in self.keys.items():
            lines.append(
                f"    if ({ref} == NULL && ({ref} = PyUnicode_InternFromString({c_string(text)}))"
                " == NULL) return NULL;"
            )
        for names, ref in self.kwnames.items():
            keys = ", ".join(self.keys[name] for name in names)
            lines.append(
                f"    if ({ref} == NULL && ({ref} = PyTuple_Pack({len(names)}, {keys})) == NULL)"
                " return NULL;"
            )
        lines += [f"    memset(&S{n}, 0, sizeof S{n});" for n in range(self.sites)]
        return lines


# ---- one body ------------------------------------------------------------------------------------


@dataclass
class _Loop:
    next_label: str  # where `continue` goes
    end_label: str  # where `break` goes


class _Body:
    """The translation of one `__call__`, given the kinds of its locals; `assigned` collects
    the kinds the body gives them, for the next pass."""

    def __init__(
        self, module: _Module, cls: ClassInfo, func: ast.FunctionDef, local_kinds: dict[str, Kind]
    ) -> None:
        self.module, self.cls, self.func = module, cls, func
        self.local_kinds = local_kinds
        self.assigned: dict[str, Kind] = {}
        self.out: list[str] = []
        self.depth = 1
        self.decls: dict[str, str] = {}  # C temporaries of a statement -> declaration
        self.objects: list[str] = []  # temporaries that own a reference
        # the Python locals live in a frame the chunks of the body share (_function_text)
        self.frame: dict[str, str] = {}
        self.frame_objects: list[str] = []
        self.marks: list[int] = []  # where each statement of the body begins in `out`
        self.named: dict[str, V] = {}  # targets of `:=`, within the statement
        self.narrowed: dict[str, Int] = {}  # locals known to lie in a smaller range here
        self.loops: list[_Loop] = []
        self.labels = 0
        self.uses_globals = False

    # -- emission
    def line(self, text: str) -> None:
        self.out.append("    " * self.depth + text)

    def check(self, call: str) -> None:
        self.line(f"if (PADT_UNLIKELY({call} < 0)) goto padt_error;")

    @contextlib.contextmanager
    def captured(self) -> Iterator[list[str]]:
        """Lines emitted meanwhile go to the list given, one level deeper."""
        saved, self.out = self.out, []
        lines = self.out
        self.depth += 1
        try:
            yield lines
        finally:
            self.depth -= 1
            self.out = saved

    def temp(self, ctype: str, init: str = "0") -> str:
        name = f"t{len(self.decls)}"
        self.decls[name] = f"{ctype} {name} = {init};"
        if ctype == "PyObject *":
            self.objects.append(name)
        return name

    def label(self, what: str) -> str:
        self.labels += 1
        return f"L{self.labels}_{what}"

    # -- statements
    def body(self) -> None:
        for statement in self.func.body:
            self.marks.append(len(self.out))
            self.statement(statement)

    def block(self, statements: list[ast.stmt]) -> None:
        for statement in statements:
            self.statement(statement)

    def statement(self, node: ast.stmt) -> None:
        self.named = {}
        self.line(f"padt_line = {node.lineno};")
        if isinstance(node, ast.Assign):
            if len(node.targets) != 1:
                _refuse("an assignment to several targets", node)
            self.assign(node.targets[0], node.value, node)
        elif isinstance(node, ast.AugAssign):
            target = node.target
            load = ast.copy_location(_as_load(target), target)
            value = ast.copy_location(ast.BinOp(load, node.op, node.value), node)
            self.assign(target, value, node)
        elif isinstance(node, ast.Expr):
            self.call_statement(node.value)
        elif isinstance(node, ast.If):
            self.if_statement(node)
        elif isinstance(node, ast.While):
            self.while_loop(node)
        elif isinstance(node, ast.For):
            self.for_loop(node)
        elif isinstance(node, ast.Break | ast.Continue):
            if not self.loops:
                _refuse("break outside a loop", node)
            loop = self.loops[-1]
            self.line(f"goto {loop.end_label if isinstance(node, ast.Break) else loop.next_label};")
        elif isinstance(node, ast.Return):
            if node.value is not None and not _is_none(node.value):
                _refuse("a body that returns a value", node)
            self.line("goto padt_done;")
        elif isinstance(node, ast.Pass):
            pass
        else:
            _refuse(f"a {type(node).__name__} statement", node)

    def assign(self, target: ast.expr, value_node: ast.expr, node: ast.stmt) -> None:
        if isinstance(target, ast.Name):
            self.assign_local(target.id, value_node, node)
            return
        value = self.expr(value_node)
        if isinstance(target, ast.Attribute):
            owner = self.expr(target.value)
            if not isinstance(owner.kind, Instance):
                _refuse("a store into something else than a generated object", node)
            member = self.member_kind(owner.kind, target.attr, node)
            slot = self.module.offset(owner.kind.cls, target.attr)
            place = f"PADT_PLACE({owner.c}, {slot})"
            self.store(place, value, member, f"{owner.kind.cls}.{target.attr}", node)
        elif isinstance(target, ast.Subscript):
            array = self.expr(target.value)
            if not isinstance(array.kind, Array) or array.kind.element is None:
                _refuse("a store into something else than an array of elementary values", node)
            offset = self.list_offset(array, target.slice)
            place = f"PADT_ITEM_PLACE({array.c}, {offset})"
            self.store(place, value, array.kind.element, "an array element", node)
        else:
            _refuse(f"a store into a {type(target).__name__}", node)

    def store(self, place: str, value: V, declared: Kind | None, what: str, node: ast.AST) -> None:
        """`value` into a slot or list item of a variable of `declared`, as Python holds it."""
        if isinstance(declared, Bool) and isinstance(value.kind, Bool):
            self.line(f"padt_set_bool({place}, {value.c});")
            return
        if isinstance(declared, Float) and isinstance(value.kind, Float):
            self.check(f"padt_set_float({place}, {value.c})")
            return
        if isinstance(declared, Int) and isinstance(value.kind, Int):
            if value.kind.stand_in:
                _refuse("a REAL's integer stored without a wrap", node)
            if not value.kind.within(declared):
                # not proven in range: the contract says it is; a value outside is a fault
                self.check(
                    f"padt_in_range((padt_i128)({value.c}), {c_int(declared.lo)}, "
                    f"{c_int(declared.hi)}, {c_string(what)})"
                )
            setter = "padt_set_int" if value.kind.fits64 else "padt_set_int128"
            self.check(f"{setter}({place}, {value.c})")
            return
        _refuse(f"a {_kind_name(value.kind)} stored into {_kind_name(declared)}", node)

    def assign_local(self, name: str, value_node: ast.expr, node: ast.stmt) -> None:
        if name == "s" or (name.startswith("_") and not name.startswith("__")):
            _refuse(f"an assignment to {name}", node)
        if isinstance(value_node, ast.Call) and _called_name(value_node) == "range":
            kind: Kind = self.range_kind(value_node)
            self.note_assigned(name, kind, node)
            start, stop = self.range_bounds(value_node)
            local = self.local_ref(name, node)
            self.line(f"{local}_start = {start.c}; {local}_stop = {stop.c};")
            return
        value = self.expr(value_node)
        if isinstance(value.kind, Int) and value.kind.stand_in:
            _refuse("a REAL's integer kept in a local", node)
        self.note_assigned(name, value.kind, node)
        local_kind = self.local_kind(name)
        local = self.local_ref(name, node)
        if isinstance(local_kind, Int) and isinstance(value.kind, Int):
            if value.kind.fits64 or not local_kind.fits64:
                self.line(f"{local} = {value.c};")
            else:
                self.check(f"padt_narrow({value.c}, &{local})")
        elif isinstance(local_kind, Bool | Float) and value.kind == local_kind:
            self.line(f"{local} = {value.c};")
        elif isinstance(local_kind, Instance | Hook) and value.kind == local_kind:
            self.line(f"Py_XSETREF({local}, Py_NewRef({value.c}));")
        else:
            _refuse(f"local {name} takes a {_kind_name(value.kind)}", node)

    def note_assigned(self, name: str, kind: Kind, node: ast.AST) -> None:
        known = self.assigned.get(name)
        joined = kind if known is None else join(known, kind)
        if joined is None:
            _refuse(f"local {name} holds values of different kinds", node)
        self.assigned[name] = joined

    def local_kind(self, name: str) -> Kind | None:
        """The kind of a local: as the passes before found it, else as this pass has so far."""
        return self.local_kinds.get(name) or self.assigned.get(name)

    def local_ref(self, name: str, node: ast.AST) -> str:
        """The C variable of a Python local (declared once)."""
        kind = self.local_kind(name)
        if kind is None:
            _refuse(f"local {name} is read before it is assigned", node)
        c = f"l_{_identifier(name)}"
        if c not in self.frame:
            if isinstance(kind, Int):
                self.frame[c] = f"{kind.ctype} {c};"
            elif isinstance(kind, Bool):
                self.frame[c] = f"int {c};"
            elif isinstance(kind, Float):
                self.frame[c] = f"double {c};"
            elif isinstance(kind, Instance | Hook):
                self.frame[c] = f"PyObject *{c};"
                self.frame_objects.append(c)
            elif isinstance(kind, Range):
                self.frame[c] = f"int64_t {c}_start, {c}_stop;"
            else:
                _refuse(f"local {name} holds a {_kind_name(kind)}", node)
        return f"f->{c}"

    def call_statement(self, call: ast.expr) -> None:
        if isinstance(call, ast.Call) and _called_name(call) in self.module.functions:
            self.function_call(call)  # its result, if any, dropped at the chunk's end
            return
        if not isinstance(call, ast.Call) or call.keywords:
            _refuse("an expression statement that is no call", call)
        func = call.func
        if isinstance(func, ast.Attribute) and func.attr == "__call__" and not call.args:
            target = self.expr(func.value)
            if not isinstance(target.kind, Instance):
                _refuse("a call of something else than a generated object", call)
            self.check(f"padt_call({target.c}, &{self.module.site()})")
            return
        if not call.args:
            callee = self.expr(func)
            if isinstance(callee.kind, Hook):
                self.check(f"padt_call_any({callee.c})")
                return
        _refuse(f"a call of {ast.unparse(func)}", call)

    def if_statement(self, node: ast.If) -> None:
        test = self.condition(node.test)
        self.line(f"if ({test}) {{")
        self.depth += 1
        with self.refined(node.test):
            self.block(node.body)
        self.depth -= 1
        if node.orelse:
            self.line("} else {")
            self.depth += 1
            self.block(node.orelse)
            self.depth -= 1
        self.line("}")

    def while_loop(self, node: ast.While) -> None:
        loop = _Loop(self.label("next"), self.label("end"))
        otherwise = self.label("else")
        self.line("for (;;) {")
        self.depth += 1
        test = self.condition(node.test)
        self.line(f"if (!({test})) goto {otherwise};")
        self.loops.append(loop)
        self.block(node.body)
        self.loops.pop()
        self.line(f"{loop.next_label}:")
        self.breathe()
        self.depth -= 1
        self.line("}")
        self.line(f"{otherwise}:;")
        self.block(node.orelse)
        self.line(f"{loop.end_label}:;")

    def for_loop(self, node: ast.For) -> None:
        if not isinstance(node.target, ast.Name):
            _refuse("a loop that unpacks", node)
        if isinstance(node.iter, ast.Name) and isinstance(self.local_kind(node.iter.id), Range):
            kind = self.local_kind(node.iter.id)
            assert isinstance(kind, Range)
            local = self.local_ref(node.iter.id, node)
            start, stop = V(kind.start, f"{local}_start"), V(kind.stop, f"{local}_stop")
        elif isinstance(node.iter, ast.Call) and _called_name(node.iter) == "range":
            kind = self.range_kind(node.iter)
            start, stop = self.range_bounds(node.iter)
        else:
            _refuse("a loop over something else than a range", node)
        step = kind.step
        if not Int(kind.stop.lo - abs(step), kind.stop.hi + abs(step)).fits64:
            _refuse("a range that ends at the limits of 64 bits", node)
        # the loop variable takes every value of the range
        first, last = (
            (kind.start.lo, kind.stop.hi - 1) if step > 0 else (kind.stop.lo + 1, kind.start.hi)
        )
        counter_kind = Int(min(first, last), max(first, last))
        name = node.target.id
        self.note_assigned(name, counter_kind, node)
        local_kind = self.local_kind(name)
        loop = _Loop(self.label("next"), self.label("end"))
        counter = self.temp("int64_t")
        bound = self.temp("int64_t")
        self.line(f"{bound} = {stop.c};")
        relation = "<" if step > 0 else ">"
        self.line(
            f"for ({counter} = {start.c}; {counter} {relation} {bound}; {counter} += {step}) {{"
        )
        self.depth += 1
        if not isinstance(local_kind, Int):
            _refuse(f"loop variable {name} holds other values too", node)
        self.line(f"{self.local_ref(name, node)} = {counter};")
        self.loops.append(loop)
        self.block(node.body)
        self.loops.pop()
        self.line(f"{loop.next_label}:")
        self.breathe()
        self.depth -= 1
        self.line("}")
        self.block(node.orelse)
        self.line(f"{loop.end_label}:;")

    def breathe(self) -> None:
        self.line("if (PADT_UNLIKELY(--padt_breath == 0)) {")
        self.line("    padt_breath = PADT_BREATH;")
        self.line("    if (padt_breathe() < 0) goto padt_error;")
        self.line("}")

    def range_kind(self, call: ast.Call) -> Range:
        if call.keywords or len(call.args) != 3:
            _refuse("a range without start, stop and step", call)
        step = _constant_int(call.args[2])
        if not step:
            _refuse("a range with a step that is not a constant", call)
        start, stop = (self.expr_kind_int(arg) for arg in call.args[:2])
        return Range(start, stop, step)

    def expr_kind_int(self, node: ast.expr) -> Int:
        with self.captured():  # only the kind: the values are computed by range_bounds
            value = self.expr(node)
        if not isinstance(value.kind, Int) or not value.kind.fits64:
            _refuse("a range over values beyond 64 bits", node)
        return value.kind

    def range_bounds(self, call: ast.Call) -> tuple[V, V]:
        start, stop = (self.int_value(arg) for arg in call.args[:2])
        held_start = self.temp("int64_t")
        self.line(f"{held_start} = {start.c};")  # Python evaluates start before stop
        return V(start.kind, held_start), stop

    def int_value(self, node: ast.expr) -> V:
        value = self.expr(node)
        if isinstance(value.kind, Bool):
            return V(Int(0, 1), value.c)
        if not isinstance(value.kind, Int) or not value.kind.fits64:
            _refuse("an integer beyond 64 bits where 64 are needed", node)
        return value

    # -- conditions and refinements
    def condition(self, node: ast.expr) -> str:
        value = self.expr(node)
        if isinstance(value.kind, Bool):
            return value.c
        if isinstance(value.kind, Int):
            return f"({value.c}) != 0"
        if isinstance(value.kind, Float):
            return f"({value.c}) != 0.0"  # NaN is true, as in Python
        _refuse(f"a {_kind_name(value.kind)} as a condition", node)

    @contextlib.contextmanager
    def refined(self, test: ast.expr) -> Iterator[None]:
        """Within the true branch of `lo <= x <= hi` (x a local or a `:=` target), x is
        known to lie in lo..hi: an array offset proven in bounds needs no check."""
        found = _bounds_test(test)
        if found is None:
            yield
            return
        name, lo, hi = found
        current = self.named.get(name)
        if current is not None and isinstance(current.kind, Int):
            narrowed = _narrowed(current.kind, lo, hi)
            self.named[name] = V(narrowed, current.c)
            try:
                yield
            finally:
                self.named[name] = current
            return
        kind = self.narrowed.get(name) or self.local_kinds.get(name)
        if isinstance(kind, Int):
            saved = self.narrowed.get(name)
            self.narrowed[name] = _narrowed(kind, lo, hi)
            try:
                yield
            finally:
                if saved is None:
                    del self.narrowed[name]
                else:
                    self.narrowed[name] = saved
            return
        yield

    # -- expressions
    def expr(self, node: ast.expr) -> V:
        if isinstance(node, ast.Constant):
            return _constant(node)
        if isinstance(node, ast.Name):
            return self.name(node)
        if isinstance(node, ast.Attribute):
            return self.attribute(node)
        if isinstance(node, ast.Subscript):
            return self.subscript(node)
        if isinstance(node, ast.BinOp):
            return self.binary(node)
        if isinstance(node, ast.UnaryOp):
            return self.unary(node)
        if isinstance(node, ast.Compare):
            return self.compare(node)
        if isinstance(node, ast.BoolOp):
            return self.bool_op(node)
        if isinstance(node, ast.IfExp):
            return self.if_expr(node)
        if isinstance(node, ast.NamedExpr):
            value = self.expr(node.value)
            if not isinstance(value.kind, Int | Bool | Float):
                _refuse("a := of something else than a number", node)
            held = self.temp(_ctype(value.kind))
            self.line(f"{held} = {value.c};")
            self.named[node.target.id] = V(value.kind, held)
            return V(value.kind, held)
        if isinstance(node, ast.Call):
            return self.call_value(node)
        _refuse(f"a {type(node).__name__} expression", node)

    def name(self, node: ast.Name) -> V:
        name = node.id
        if name in self.named:
            return self.named[name]
        if name == "s":
            return V(Instance(self.cls.name), "s")
        if name == TICK.name:
            held = self.temp("PyObject *", "NULL")
            self.objects.remove(held)  # borrowed: the namespace holds it
            self.line(f"{held} = padt_global({self.module.key(TICK.name)});")
            self.line(f"if (PADT_UNLIKELY({held} == NULL)) goto padt_error;")
            return V(Hook(), held)
        if name == "_G":
            if self.module.globals_class is None:
                _refuse("_G without globals", node)
            self.uses_globals = True
            self.module.type_ref(self.module.globals_class)
            return V(Instance(self.module.globals_class), "padt_g")
        if name == "_SYS":
            return V(System(), "padt_sys")
        kind = self.local_kind(name)
        if kind is not None:
            local = self.local_ref(name, node)
            if isinstance(kind, Instance | Hook):
                self.line(f"if (PADT_UNLIKELY({local} == NULL)) goto padt_unbound;")
            narrowed = self.narrowed.get(name)
            return V(narrowed if narrowed is not None else kind, local)
        _refuse(f"the name {name}", node)

    def member_kind(self, owner: Instance, attr: str, node: ast.AST) -> Kind:
        info = self.module.classes.get(owner.cls)
        kind = info.members.get(attr) if info is not None else None
        if kind is None:
            _refuse(f"the variable {attr}, of a type the tier leaves to Python", node)
        return kind

    def attribute(self, node: ast.Attribute) -> V:
        owner = self.expr(node.value)
        if isinstance(owner.kind, Instance):
            kind = self.member_kind(owner.kind, node.attr, node)
            slot = f"PADT_SLOT({owner.c}, {self.module.offset(owner.kind.cls, node.attr)})"
            return self.unboxed(slot, kind, node.attr, node)
        if isinstance(owner.kind, System):
            if node.attr in SYSTEM_BOOLS:
                kind = Bool()
            elif node.attr in SYSTEM_INTS:
                kind = FULL64
            else:
                _refuse(f"_SYS.{node.attr}", node)
            held = self.temp("PyObject *", "NULL")
            key = self.module.key(node.attr)
            self.line(f"Py_XSETREF({held}, PyObject_GetAttr(padt_sys, {key}));")
            return self.unboxed(held, kind, f"_SYS.{node.attr}", node)
        if isinstance(owner.kind, Range) and node.attr in ("start", "stop"):
            bound = owner.kind.start if node.attr == "start" else owner.kind.stop
            return V(bound, f"{owner.c}_{node.attr}")
        _refuse(f"the attribute {node.attr} of a {_kind_name(owner.kind)}", node)

    def unboxed(self, obj: str, kind: Kind, what: str, node: ast.AST) -> V:
        """The value of a Python object that holds a `kind` (of type checked on the way in:
        a wrong one is a fault, `padt_bad`)."""
        if isinstance(kind, Int):
            held = self.temp("int64_t")
            small = Int(-(1 << 30) + 1, (1 << 30) - 1)
            macro = "PADT_GET_SMALL" if kind.within(small) else "PADT_GET_INT"
            self.line(f"{macro}({obj}, {held});")
            return V(kind, held)
        if isinstance(kind, Bool):
            held = self.temp("int")
            self.line(f"PADT_GET_BOOL({obj}, {held});")
            return V(kind, held)
        if isinstance(kind, Float):
            held = self.temp("double")
            self.line(f"PADT_GET_FLOAT({obj}, {held});")
            return V(kind, held)
        held = self.temp("PyObject *", "NULL")
        self.objects.remove(held)  # borrowed from the slot, which keeps it during the statement
        self.line(f"{held} = {obj};")
        if isinstance(kind, Instance):
            self.line(f"PADT_CHECK_INSTANCE({held}, {self.module.type_ref(kind.cls)});")
        elif isinstance(kind, Array):
            self.line(f"PADT_CHECK_LIST({held});")
        else:
            _refuse(f"a {_kind_name(kind)} read from {what}", node)
        return V(kind, held)

    def list_offset(self, array: V, index_node: ast.expr) -> str:
        index = self.int_value(index_node)
        offset = self.temp("Py_ssize_t")
        self.check(f"padt_index({array.c}, {index.c}, &{offset})")
        return offset

    def subscript(self, node: ast.Subscript) -> V:
        array = self.expr(node.value)
        if not isinstance(array.kind, Array) or array.kind.element is None:
            _refuse("an index into something else than an array the tier knows", node)
        offset = self.list_offset(array, node.slice)
        element = f"PyList_GET_ITEM({array.c}, {offset})"
        return self.unboxed(element, array.kind.element, "an array element", node)

    def binary(self, node: ast.BinOp) -> V:
        left, right = self.expr(node.left), self.expr(node.right)
        op = node.op
        if isinstance(left.kind, Bool) and isinstance(right.kind, Bool):
            symbol = {ast.BitAnd: "&", ast.BitOr: "|", ast.BitXor: "^"}.get(type(op))
            if symbol is not None:
                return V(Bool(), f"({left.c} {symbol} {right.c})")
        if isinstance(left.kind, Float) or isinstance(right.kind, Float):
            symbol = {ast.Add: "+", ast.Sub: "-", ast.Mult: "*"}.get(type(op))
            if symbol is None:
                _refuse(f"the operator {type(op).__name__} on a REAL", node)
            a, b = _as_float(left, node), _as_float(right, node)
            return V(Float(), f"({a.c} {symbol} {b.c})")
        a, b = _as_int(left, node), _as_int(right, node)
        assert isinstance(a.kind, Int) and isinstance(b.kind, Int)
        result = _result_range(op, a.kind, b.kind, node)
        if a.kind.stand_in or b.kind.stand_in:
            if isinstance(op, ast.RShift):
                _refuse("a shift right of a REAL's integer", node)
            masked = isinstance(op, ast.BitAnd) and result.lo >= 0 and result.hi < 1 << 64
            # a ring operation modulo 2**64 keeps the stand-in's congruence; a mask of at
            # most 64 bits takes it off: what is left is exact
            result = replace(result, stand_in=not masked)
        if not result.fits128:
            _refuse("an integer beyond 128 bits", node)
        # computed in the widest C type among the operands and the result, then narrowed to
        # the result's, which holds the value
        wide = (
            "padt_i128" if "padt_i128" in (a.kind.ctype, b.kind.ctype, result.ctype) else "int64_t"
        )
        x = a.c if a.kind.ctype == wide else f"(({wide}){a.c})"
        y = b.c if b.kind.ctype == wide else f"(({wide}){b.c})"
        if isinstance(op, ast.LShift):
            unsigned = "uint64_t" if wide == "int64_t" else "unsigned __int128"
            text = f"(({wide})(({unsigned}){x} << {b.c}))"
        elif isinstance(op, ast.RShift):
            width = 64 if wide == "int64_t" else 128
            if b.kind.hi >= width:
                text = f"({b.c} >= {width - 1} ? ({x} >> {width - 1}) : ({x} >> {b.c}))"
            else:
                text = f"({x} >> {b.c})"
        else:
            symbol = {
                ast.Add: "+", ast.Sub: "-", ast.Mult: "*", ast.BitAnd: "&", ast.BitOr: "|",
                ast.BitXor: "^",
            }[type(op)]  # fmt: skip
            text = f"({x} {symbol} {y})"
        return V(result, text if wide == result.ctype else f"(({result.ctype}){text})")

    def unary(self, node: ast.UnaryOp) -> V:
        value = self.expr(node.operand)
        if isinstance(node.op, ast.Not):
            if isinstance(value.kind, Bool):
                return V(Bool(), f"(!{value.c})")
            if isinstance(value.kind, Int):
                return V(Bool(), f"({value.c} == 0)")
            if isinstance(value.kind, Float):
                return V(Bool(), f"({value.c} == 0.0)")
            _refuse(f"not of a {_kind_name(value.kind)}", node)
        if isinstance(value.kind, Float):
            if isinstance(node.op, ast.USub):
                return V(Float(), f"(-{value.c})")
            if isinstance(node.op, ast.UAdd):
                return value
            _refuse("~ of a REAL", node)
        number = _as_int(value, node)
        assert isinstance(number.kind, Int)
        lo, hi = number.kind.lo, number.kind.hi
        if isinstance(node.op, ast.UAdd):
            return number
        negated = isinstance(node.op, ast.USub)
        result = Int(-hi, -lo) if negated else Int(-hi - 1, -lo - 1)
        result = replace(result, stand_in=number.kind.stand_in)
        if not result.fits128:
            _refuse("an integer beyond 128 bits", node)
        wide = "padt_i128" if "padt_i128" in (number.kind.ctype, result.ctype) else "int64_t"
        sign = "-" if isinstance(node.op, ast.USub) else "~"
        operand = number.c if number.kind.ctype == wide else f"(({wide}){number.c})"
        text = f"({sign}{operand})"
        return V(result, text if wide == result.ctype else f"(({result.ctype}){text})")

    def compare(self, node: ast.Compare) -> V:
        if len(node.ops) == 1 and isinstance(node.ops[0], ast.Is | ast.IsNot):
            return self.identity(node)
        left = self.comparable(self.expr(node.left), node)
        pairs = list(zip(node.ops, node.comparators, strict=True))
        op, right_node = pairs[0]
        right = self.comparable(self.expr(right_node), node)
        if len(pairs) == 1:
            return V(Bool(), _comparison(left, op, right, node))
        # `a < b < c`: b is evaluated once, c only while the comparisons before hold
        right = self.held(right)
        flag = self.temp("int")
        self.line(f"{flag} = {_comparison(left, op, right, node)};")
        self.compare_rest(flag, right, pairs[1:], node)
        return V(Bool(), flag)

    def held(self, value: V) -> V:
        """The value in a temporary, unless it is one already (or a constant)."""
        if value.c.isidentifier() or value.c.lstrip("-").isdigit():
            return value
        held = self.temp(_ctype(value.kind))
        self.line(f"{held} = {value.c};")
        return V(value.kind, held)

    def compare_rest(
        self, flag: str, left: V, rest: list[tuple[ast.cmpop, ast.expr]], node: ast.Compare
    ) -> None:
        for n, (op, right_node) in enumerate(rest):
            self.line(f"if ({flag}) {{")
            with self.captured() as lines:
                right = self.comparable(self.expr(right_node), node)
                if n < len(rest) - 1:
                    right = self.held(right)
                self.line(f"{flag} = {_comparison(left, op, right, node)};")
            self.out.extend(lines)
            self.line("}")
            left = right

    def comparable(self, value: V, node: ast.AST) -> V:
        if isinstance(value.kind, Int | Bool | Float):
            return value
        _refuse(f"a comparison of a {_kind_name(value.kind)}", node)

    def identity(self, node: ast.Compare) -> V:
        left, right = node.left, node.comparators[0]
        if not _is_none(right):
            _refuse("`is` with something else than None", node)
        value = self.expr(left)
        if not isinstance(value.kind, Hook):
            _refuse(f"`is None` of a {_kind_name(value.kind)}", node)
        symbol = "==" if isinstance(node.ops[0], ast.Is) else "!="
        return V(Bool(), f"({value.c} {symbol} Py_None)")

    def bool_op(self, node: ast.BoolOp) -> V:
        first = self.expr(node.values[0])
        if not isinstance(first.kind, Bool):
            _refuse("and/or of something else than BOOL", node)
        flag = self.temp("int")
        self.line(f"{flag} = {first.c};")
        is_and = isinstance(node.op, ast.And)
        for operand in node.values[1:]:
            self.line(f"if ({flag if is_and else '!' + flag}) {{")
            with self.captured() as lines:
                value = self.expr(operand)
                if not isinstance(value.kind, Bool):
                    _refuse("and/or of something else than BOOL", node)
                self.line(f"{flag} = {value.c};")
            self.out.extend(lines)
            self.line("}")
        return V(Bool(), flag)

    def if_expr(self, node: ast.IfExp) -> V:
        test = self.condition(node.test)
        with self.captured() as body_lines, self.refined(node.test):
            body = self.expr(node.body)
        with self.captured() as else_lines:
            orelse = self.expr(node.orelse)
        if isinstance(body.kind, Bool) and isinstance(orelse.kind, Bool):
            kind: Kind = Bool()
        elif isinstance(body.kind, Int) and isinstance(orelse.kind, Int):
            kind = join(body.kind, orelse.kind) or body.kind
        elif isinstance(body.kind, Float) and isinstance(orelse.kind, Float):
            kind = Float()
        else:
            _refuse("a conditional expression of two kinds", node)
        ctype = _ctype(kind)
        if not body_lines and not else_lines:
            return V(kind, f"({test} ? ({ctype}){body.c} : ({ctype}){orelse.c})")
        held = self.temp(ctype)
        self.line(f"if ({test}) {{")
        self.out.extend(body_lines)
        self.line(f"    {held} = {body.c};")
        self.line("} else {")
        self.out.extend(else_lines)
        self.line(f"    {held} = {orelse.c};")
        self.line("}")
        return V(kind, held)

    def call_value(self, node: ast.Call) -> V:
        name = _called_name(node)
        if name in self.module.functions:
            info, returned = self.function_call(node)
            if not isinstance(info.result, Int | Bool | Float):
                why = "a FUNCTION whose result the tier leaves to Python"
                _refuse(f"a call of {name}, {why}", node)
            return self.unboxed(returned, info.result, f"the result of {name}", node)
        if node.keywords:
            _refuse(f"a call of {ast.unparse(node.func)} with keywords", node)
        if name == IX.name and len(node.args) == len(IX.params):
            index = self.int_value(node.args[0])
            low, high = (_constant_int(arg) for arg in node.args[1:])
            if low is None or high is None:
                _refuse(f"{IX.name} with bounds that are not constants", node)
            held = self.temp("int64_t")
            self.line(f"if (PADT_LIKELY({low} <= {index.c} && {index.c} <= {high})) {{")
            self.line(f"    {held} = {index.c} - {c_int(low)};")
            self.line("} else {")
            raised = f'"{IX.name}", {len(IX.params)}, {index.c}, {c_int(low)}, {c_int(high)}'
            self.line(f"    padt_raise_through({raised});")
            self.line("    goto padt_error;")
            self.line("}")
            return V(Int(0, max(0, high - low)), held)
        if name in (IDIV.name, IMOD.name) and len(node.args) == len(IDIV.params):
            a, b = (self.int_value(arg) for arg in node.args)
            assert isinstance(a.kind, Int) and isinstance(b.kind, Int)
            top = max(abs(a.kind.lo), abs(a.kind.hi))
            if name == IMOD.name:  # smaller than the divisor
                top = min(top, max(0, max(abs(b.kind.lo), abs(b.kind.hi)) - 1))
            result = Int(-top, top)  # the smallest 64-bit integer / -1: 2**63, in 128 bits
            held = self.temp(result.ctype)
            helper = f"padt{name}" if result.fits64 else "padt_idiv128"  # padt_idiv, padt_imod
            self.check(f"{helper}({a.c}, {b.c}, &{held})")
            return V(result, held)
        if name in (F32.name, "float") and len(node.args) == 1:
            value = self.expr(node.args[0])
            number = _as_float(value, node)
            if name == "float":
                return number
            # REAL: rounded to 32 bits (an integer, as Python converts it: to a double first)
            return V(Float(), f"((double)(float){number.c})")
        if name in (ROUND.name, "int") and len(node.args) == 1:
            value = self.expr(node.args[0])
            if isinstance(value.kind, Float):
                held = self.temp("padt_i128")
                helper = "padt_round" if name == ROUND.name else "padt_trunc"
                self.check(f"{helper}({value.c}, &{held})")
                return V(FROM_REAL, held)
        if name == FDIV.name and len(node.args) == len(FDIV.params):
            a, b = (_as_float(self.expr(arg), node) for arg in node.args)
            return V(Float(), f"padt_fdiv({a.c}, {b.c})")
        if name == "abs" and len(node.args) == 1:
            value = self.expr(node.args[0])
            if isinstance(value.kind, Float):
                return V(Float(), f"fabs({value.c})")
            if isinstance(value.kind, Int) and not value.kind.stand_in:
                return self.absolute(self.held(value))
        if name in ("min", "max") and len(node.args) >= 2:
            return self.extreme(name, node)
        if name == "len" and len(node.args) == 1:
            target = self.expr(node.args[0])
            if isinstance(target.kind, Range):
                return self.range_length(target)
        _refuse(f"a call of {ast.unparse(node.func)}", node)

    def function_call(self, node: ast.Call) -> tuple[FunctionInfo, str]:
        """A FUNCTION of the artifact called as Python calls it, with the values boxed;
        the result in a temporary that owns it."""
        name = _called_name(node)
        assert name is not None
        info = self.module.functions[name]
        if info.outputs:
            _refuse(f"a call of {name}, a FUNCTION with VAR_OUTPUT or VAR_IN_OUT", node)
        if any(keyword.arg is None for keyword in node.keywords):
            _refuse(f"a call of {name} with ** arguments", node)
        values = [*node.args, *(keyword.value for keyword in node.keywords)]
        boxed: list[str] = []
        for value_node in values:
            value = self.expr(value_node)
            kind = value.kind
            if isinstance(kind, Int) and kind.fits64 and not kind.stand_in:
                box = f"PyLong_FromLongLong({value.c})"
            elif isinstance(kind, Bool):
                box = f"PADT_BOOL_OBJECT({value.c})"
            elif isinstance(kind, Float):
                box = f"PyFloat_FromDouble({value.c})"
            else:
                _refuse(f"an argument of {name} that holds a {_kind_name(kind)}", value_node)
            held = self.temp("PyObject *", "NULL")
            self.line(f"Py_XSETREF({held}, {box});")
            self.line(f"if (PADT_UNLIKELY({held} == NULL)) goto padt_error;")
            boxed.append(held)
        keywords = tuple(str(keyword.arg) for keyword in node.keywords)
        names = self.module.names(keywords) if keywords else "NULL"
        args = f"(PyObject *[]){{{', '.join(boxed)}}}" if boxed else "NULL"
        result = self.temp("PyObject *", "NULL")
        self.line(
            f"Py_XSETREF({result}, padt_call_function({self.module.key(name)}, {args}, "
            f"{len(node.args)}, {names}));"
        )
        self.line(f"if (PADT_UNLIKELY({result} == NULL)) goto padt_error;")
        return info, result

    def absolute(self, value: V) -> V:
        kind = value.kind
        assert isinstance(kind, Int)
        top = max(abs(kind.lo), abs(kind.hi))
        result = Int(0 if kind.lo <= 0 <= kind.hi else min(abs(kind.lo), abs(kind.hi)), top)
        wide = "padt_i128" if "padt_i128" in (kind.ctype, result.ctype) else "int64_t"
        x = value.c if kind.ctype == wide else f"(({wide}){value.c})"
        return V(result, f"(({result.ctype})({x} < 0 ? -{x} : {x}))")

    def extreme(self, name: str, node: ast.Call) -> V:
        """min() and max() of REALs or of integers, as Python takes them: the first
        argument, replaced by each later one that is smaller (larger); NaN as it does."""
        values = [self.held(self.expr(arg)) for arg in node.args]
        relation = "<" if name == "min" else ">"
        if all(isinstance(v.kind, Float) for v in values):
            kind: Kind = Float()
        elif all(_plain64(v.kind) for v in values):
            bounds = [v.kind for v in values if isinstance(v.kind, Int)]
            pick = min if name == "min" else max
            kind = Int(pick(k.lo for k in bounds), pick(k.hi for k in bounds))
        else:
            _refuse(f"{name}() of mixed or wide values", node)
        held = self.temp(_ctype(kind))
        self.line(f"{held} = {values[0].c};")
        for value in values[1:]:
            self.line(f"if ({value.c} {relation} {held}) {held} = {value.c};")
        return V(kind, held)

    def range_length(self, target: V) -> V:
        kind = target.kind
        assert isinstance(kind, Range)
        step = kind.step
        span = (
            f"({target.c}_stop - {target.c}_start)"
            if step > 0
            else f"({target.c}_start - {target.c}_stop)"
        )
        size = abs(step)
        most = max(
            0, (kind.stop.hi - kind.start.lo) if step > 0 else (kind.start.hi - kind.stop.lo)
        )
        held = self.temp("int64_t")
        self.line(f"{held} = {span} > 0 ? ({span} + {size - 1}) / {size} : 0;")
        return V(Int(0, (most + size - 1) // size), held)


# ---- helpers of expressions ----------------------------------------------------------------------


def _as_load(target: ast.expr) -> ast.expr:
    copied = ast.parse(ast.unparse(target), mode="eval").body
    return copied


def _is_none(node: ast.expr) -> bool:
    return isinstance(node, ast.Constant) and node.value is None


def _called_name(call: ast.Call) -> str | None:
    return call.func.id if isinstance(call.func, ast.Name) else None


def _constant(node: ast.Constant) -> V:
    value = node.value
    if isinstance(value, bool):
        return V(Bool(), "1" if value else "0")
    if isinstance(value, int):
        kind = Int(value, value)
        if not kind.fits128:
            _refuse("an integer constant beyond 128 bits", node)
        return V(kind, c_int(value))
    if isinstance(value, float) and math.isfinite(value):
        return V(Float(), f"({value.hex()})")  # exact: C99 reads hexadecimal doubles
    _refuse(f"a constant {type(value).__name__}", node)


def _constant_int(node: ast.expr) -> int | None:
    if isinstance(node, ast.Constant) and type(node.value) is int:
        return node.value
    if (
        isinstance(node, ast.UnaryOp)
        and isinstance(node.op, ast.USub)
        and isinstance(node.operand, ast.Constant)
        and type(node.operand.value) is int
    ):
        return -node.operand.value
    return None


def _bounds_test(test: ast.expr) -> tuple[str, int, int] | None:
    """`lo <= x <= hi` (also with `x := ...`, and `<`): the name and its inclusive bounds."""
    if not isinstance(test, ast.Compare) or len(test.ops) != 2:
        return None
    low, high = _constant_int(test.left), _constant_int(test.comparators[1])
    middle = test.comparators[0]
    if isinstance(middle, ast.NamedExpr):
        middle = middle.target
    if low is None or high is None or not isinstance(middle, ast.Name):
        return None
    first, second = test.ops
    if not isinstance(first, ast.LtE | ast.Lt) or not isinstance(second, ast.LtE | ast.Lt):
        return None
    low += isinstance(first, ast.Lt)
    high -= isinstance(second, ast.Lt)
    return middle.id, low, high


def _plain64(kind: Kind) -> bool:
    return isinstance(kind, Int) and kind.fits64 and not kind.stand_in


def _narrowed(kind: Int, lo: int, hi: int) -> Int:
    """`kind` known to lie in lo..hi: exact there when that is short of the stand-ins."""
    exact = lo > -STAND_IN_FROM and hi < STAND_IN_FROM
    return Int(max(lo, kind.lo), min(hi, kind.hi), kind.stand_in and not exact)


def _as_int(value: V, node: ast.AST) -> V:
    if isinstance(value.kind, Bool):
        return V(Int(0, 1), f"((int64_t){value.c})")
    if isinstance(value.kind, Int):
        return value
    _refuse(f"arithmetic on a {_kind_name(value.kind)}", node)


def _bits(kind: Int) -> int:
    """The smallest k with -2**k <= lo and hi < 2**k."""
    k = 0
    while not (-(1 << k) <= kind.lo and kind.hi < (1 << k)):
        k += 1
    return k


def _result_range(op: ast.operator, a: Int, b: Int, node: ast.AST) -> Int:
    if isinstance(op, ast.Add):
        return Int(a.lo + b.lo, a.hi + b.hi)
    if isinstance(op, ast.Sub):
        return Int(a.lo - b.hi, a.hi - b.lo)
    if isinstance(op, ast.Mult):
        products = (a.lo * b.lo, a.lo * b.hi, a.hi * b.lo, a.hi * b.hi)
        return Int(min(products), max(products))
    if isinstance(op, ast.BitAnd | ast.BitOr | ast.BitXor):
        if isinstance(op, ast.BitAnd) and (a.lo >= 0 or b.lo >= 0):
            highs = [k.hi for k in (a, b) if k.lo >= 0]
            return Int(0, min(highs))
        if a.lo >= 0 and b.lo >= 0:
            return Int(0, (1 << max(_bits(a), _bits(b))) - 1)
        k = max(_bits(a), _bits(b))
        return Int(-(1 << k), (1 << k) - 1)
    if isinstance(op, ast.LShift | ast.RShift):
        if b.lo < 0:
            _refuse("a shift by a count that may be negative", node)
        if isinstance(op, ast.RShift):
            return Int(min(a.lo, a.lo >> b.hi), max(a.hi >> b.hi, a.hi >> b.lo))
        if b.hi > 127:
            _refuse("a shift left by more than 127", node)
        ends = (a.lo << b.lo, a.lo << b.hi, a.hi << b.lo, a.hi << b.hi)
        return Int(min(ends), max(ends))
    _refuse(f"the operator {type(op).__name__}", node)


def _comparison(left: V, op: ast.cmpop, right: V, node: ast.AST) -> str:
    for one, other in ((left, right), (right, left)):
        # a stand-in is beyond 2**126 where the true value is: on the same side of any
        # 64-bit value, but not of another stand-in
        if (
            isinstance(one.kind, Int)
            and one.kind.stand_in
            and not (isinstance(other.kind, Bool) or _plain64(other.kind))
        ):
            _refuse("a REAL's integer compared with more than 64 bits", node)
    floats = isinstance(left.kind, Float) or isinstance(right.kind, Float)
    for side in (left, right):
        if floats and isinstance(side.kind, Int) and not side.kind.within(EXACT_IN_DOUBLE):
            # Python compares an integer with a REAL exactly; C would round it first
            _refuse("an integer beyond 2**53 compared with a REAL", node)
    return f"({left.c} {_relation(op, node)} {right.c})"


def _relation(op: ast.cmpop, node: ast.AST) -> str:
    symbol = _RELATIONS.get(type(op))
    if symbol is None:
        _refuse(f"a comparison {type(op).__name__}", node)
    return symbol


def _ctype(kind: Kind) -> str:
    if isinstance(kind, Int):
        return kind.ctype
    return "double" if isinstance(kind, Float) else "int"


def _as_float(value: V, node: ast.AST) -> V:
    """A number as Python turns it into a float: an integer is converted (exactly as C
    does within 64 bits: to the nearest double, ties to even)."""
    if isinstance(value.kind, Float):
        return value
    if isinstance(value.kind, Bool) or (isinstance(value.kind, Int) and value.kind.fits64):
        return V(Float(), f"((double){value.c})")
    _refuse(f"a {_kind_name(value.kind)} in REAL arithmetic", node)


def _kind_name(kind: Kind | None) -> str:
    return "kind the tier leaves to Python" if kind is None else type(kind).__name__


# ---- a unit --------------------------------------------------------------------------------------


def _translate_body(module: _Module, cls: ClassInfo, func: ast.FunctionDef) -> str:
    """The C function of one `__call__`; NotTranslated when it cannot be. The statics it
    needs join `module` only when it is translated."""
    args = func.args
    if [a.arg for a in args.args] != ["s"] or args.vararg or args.kwarg or args.kwonlyargs:
        _refuse("a body with arguments", func)
    _check_named_targets(func)
    kinds: dict[str, Kind] = {}
    for attempt in range(2 * WIDEN_AFTER + 2):
        trial = replace(
            module,
            types=dict(module.types),
            offsets=dict(module.offsets),
            keys=dict(module.keys),
        )
        body = _Body(trial, cls, func, kinds)
        body.body()
        merged = dict(kinds)
        for name, kind in body.assigned.items():
            known = merged.get(name)
            joined = kind if known is None else join(known, kind)
            if joined is None:
                _refuse(f"local {name} holds values of different kinds", func)
            if (
                attempt >= WIDEN_AFTER
                and isinstance(joined, Int)
                and joined != known
                and (known is None or (isinstance(known, Int) and known.within(FULL64)))
            ):
                # a local that still grows (a counter) takes the whole 64-bit range; a
                # value beyond it is refused at run time (padt_narrow)
                joined = FULL64
            merged[name] = joined
        if merged == kinds:
            module.types, module.offsets, module.keys = trial.types, trial.offsets, trial.keys
            module.sites = trial.sites
            return _function_text(body, func)
        kinds = merged
    _refuse("the kinds of the locals do not settle", func)


def _check_named_targets(func: ast.FunctionDef) -> None:
    """A `:=` target is kept in a temporary of its statement: refused when the body also
    assigns that name otherwise (its later reads would miss the value)."""
    targets = [node.target for node in ast.walk(func) if isinstance(node, ast.NamedExpr)]
    named = {target.id for target in targets}
    skipped = {id(target) for target in targets}
    assigned = {
        node.id
        for node in ast.walk(func)
        if isinstance(node, ast.Name)
        and isinstance(node.ctx, ast.Store)
        and id(node) not in skipped
    }
    both = named & assigned
    if both:
        _refuse(f"{sorted(both)[0]} both a := target and a local", func)


CHUNK_LINES = 300  # C lines per function: the compiler's time grows faster than their number
_TEMP = re.compile(r"\bt\d+\b")


def _chunks(body: _Body) -> list[list[str]]:
    """The body's lines cut between its statements into pieces of about CHUNK_LINES."""
    bounds = [*body.marks, len(body.out)]
    chunks: list[list[str]] = [[]]
    for start, end in itertools.pairwise(bounds):
        if chunks[-1] and len(chunks[-1]) + end - start > CHUNK_LINES:
            chunks.append([])
        chunks[-1].extend(body.out[start:end])
    return chunks


def _function_text(body: _Body, func: ast.FunctionDef) -> str:
    """The body as C: a function per chunk of statements (never inlined: one function of
    the whole body would take the compiler minutes), and the body's own, which calls them
    in turn. The Python locals are in a frame the chunks share."""
    name = _function_name(body.cls.name)
    module = body.module
    frame = [
        "typedef struct {",
        "    int line;",
        "    PyObject *g, *sys;",
        *(f"    {field}" for field in body.frame.values()),
        f"}} {name}_frame;",
        "",
    ]
    chunk_texts: list[str] = []
    chunk_names: list[str] = []
    for n, lines in enumerate(_chunks(body)):
        used = set(_TEMP.findall("\n".join(lines)))
        temps = [decl for temp, decl in body.decls.items() if temp in used]
        owned = [temp for temp in body.objects if temp in used]
        cleanup = [f"    Py_XDECREF({temp});" for temp in owned]
        chunk = f"{name}_{n}"
        chunk_names.append(chunk)
        chunk_texts.append(
            "\n".join(
                [
                    "static __attribute__((noinline)) int",
                    f"{chunk}(PyObject *s, {name}_frame *f)",
                    "{",
                    "    int padt_line = f->line;",
                    "    int padt_breath = PADT_BREATH;",
                    "    PyObject *padt_g = f->g, *padt_sys = f->sys;",
                    "    (void)padt_g; (void)padt_sys; (void)padt_breath;",
                    *(f"    {decl}" for decl in temps),
                    *lines,
                    *cleanup,
                    "    return 0;",
                    "padt_done:",
                    *cleanup,
                    "    return 1;",
                    "padt_unbound:",
                    '    PyErr_SetString(PyExc_UnboundLocalError, "native code: a local read before'
                    ' it is set");',
                    "    goto padt_error;",
                    "padt_bad:",
                    "    padt_bad_read();",
                    "padt_error:",
                    "    f->line = padt_line;",
                    *cleanup,
                    "    return -1;",
                    "}",
                    "",
                ]
            )
        )
    setup: list[str] = []
    if body.uses_globals:
        globals_type = module.types[module.globals_class or ""]
        setup += [
            f"    f->g = padt_global({module.key('_G')});",
            "    if (f->g == NULL) goto padt_error;",
            "    Py_INCREF(f->g);",
            f"    if (!PyObject_TypeCheck(f->g, (PyTypeObject *){globals_type})) {{",
            "        padt_bad_read();",
            "        goto padt_error;",
            "    }",
        ]
    if any("padt_sys" in line for line in body.out):
        setup += [
            f"    f->sys = padt_global({module.key('_SYS')});",
            "    if (f->sys == NULL) goto padt_error;",
            "    Py_INCREF(f->sys);",
        ]
    cleanup = [f"    Py_XDECREF(f->{field});" for field in ("g", "sys", *body.frame_objects)]
    main = [
        "static PyObject *",
        f"{name}(PyObject *s, PyObject *Py_UNUSED(ignored))",
        "{",
        f"    {name}_frame frame;",
        f"    {name}_frame *f = &frame;",
        "    int done = 0;",
        "    memset(f, 0, sizeof frame);",
        f"    f->line = {func.lineno};",
        *setup,
        *(f"    if ((done = {chunk}(s, f)) != 0) goto padt_end;" for chunk in chunk_names),
        "padt_end:",
        "    if (done < 0) goto padt_error;",
        *cleanup,
        "    Py_RETURN_NONE;",
        "padt_error:",
        f"    _PyTraceback_Add({c_string(body.cls.name + '.__call__')}, "
        f"{c_string(module.filename)}, f->line);",
        *cleanup,
        "    return NULL;",
        "}",
    ]
    return "\n".join([*frame, *chunk_texts, *main])


def _function_name(class_name: str) -> str:
    return f"F_{_identifier(class_name)}"


def translate_unit(
    unit: PouCode,
    classes: dict[str, ClassInfo],
    globals_class: str | None,
    functions: dict[str, FunctionInfo] | None = None,
) -> Translated:
    """The C module of one unit: every `__call__` of its classes that can be translated
    (calling the FUNCTIONs of `functions` as Python code)."""
    module = _Module(
        classes, code_filename(unit), globals_class=globals_class, functions=functions or {}
    )
    tree = ast.parse(unit.source)
    bodies: list[tuple[str, str]] = []  # (class name, C text)
    left: list[tuple[str, str]] = []
    for node in tree.body:
        if not isinstance(node, ast.ClassDef):
            continue
        for item in node.body:
            if not isinstance(item, ast.FunctionDef) or item.name != "__call__":
                continue
            body_name = f"{node.name}.__call__"
            info = classes.get(node.name)
            if info is None:
                left.append((body_name, "a class the artifact does not describe"))
                continue
            try:
                bodies.append((node.name, _translate_body(module, info, item)))
            except NotTranslated as reason:
                left.append((body_name, str(reason)))
            except RecursionError:
                left.append((body_name, "an expression nested too deep"))
    if not bodies:
        return Translated(unit.name, "", "", (), tuple(left))
    source = _module_text(module, bodies)
    digest = hashlib.sha256(source.encode()).hexdigest()[:24]
    name = f"padt_{digest}"
    return Translated(
        unit.name,
        name,
        source.replace(NAME_PLACEHOLDER, name),
        tuple(f"{cls}.__call__" for cls, _ in bodies),
        tuple(left),
    )


def _module_text(module: _Module, functions: list[tuple[str, str]]) -> str:
    types = [module.type_ref(cls) for cls, _ in functions]
    lines = [
        c_comment(f"native code of {module.filename}: written by runtime/code/native/translate.py"),
        '#include "padt_native.h"',
        "",
        *module.statics(),
        "",
    ]
    for _, text in functions:
        lines += [text, ""]
    for n, (cls, _) in enumerate(functions):
        # the C body on an instance of its class only (its slots' offsets): the Python body
        # on any other, a derived block's in its SUPER^() (padt_native.h, padt_python_body)
        lines += [
            "static PyObject *",
            f"W{n}(PyObject *s, PyObject *ignored)",
            "{",
            f"    if (PADT_LIKELY(PyObject_TypeCheck(s, (PyTypeObject *){types[n]})))",
            f"        return {_function_name(cls)}(s, ignored);",
            f"    return padt_python_body({types[n]}, s);",
            "}",
            "",
            f'static PyMethodDef M{n} = {{"__call__", (PyCFunction)W{n}, METH_NOARGS, NULL}};',
            "",
        ]
    lines += [
        "",
        "static PyObject *",
        "padt_bind(PyObject *module, PyObject *args)",
        "{",
        "    PyObject *ns, *breathe, *bodies;",
        '    if (!PyArg_ParseTuple(args, "OO", &ns, &breathe)) return NULL;',
        "    if (padt_bind_common(ns, breathe) < 0) return NULL;",
        *module.binding(),
        "    if ((bodies = PyDict_New()) == NULL) return NULL;",
    ]
    for n, (cls, _) in enumerate(functions):
        lines.append(
            f"    if (padt_add_method(bodies, {c_string(cls)}, &M{n}) < 0) "
            "{ Py_DECREF(bodies); return NULL; }"
        )
    lines += [
        "    return bodies;",
        "}",
        "",
        "static PyMethodDef padt_methods[] = {",
        '    {"bind", padt_bind, METH_VARARGS, NULL},',
        "    {NULL, NULL, 0, NULL},",
        "};",
        "",
        "static struct PyModuleDef padt_module = {",
        f'    PyModuleDef_HEAD_INIT, "{NAME_PLACEHOLDER}", NULL, -1, padt_methods,',
        "};",
        "",
        f"PyMODINIT_FUNC PyInit_{NAME_PLACEHOLDER}(void)",
        "{",
        "    return PyModule_Create(&padt_module);",
        "}",
        "",
    ]
    return "\n".join(lines)
