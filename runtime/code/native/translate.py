"""The typed form to C: the bodies (`__call__`) of the generated classes of one unit of an
artifact, as one C module that `runtime/code/native/tier.py` loads and binds.

The C is made from the unit's typed form (runtime/contract/code/), the nodes the Python
tier's code is printed from, and the Python code is the reference: a body is translated
only when every construct in it is one the translator knows and every integer it computes
provably fits the C type it is computed in (`runtime/code/native/kinds.py`); anything else
leaves the body to Python, with the reason. The C code works on the same objects as the
Python code (slots of the generated classes), so both tiers can run side by side and every
service of the runtime sees one kind of data. Image mode (image_body.py: the C of a body
on a memory image) is this translator with its own reads, stores and calls (`Mode`).
"""

from __future__ import annotations

import contextlib
import hashlib
import itertools
import math
import re
from collections.abc import Callable, Iterator
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
    Implementer,
    Instance,
    Int,
    Kind,
    Nothing,
    Outputs,
    Range,
    Ref,
    Results,
    Text,
    interface_key,
    join,
    kind_of_type,
)
from runtime.contract.artifact import PouCode
from runtime.contract.code.names import CLASS_NAME, MATH_FUNCTIONS, METHOD_NAME
from runtime.contract.code.python_text import printed_lines, python_text
from runtime.contract.code.statements import (
    Assign,
    Break,
    Continue,
    Elif,
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
    Named,
    Repeated,
    Sequence,
    Slice,
    This,
    Unary,
    Var,
    Wrap,
)
from runtime.contract.code.units import Class, Function, Unit
from runtime.contract.intrinsic_table import (
    COPY,
    DEREF,
    DEREF_SET,
    F32,
    FDIV,
    FILL,
    IDIV,
    IMOD,
    IX,
    MUX,
    POW,
    REF,
    ROL,
    ROR,
    ROUND,
    SAFE_MATH,
    TICK,
)
from runtime.contract.layout import Shape

NAME_PLACEHOLDER = "padt_unit"
WIDEN_AFTER = 3  # passes over a body before a growing local takes the whole 64-bit range
MAX_LIST = 1 << 24  # elements of a list a body makes afresh (a FUNCTION's local array)
_RELATIONS = frozenset({"==", "!=", "<", "<=", ">", ">="})
# the runtime's string functions called from C, by the kind of their result (an integer
# one only where its range is known: a position, a character's code)
_HELPER_RESULTS: dict[str, Kind] = {
    **dict.fromkeys(
        ("_left", "_right", "_mid", "_insert", "_delete", "_replace", "_w2s", "_s2w"), Text()
    ),
    **dict.fromkeys(("_real_to_str", "_time_to_str", "_date_to_str"), Text()),
    "_str_to_real": Float(),
    "_str_to_bool": Bool(),
    "_find": Int(0, INT64_MAX),
    "_ord": Int(0, 0x10FFFF),
    # integers of any size, which the compiler wraps to their type at once: read as a REAL's
    # integer is (Int.stand_in), exact within 2**126
    **dict.fromkeys(("_str_to_int", "_str_to_time", "_bcd_to_int", "_int_to_bcd"), FROM_REAL),
    "_setbits": FROM_REAL,
    # an SFC step's time: now less when it became active, both times of the clock (64 bits)
    "_step_time": FULL64,
}
# functions of the runtime's called as a statement, their result (None) dropped: an SFC step
# becoming active, an array or structure written whole into a variable, in place (`_fill`)
_HELPER_STATEMENTS = frozenset({"_step_enter", FILL.name})
# ULINT and LWORD, which C holds in a padt_i128
UNSIGNED64 = Int(0, (1 << 64) - 1)
# the operations whose result modulo 2**64 needs only the operands modulo 2**64 (`<<` by
# an exact count)
_RING_OPS = frozenset({"+", "-", "*", "&", "|", "^", "<<"})
_PY_OPS = {"==": "Py_EQ", "!=": "Py_NE", "<": "Py_LT", "<=": "Py_LE", ">": "Py_GT", ">=": "Py_GE"}
_BIT_OPS = frozenset({"&", "|", "^"})


class NotTranslated(Exception):
    """A body the tier leaves to Python; the message says why (and at which ST line, once
    the statement is known)."""

    def __init__(self, reason: str, st_line: int = 0) -> None:
        self.reason = reason
        super().__init__(f"{reason} (ST line {st_line})" if st_line else reason)


def _refuse(reason: str) -> NoReturn:
    raise NotTranslated(reason)


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
    """A value: its kind, and a C expression without side effects that yields it (in image
    mode, an array's is where it begins, and `shape` says how its elements lie)."""

    kind: Kind
    c: str
    shape: Shape | None = None
    # an array or instance `_copy` made: Python code given it may have one of its own (in
    # image mode a list of its values; without `_copy`, Python code would hold the place)
    copied: bool = False
    # of `Results`: the value of each item
    parts: tuple[V, ...] = ()


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
    here, runtime/contract/code/form_check.py; this holds whatever a name holds)."""
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
    function_sites: int = 0
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

    def function_site(self) -> str:
        """A call site of a FUNCTION of numbers and BOOLs."""
        self.function_sites += 1
        return f"FS{self.function_sites - 1}"

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
        lines += [f"static padt_fsite FS{n};" for n in range(self.function_sites)]
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
        lines += [f"    memset(&FS{n}, 0, sizeof FS{n});" for n in range(self.function_sites)]
        return lines


# ---- one body ------------------------------------------------------------------------------------


@dataclass
class _Loop:
    next_label: str  # where `continue` goes
    end_label: str  # where `break` goes


@dataclass(frozen=True)
class _Numbered:
    """A `__call__` with the line of the printed Python its header is on, and the lines of
    its statements' (and ELSIF branches') headers in the order they are printed: the C
    sets `padt_line` to them, so that a fault's traceback names the line a fault of the
    Python tier names, which `runtime/code/fault_location.py` maps to the ST line."""

    function: Function
    line: int
    headers: tuple[tuple[Stmt | Elif, int], ...]


def _numbered(form: Class | Function, function: Function) -> _Numbered:
    line, headers, inside = 0, [], False
    for number, printed in enumerate(printed_lines(form), start=1):
        if isinstance(printed.header, Function):
            inside = printed.header is function
            line = number if inside else line
        elif inside and printed.header is not None:
            headers.append((printed.header, number))
    return _Numbered(function, line, tuple(headers))


class _Body:
    """The translation of one `__call__`, given the kinds of its locals; `assigned` collects
    the kinds the body gives them, for the next pass."""

    context = "NULL"  # what a FUNCTION's C body is given as its context (image mode's)
    # a structure or an array is a Python object here, which a FUNCTION's C body on slots
    # takes and gives (native memory holds them as bytes: image_body.py)
    objects_direct = True

    def __init__(
        self, module: _Module, cls: ClassInfo, func: _Numbered, local_kinds: dict[str, Kind]
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
        self.named_targets: set[str] = set()  # every `:=` target of the body
        self.narrowed: dict[str, Int] = {}  # locals known to lie in a smaller range here
        self.loops: list[_Loop] = []
        self.labels = 0
        self.uses_globals = False
        self.headers = iter(func.headers)
        self.st_line = 0  # of the statement being translated: where a refusal is

    @property
    def qualname(self) -> str:
        """The function a fault's traceback names."""
        return f"{self.cls.name}.__call__"

    @property
    def c_name(self) -> str:
        """The C function of the body (its chunks and frame named after it)."""
        return _function_name(self.cls.name)

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

    def header(self, node: Stmt | Elif) -> None:
        """The statement (or branch) `node` begins: its printed line for a fault."""
        printed, number = next(self.headers)
        assert printed is node, "statements translated in another order than printed"
        self.named = {}
        self.st_line = node.line or self.st_line
        self.line(f"padt_line = {number};")

    # -- statements
    def body(self) -> None:
        for statement in self.func.function.body:
            self.marks.append(len(self.out))
            self.statement(statement)
        self.st_line = 0  # of the whole body
        both = self.named_targets & self.assigned.keys()
        if both:
            # a `:=` target is kept in a temporary of its statement: a name the body also
            # assigns otherwise would miss the value in its later reads
            _refuse(f"{sorted(both)[0]} both a := target and a local")

    def block(self, statements: tuple[Stmt, ...]) -> None:
        for statement in statements:
            self.statement(statement)

    def statement(self, node: Stmt) -> None:
        self.header(node)
        match node:
            case Assign(target=target, value=value, augmented=op):
                if op is not None:
                    value = Binary(op, target, value, "")
                self.assign(target, value)
            case Evaluate(value=value):
                self.call_statement(value)
            case If():
                self.if_statement(node)
            case While():
                self.while_loop(node)
            case ForEach():
                self.for_loop(node)
            case Break() | Continue():
                if not self.loops:
                    _refuse("break outside a loop")
                loop = self.loops[-1]
                self.line(f"goto {loop.end_label if isinstance(node, Break) else loop.next_label};")
            case Return(value=value):
                self.returned(value)
                self.line("goto padt_done;")
            case Pass():
                pass

    def returned(self, value: Expr | None) -> None:
        """What a `return` gives back (a `__call__` gives nothing)."""
        if value is not None and not _is_none(value):
            _refuse("a body that returns a value")

    def assign(self, target: Expr, value_node: Expr) -> None:
        if isinstance(target, Var) and target.where == "local":
            self.assign_local(target.name, value_node)
            return
        value = self.null() if _is_none(value_node) else self.expr(value_node)
        if isinstance(target, Var | Member):
            owner = self.owner(target)
            if not isinstance(owner.kind, Instance):
                _refuse("a store into something else than a generated object")
            self.store_member(owner, target.name, value)
        elif isinstance(target, Index):
            self.store_element(self.expr(target.base), target.offset, value)
        else:
            _refuse(f"a store into a {type(target).__name__}")

    def store_member(self, owner: V, attr: str, value: V) -> None:
        """`value` into the variable `attr` of the instance `owner`."""
        assert isinstance(owner.kind, Instance)
        member = self.member_kind(owner.kind, attr)
        place = f"PADT_PLACE({owner.c}, {self.module.offset(owner.kind.cls, attr)})"
        self.store(place, value, member, f"{owner.kind.cls}.{attr}")

    def store_element(self, array: V, index_node: Expr, value: V) -> None:
        """`value` into the element at offset `index_node` of `array`."""
        if not isinstance(array.kind, Array) or array.kind.element is None:
            _refuse("a store into something else than an array of elementary values")
        offset = self.list_offset(array, index_node)
        place = f"PADT_ITEM_PLACE({array.c}, {offset})"
        self.store(place, value, array.kind.element, "an array element")

    def store(self, place: str, value: V, declared: Kind | None, what: str) -> None:
        """`value` into a slot or list item of a variable of `declared`, as Python holds it."""
        if isinstance(declared, Bool) and isinstance(value.kind, Bool):
            self.line(f"padt_set_bool({place}, {value.c});")
            return
        if isinstance(declared, Float) and isinstance(value.kind, Float):
            self.check(f"padt_set_float({place}, {value.c})")
            return
        if isinstance(declared, Int) and isinstance(value.kind, Int):
            self.storable(value, declared, what)
            setter = "padt_set_int" if value.kind.fits64 else "padt_set_int128"
            self.check(f"{setter}({place}, {value.c})")
            return
        if isinstance(declared, Ref) and value.kind == Ref(None) and value.c == "Py_None":
            self.check(f"padt_put({place}, Py_NewRef(Py_None))")  # NULL, REF= 0
            return
        if (
            isinstance(declared, Ref)
            and isinstance(declared.target, Implementer)
            and isinstance(value.kind, Ref)
        ):
            # a reference to an instance into an interface variable (the compiler checked
            # that its class conforms): the place takes the reference, as Python's store
            self.check(f"padt_put({place}, Py_NewRef({value.c}))")
            return
        if isinstance(declared, Instance | Array | Text | Ref) and value.kind == declared:
            # a text, a whole array or structure (a copy): the place takes the object as
            # Python's store does
            self.check(f"padt_put({place}, Py_NewRef({value.c}))")
            return
        _refuse(f"a {_kind_name(value.kind)} stored into {_kind_name(declared)}")

    def storable(self, value: V, declared: Int, what: str) -> None:
        """An integer about to be stored into a variable of `declared`: a fault where it is
        outside its range (the contract says it is not; checked where not proven)."""
        assert isinstance(value.kind, Int)
        if value.kind.stand_in:
            _refuse("a REAL's integer stored without a wrap")
        if not value.kind.within(declared):
            self.check(
                f"padt_in_range((padt_i128)({value.c}), {c_int(declared.lo)}, "
                f"{c_int(declared.hi)}, {c_string(what)})"
            )

    def assign_local(self, name: str, value_node: Expr) -> None:
        if name == "s" or (name.startswith("_") and not name.startswith("__")):
            _refuse(f"an assignment to {name}")
        if isinstance(value_node, Call) and value_node.callee == "range":
            kind: Kind = self.range_kind(value_node)
            self.note_assigned(name, kind)
            start, stop = self.range_bounds(value_node)
            local = self.local_ref(name)
            self.line(f"{local}_start = {start.c}; {local}_stop = {stop.c};")
            return
        value = self.expr(value_node)
        if isinstance(value.kind, Int) and value.kind.stand_in:
            _refuse("a REAL's integer kept in a local")
        self.note_assigned(name, value.kind)
        local_kind = self.local_kind(name)
        local = self.local_ref(name)
        if isinstance(local_kind, Int) and isinstance(value.kind, Int):
            if value.kind.fits64 or not local_kind.fits64:
                self.line(f"{local} = {value.c};")
            else:
                self.check(f"padt_narrow({value.c}, &{local})")
        elif isinstance(local_kind, Bool | Float) and value.kind == local_kind:
            self.line(f"{local} = {value.c};")
        elif isinstance(local_kind, Results) and value.kind == local_kind:
            for n, part in enumerate(value.parts):
                if _is_object(part.kind):
                    self.keep(f"{local}_{n}", part)
                else:
                    self.line(f"{local}_{n} = {part.c};")
        elif isinstance(local_kind, Instance | Outputs | Hook | Text | Array) and (
            value.kind == local_kind
        ):
            self.keep(local, value)
        else:
            _refuse(f"local {name} takes a {_kind_name(value.kind)}")

    def keep(self, local: str, value: V) -> None:
        """An instance, a text, a FUNCTION's outputs or a hook into a local of the frame."""
        self.line(f"Py_XSETREF({local}, Py_NewRef({value.c}));")

    def note_assigned(self, name: str, kind: Kind) -> None:
        known = self.assigned.get(name)
        joined = kind if known is None else join(known, kind)
        if joined is None:
            _refuse(f"local {name} holds values of different kinds")
        self.assigned[name] = joined

    def local_kind(self, name: str) -> Kind | None:
        """The kind of a local: as the passes before found it, else as this pass has so far."""
        return self.local_kinds.get(name) or self.assigned.get(name)

    def local_ref(self, name: str) -> str:
        """The C variable of a Python local (declared once)."""
        kind = self.local_kind(name)
        if kind is None:
            _refuse(f"local {name} is read before it is assigned")
        c = f"l_{_identifier(name)}"
        if c not in self.frame:
            if isinstance(kind, Int):
                self.frame[c] = f"{kind.ctype} {c};"
            elif isinstance(kind, Bool):
                self.frame[c] = f"int {c};"
            elif isinstance(kind, Float):
                self.frame[c] = f"double {c};"
            elif isinstance(kind, Instance | Outputs | Hook | Text | Array):
                self.frame[c] = f"PyObject *{c};"
                self.frame_objects.append(c)
            elif isinstance(kind, Range):
                self.frame[c] = f"int64_t {c}_start, {c}_stop;"
            elif isinstance(kind, Results):
                items = list(enumerate(kind.items))
                self.frame[c] = " ".join(f"{_ctype(item)} {c}_{n};" for n, item in items)
                self.frame_objects += [f"{c}_{n}" for n, item in items if _is_object(item)]
            else:
                _refuse(f"local {name} holds a {_kind_name(kind)}")
        return f"f->{c}"

    def call_statement(self, call: Expr) -> None:
        if isinstance(call, Index):  # `t[0]`: a call's unused result, read and dropped
            self.expr(call)
            return
        if isinstance(call, Call) and call.callee == DEREF_SET.name and len(call.args) == 2:
            held, value = (self.expr(arg) for arg in call.args)
            if not isinstance(held.kind, Ref) or held.kind.target is None:
                _refuse(f"{DEREF_SET.name} of a {_kind_name(held.kind)}")
            if value.kind != held.kind.target and not (
                isinstance(value.kind, Int) and isinstance(held.kind.target, Int)
            ):
                _refuse(f"a {_kind_name(value.kind)} written through a reference")
            args = [held.c, self.boxed(value, DEREF_SET.name)]
            self.owned_object(_vector_call(self.module.key(DEREF_SET.name), args))
            return
        if not isinstance(call, Call):
            _refuse("an expression statement that is no call")
        if self.direct_call(call) is not None:
            return  # what it gives dropped
        if (
            isinstance(call.callee, str) and call.callee in self.module.functions
        ) or self.is_method_call(call):
            self.function_call(call)  # its result, if any, dropped at the chunk's end
            return
        if call.keywords:
            _refuse("an expression statement that is no call")
        callee = call.callee
        if isinstance(callee, str) and callee in _HELPER_STATEMENTS:
            self.helper_statement(callee, call)
            return
        if isinstance(callee, Member) and callee.name == "__call__" and not call.args:
            target = self.expr(callee.base)
            if not isinstance(target.kind, Instance):
                _refuse("a call of something else than a generated object")
            self.call_instance(target)
            return
        if not isinstance(callee, str) and not call.args:
            hook = self.expr(callee)
            if isinstance(hook.kind, Hook):
                self.call_hook(hook)
                return
        _refuse(f"a call of {_callee_text(call)}")

    def helper_statement(self, callee: str, call: Call) -> None:
        """A function of the runtime's called for what it does (`_step_enter`)."""
        args = [self.boxed(self.expr(arg), callee) for arg in call.args]
        self.owned_object(_vector_call(self.module.key(callee), args))

    def call_hook(self, hook: V) -> None:
        """`t()` of a hook (`_tick`: the slice meter, which may suspend the program)."""
        self.check(f"padt_call_any({hook.c})")

    def call_instance(self, target: V) -> None:
        """The body of the instance `target` (a block's call)."""
        self.check(f"padt_call({target.c}, &{self.module.site()})")

    def if_statement(self, node: If) -> None:
        """IF with its ELSIFs, each nested in the ELSE of the one before, as Python runs
        them."""
        self.branch(node.test, node.body)
        for branch in node.elifs:
            self.line("} else {")
            self.depth += 1
            self.header(branch)
            self.branch(branch.test, branch.body)
        if node.orelse:
            self.line("} else {")
            self.depth += 1
            self.block(node.orelse)
            self.depth -= 1
        for _ in node.elifs:
            self.line("}")
            self.depth -= 1
        self.line("}")

    def branch(self, test: Expr, body: tuple[Stmt, ...]) -> None:
        """`if (test) {` and the body, within the test's refinement; left open."""
        self.line(f"if ({self.condition(test)}) {{")
        self.depth += 1
        with self.refined(test):
            self.block(body)
        self.depth -= 1

    def while_loop(self, node: While) -> None:
        loop = _Loop(self.label("next"), self.label("end"))
        self.line("for (;;) {")
        self.depth += 1
        test = self.condition(node.test)
        self.line(f"if (!({test})) goto {loop.end_label};")
        self.loops.append(loop)
        self.block(node.body)
        self.loops.pop()
        self.line(f"{loop.next_label}:")
        self.breathe()
        self.depth -= 1
        self.line("}")
        self.line(f"{loop.end_label}:;")

    def for_loop(self, node: ForEach) -> None:
        numbers = node.numbers
        if isinstance(numbers, Var) and isinstance(self.local_kind(numbers.name), Range):
            kind = self.local_kind(numbers.name)
            assert isinstance(kind, Range)
            local = self.local_ref(numbers.name)
            start, stop = V(kind.start, f"{local}_start"), V(kind.stop, f"{local}_stop")
        elif isinstance(numbers, Call) and numbers.callee == "range":
            kind = self.range_kind(numbers)
            start, stop = self.range_bounds(numbers)
        else:
            _refuse("a loop over something else than a range")
        step = kind.step
        if not Int(kind.stop.lo - abs(step), kind.stop.hi + abs(step)).fits64:
            _refuse("a range that ends at the limits of 64 bits")
        # the loop variable takes every value of the range
        first, last = (
            (kind.start.lo, kind.stop.hi - 1) if step > 0 else (kind.stop.lo + 1, kind.start.hi)
        )
        counter_kind = Int(min(first, last), max(first, last))
        name = node.name
        self.note_assigned(name, counter_kind)
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
            _refuse(f"loop variable {name} holds other values too")
        self.line(f"{self.local_ref(name)} = {counter};")
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

    def range_kind(self, call: Call) -> Range:
        if call.keywords or len(call.args) != 3:
            _refuse("a range without start, stop and step")
        step = _constant_int(call.args[2])
        if not step:
            _refuse("a range with a step that is not a constant")
        start, stop = (self.expr_kind_int(arg) for arg in call.args[:2])
        return Range(start, stop, step)

    def expr_kind_int(self, node: Expr) -> Int:
        with self.captured():  # only the kind: the values are computed by range_bounds
            value = self.expr(node)
        if not isinstance(value.kind, Int) or not value.kind.fits64:
            _refuse("a range over values beyond 64 bits")
        return value.kind

    def range_bounds(self, call: Call) -> tuple[V, V]:
        start, stop = (self.int_value(arg) for arg in call.args[:2])
        held_start = self.temp("int64_t")
        self.line(f"{held_start} = {start.c};")  # Python evaluates start before stop
        return V(start.kind, held_start), stop

    def division_operand(self, node: Expr) -> V:
        """An operand of integer division or MOD: an exact integer of up to 128 bits (a
        ULINT's in a padt_i128)."""
        value = self.expr(node)
        if isinstance(value.kind, Bool):
            return V(Int(0, 1), value.c)
        if not isinstance(value.kind, Int) or value.kind.stand_in or not value.kind.fits128:
            _refuse(f"an integer division of a {_kind_name(value.kind)} not exact in 128 bits")
        return value

    def int_value(self, node: Expr) -> V:
        value = self.expr(node)
        if isinstance(value.kind, Bool):
            return V(Int(0, 1), value.c)
        if not isinstance(value.kind, Int) or not value.kind.fits64:
            _refuse("an integer beyond 64 bits where 64 are needed")
        return value

    # -- conditions and refinements
    def condition(self, node: Expr) -> str:
        value = self.expr(node)
        if isinstance(value.kind, Bool):
            return value.c
        if isinstance(value.kind, Int):
            return f"({value.c}) != 0"
        if isinstance(value.kind, Float):
            return f"({value.c}) != 0.0"  # NaN is true, as in Python
        _refuse(f"a {_kind_name(value.kind)} as a condition")

    @contextlib.contextmanager
    def refined(self, test: Expr) -> Iterator[None]:
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
    def expr(self, node: Expr) -> V:
        match node:
            case Const(value=str() as text):
                return self.text_constant(text)
            case Const():
                return _constant(node)
            case Var(where="local", name=name):
                return self.local_value(name)
            case Var(where="system", name=name):
                return self.system_value(name)
            case Var() | Member():
                owner = self.owner(node)
                if isinstance(owner.kind, Range) and node.name in ("start", "stop"):
                    bound = owner.kind.start if node.name == "start" else owner.kind.stop
                    return V(bound, f"{owner.c}_{node.name}")
                if not isinstance(owner.kind, Instance):
                    _refuse(f"the attribute {node.name} of a {_kind_name(owner.kind)}")
                return self.member_value(owner, node.name)
            case This():
                return V(Instance(self.cls.name), "s")
            case Named(name=name) if name == TICK.name:
                held = self.temp("PyObject *", "NULL")
                self.objects.remove(held)  # borrowed: the namespace holds it
                self.line(f"{held} = {self.tick_read(self.module.key(TICK.name))};")
                self.line(f"if (PADT_UNLIKELY({held} == NULL)) goto padt_error;")
                return V(Hook(), held)
            case Index():
                return self.subscript(node)
            case Binary(op=op) if op in _RELATIONS:
                return self.compare(op, (node.left, node.right))
            case Binary(op="is" | "is not"):
                return self.identity(node)
            case Binary(op="+", left=Sequence() | Repeated(), right=Sequence() | Repeated()):
                return self.joined_lists(node)
            case Binary():
                return self.binary(node.op, self.expr(node.left), self.expr(node.right))
            case Unary():
                return self.unary(node)
            case Chain(op=op, values=values):
                return self.compare(op, values)
            case Logic():
                return self.logic(node)
            case Choice():
                return self.choice(node)
            case Assigned(name=name, value=value_node):
                value = self.expr(value_node)
                if not isinstance(value.kind, Int | Bool | Float):
                    _refuse("a := of something else than a number")
                held = self.temp(_ctype(value.kind))
                self.line(f"{held} = {value.c};")
                self.named[name] = V(value.kind, held)
                self.named_targets.add(name)
                return V(value.kind, held)
            case Wrap():
                return self.wrap(node)
            case Call():
                return self.call_value(node)
            case Slice(start=None, stop=int() as stop):
                return self.cut(self.expr(node.value), stop)
            case Sequence(as_tuple=False, items=items) if items:
                return self.list_literal(items, node.type)
            case Repeated(each_new=False, count=count) if 0 < count <= MAX_LIST:
                return self.repeated(node.item, count, node.type)
        _refuse(f"a {type(node).__name__} expression ({python_text(node)})")

    def list_literal(self, items: tuple[Expr, ...], declared: str) -> V:
        """`[a, b, ...]`: an array's values (a FUNCTION's constant array), a new list of the
        values boxed, each evaluated in turn as Python does."""
        values = [self.expr(item) for item in items]
        kind = self.list_kind(declared, len(values), [value.kind for value in values])
        boxed = [self.boxed(value, "a list") for value in values]  # each before the list
        made = self.owned_object(f"PyList_New({len(values)})")
        for n, item in enumerate(boxed):
            self.line(f"PyList_SET_ITEM({made}, {n}, Py_NewRef({item}));")
        return V(kind, made)

    def repeated(self, item: Expr, count: int, declared: str) -> V:
        """`[v] * n`: an array at its initial value, a new list of `count` times the value
        (one object, as Python's)."""
        value = self.expr(item)
        kind = self.list_kind(declared, count, [value.kind])
        boxed = self.boxed(value, "a list")
        made = self.owned_object(f"PyList_New({count})")
        n = self.temp("Py_ssize_t")
        self.line(f"for ({n} = 0; {n} < {count}; {n}++)")
        self.line(f"    PyList_SET_ITEM({made}, {n}, Py_NewRef({boxed}));")
        return V(kind, made)

    def joined_lists(self, node: Binary) -> V:
        """`[a, b] + [0] * n`: an array's values, those not given at their initial value."""
        left, right = self.expr(node.left), self.expr(node.right)
        assert isinstance(left.kind, Array) and isinstance(right.kind, Array)
        kinds = [kind for kind in (left.kind.element, right.kind.element) if kind is not None]
        length = left.kind.length + right.kind.length
        kind = self.list_kind(node.type, length, kinds)
        return V(kind, self.owned_object(f"PySequence_Concat({left.c}, {right.c})"))

    def list_kind(self, declared: str, length: int, kinds: list[Kind]) -> Array:
        """The kind of a list of `length` values of `kinds`: its declared array type's
        where each value fits its element (so that it is the kind of a variable or a
        parameter of that type), else the values' own."""
        kind = kind_of_type(declared, {}) if declared else None
        if (
            isinstance(kind, Array)
            and kind.length == length
            and isinstance(kind.element, Int | Bool | Float | Text)
            and all(_fits(found, kind.element) for found in kinds)
        ):
            return kind
        element = kinds[0]
        for found in kinds[1:]:
            joined = join(element, found)
            if joined is None:
                _refuse("a list of values of different kinds")
            element = joined
        if not isinstance(element, Int | Bool | Float | Text):
            _refuse(f"a list of {_kind_name(element)}")
        return Array(element, length)

    def member_value(self, owner: V, attr: str) -> V:
        """The value of the variable `attr` of the instance `owner`."""
        assert isinstance(owner.kind, Instance)
        kind = self.member_kind(owner.kind, attr)
        slot = f"PADT_SLOT({owner.c}, {self.module.offset(owner.kind.cls, attr)})"
        return self.unboxed(slot, kind, attr)

    def local_value(self, name: str) -> V:
        if name in self.named:
            return self.named[name]
        kind = self.local_kind(name)
        if kind is None:
            _refuse(f"the name {name}")
        local = self.local_ref(name)
        if isinstance(kind, Results):
            parts = tuple(V(item, f"{local}_{n}") for n, item in enumerate(kind.items))
            return V(kind, local, parts=parts)
        if isinstance(kind, Instance | Outputs | Hook | Text | Array):
            self.line(f"if (PADT_UNLIKELY({local} == NULL)) goto padt_unbound;")
        narrowed = self.narrowed.get(name)
        return V(narrowed if narrowed is not None else kind, local)

    def owner(self, node: Var | Member) -> V:
        """What holds the variable or member `node`: the instance, the globals, an object."""
        if isinstance(node, Member):
            return self.expr(node.base)
        if node.where == "instance":
            return V(Instance(self.cls.name), "s")
        if node.where == "globals":
            if self.module.globals_class is None:
                _refuse("_G without globals")
            self.uses_globals = True
            self.module.type_ref(self.module.globals_class)
            return V(Instance(self.module.globals_class), "padt_g")
        _refuse(f"a variable of {node.where}")

    def tick_read(self, key: str) -> str:
        """The C that reads `_tick` (borrowed; NULL: an error), before a loop."""
        return f"padt_global({key})"

    def system_value(self, name: str) -> V:
        if name in SYSTEM_BOOLS:
            kind: Kind = Bool()
        elif name in SYSTEM_INTS:
            kind = FULL64
        else:
            _refuse(f"_SYS.{name}")
        held = self.temp("PyObject *", "NULL")
        key = self.module.key(name)
        self.line(f"Py_XSETREF({held}, PyObject_GetAttr(padt_sys, {key}));")
        return self.unboxed(held, kind, f"_SYS.{name}")

    def member_kind(self, owner: Instance, attr: str) -> Kind:
        info = self.module.classes.get(owner.cls)
        kind = info.members.get(attr) if info is not None else None
        if kind is None:
            _refuse(f"the variable {attr}, of a type the tier leaves to Python")
        return kind

    def unboxed(self, obj: str, kind: Kind, what: str) -> V:
        """The value of a Python object that holds a `kind` (of type checked on the way in:
        a wrong one is a fault, `padt_bad`)."""
        if isinstance(kind, Int) and kind.stand_in:  # an integer of any size
            held = self.temp("padt_i128")
            self.line(f"if (PADT_UNLIKELY(!PyLong_Check({obj}))) goto padt_bad;")
            self.check(f"padt_any_int({obj}, &{held})")
            return V(kind, held)
        if isinstance(kind, Int) and not kind.fits64:
            if not kind.within(UNSIGNED64):
                _refuse(f"an integer beyond 64 bits of another range than ULINT's read from {what}")
            held = self.temp("padt_i128")
            self.line(f"PADT_GET_U64({obj}, {held});")  # ULINT, LWORD
            return V(kind, held)
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
        if isinstance(kind, Implementer):  # any object: its methods are looked up on it
            return V(kind, obj)
        held = self.temp("PyObject *", "NULL")
        if isinstance(kind, Text | Ref):
            # owned: a FUNCTION called later in the statement may store another text into
            # a global's slot, which then frees this one
            self.line(f"Py_XSETREF({held}, Py_XNewRef({obj}));")
            check = "PADT_CHECK_TEXT" if isinstance(kind, Text) else "PADT_CHECK_REF"
            self.line(f"{check}({held});")
            return V(kind, held)
        self.objects.remove(held)  # borrowed from the slot, which keeps it during the statement
        self.line(f"{held} = {obj};")
        if isinstance(kind, Instance):
            self.line(f"PADT_CHECK_INSTANCE({held}, {self.module.type_ref(kind.cls)});")
        elif isinstance(kind, Array):
            self.line(f"PADT_CHECK_LIST({held});")
        else:
            _refuse(f"a {_kind_name(kind)} read from {what}")
        return V(kind, held)

    def list_offset(self, array: V, index_node: Expr) -> str:
        index = self.int_value(index_node)
        offset = self.temp("Py_ssize_t")
        self.check(f"padt_index({array.c}, {index.c}, &{offset})")
        return offset

    def subscript(self, node: Index) -> V:
        array = self.expr(node.base)
        if isinstance(array.kind, Results):  # `t[k]` of a call of a FUNCTION's C body
            k = _constant_int(node.offset)
            if k is None or not 0 <= k < len(array.parts):
                _refuse("an item of a FUNCTION's outputs at an offset not a constant of them")
            return array.parts[k]
        if isinstance(array.kind, Outputs):  # `t[k]`: the result or an output of a call
            k = _constant_int(node.offset)
            if k is None or not 0 <= k < len(array.kind.items):
                _refuse("an item of a FUNCTION's outputs at an offset not a constant of them")
            item = array.kind.items[k]
            if isinstance(item, Nothing):  # the result of a call without one: dropped
                return V(item, "0")
            if item is None:
                _refuse("an output of a FUNCTION of a type the tier leaves to Python")
            return self.unboxed(f"PyTuple_GET_ITEM({array.c}, {k})", item, "an output")
        if not isinstance(array.kind, Array) or array.kind.element is None:
            _refuse("an index into something else than an array the tier knows")
        offset = self.list_offset(array, node.offset)
        element = f"PyList_GET_ITEM({array.c}, {offset})"
        return self.unboxed(element, array.kind.element, "an array element")

    def binary(self, op: str, left: V, right: V) -> V:
        if isinstance(left.kind, Text) or isinstance(right.kind, Text):
            if op != "+" or left.kind != right.kind:
                _refuse(
                    f"the operator {op} on a {_kind_name(left.kind)} and a {_kind_name(right.kind)}"
                )
            return self.owned(Text(), f"PyUnicode_Concat({left.c}, {right.c})")
        if isinstance(left.kind, Bool) and isinstance(right.kind, Bool) and op in _BIT_OPS:
            return V(Bool(), f"({left.c} {op} {right.c})")
        if isinstance(left.kind, Float) or isinstance(right.kind, Float):
            if op not in ("+", "-", "*"):
                _refuse(f"the operator {op} on a REAL")
            a, b = _as_float(left), _as_float(right)
            return V(Float(), f"({a.c} {op} {b.c})")
        a, b = _as_int(left), _as_int(right)
        if op in ("<<", ">>") and isinstance(b.kind, Int) and b.kind.lo < 0:
            b = self.shift_count(b)
        assert isinstance(a.kind, Int) and isinstance(b.kind, Int)
        result = _result_range(op, a.kind, b.kind)
        if a.kind.stand_in or b.kind.stand_in:
            if op == ">>":
                _refuse("a shift right of a REAL's integer")
            masked = op == "&" and result.lo >= 0 and result.hi < 1 << 64
            # a ring operation modulo 2**64 keeps the stand-in's congruence; a mask of at
            # most 64 bits takes it off: what is left is exact
            result = replace(result, stand_in=not masked)
        if not result.fits128:
            _refuse("an integer beyond 128 bits")
        # computed in the widest C type among the operands and the result, then narrowed to
        # the result's, which holds the value
        wide = (
            "padt_i128" if "padt_i128" in (a.kind.ctype, b.kind.ctype, result.ctype) else "int64_t"
        )
        x = a.c if a.kind.ctype == wide else f"(({wide}){a.c})"
        y = b.c if b.kind.ctype == wide else f"(({wide}){b.c})"
        if op == "<<":
            unsigned = "uint64_t" if wide == "int64_t" else "unsigned __int128"
            text = f"(({wide})(({unsigned}){x} << {b.c}))"
        elif op == ">>":
            width = 64 if wide == "int64_t" else 128
            if b.kind.hi >= width:
                text = f"({b.c} >= {width - 1} ? ({x} >> {width - 1}) : ({x} >> {b.c}))"
            else:
                text = f"({x} >> {b.c})"
        else:
            text = f"({x} {op} {y})"
        return V(result, text if wide == result.ctype else f"(({result.ctype}){text})")

    def shift_count(self, count: V) -> V:
        """A shift's count that may be negative: Python's fault where it is."""
        assert isinstance(count.kind, Int)
        held = self.temp(count.kind.ctype)
        self.line(f"{held} = {count.c};")
        self.line(f"if (PADT_UNLIKELY({held} < 0)) {{")
        self.line('    PyErr_SetString(PyExc_ValueError, "negative shift count");')
        self.line("    goto padt_error;")
        self.line("}")
        return V(_narrowed(count.kind, 0, count.kind.hi), held)

    def wrap(self, node: Wrap) -> V:
        """An integer brought into the range of `bits` bits as Python brings it: masked,
        the sign taken back by adding and subtracting half the range (with the offset, in
        one constant); nothing to do where its range is proven within the type's."""
        if node.bits <= 64:
            value, modular = self.ring(node.value)
            if modular:  # all the wrap keeps of the value is in its low 64 bits
                value = V(UNSIGNED64, f"((padt_i128){value.c})")
        else:
            value = self.expr(node.value)
        value = _as_int(value)
        mask, half = (1 << node.bits) - 1, 1 << (node.bits - 1)
        moved = self.binary("+", value, _int_constant(node.offset)) if node.offset else value
        assert isinstance(moved.kind, Int)
        if moved.kind.within(Int(-half, half - 1) if node.signed else Int(0, mask)):
            return moved
        if not node.signed:
            return self.binary("&", moved, _int_constant(mask))
        shifted = self.binary("+", value, _int_constant(half + node.offset))
        masked = self.binary("&", shifted, _int_constant(mask))
        return self.binary("-", masked, _int_constant(half))

    def ring(self, node: Expr) -> tuple[V, bool]:
        """`node` where only its value modulo 2**64 matters (what a wrap to at most 64 bits
        keeps): exact wherever its range fits 128 bits, as `expr` makes it (False); else
        (True) a uint64_t congruent to it modulo 2**64, the additions, subtractions,
        products, bit operations and shifts left of unsigned C arithmetic keeping that
        congruence (ULINT * ULINT, SHL of an LWORD by up to 64, chains of them: Python
        computes them exact before the wrap masks them)."""
        if not (isinstance(node, Binary) and node.op in _RING_OPS):
            return self.expr(node), False
        left, left_modular = self.ring(node.left)
        # a shift's count is taken as it is, never modulo anything
        right, right_modular = (
            (self.expr(node.right), False) if node.op == "<<" else self.ring(node.right)
        )
        if not (left_modular or right_modular):
            if not (isinstance(left.kind, Int) and isinstance(right.kind, Int)):
                return self.binary(node.op, left, right), False  # BOOLs, REALs, texts
            if node.op == "<<" and right.kind.lo < 0:
                right = self.shift_count(right)
            assert isinstance(left.kind, Int) and isinstance(right.kind, Int)
            if (node.op != "<<" or right.kind.hi <= 127) and _result_range(
                node.op, left.kind, right.kind
            ).fits128:
                return self.binary(node.op, left, right), False
        # a stand-in (a REAL's integer) is congruent to the true value modulo 2**64 too
        x = left.c if left_modular else f"((uint64_t){_as_int(left).c})"
        if node.op == "<<":
            count = _as_int(right)
            assert isinstance(count.kind, Int)
            if count.kind.stand_in:
                _refuse("a shift by a REAL's integer")
            if count.kind.lo < 0:
                count = self.shift_count(count)
            assert isinstance(count.kind, Int)
            shifted = f"({x} << {count.c})"
            if count.kind.hi >= 64:  # a shift by the width or more: undefined in C, 0 here
                shifted = f"({count.c} >= 64 ? (uint64_t)0 : {shifted})"
            return V(UNSIGNED64, shifted), True
        y = right.c if right_modular else f"((uint64_t){_as_int(right).c})"
        return V(UNSIGNED64, f"((uint64_t)({x} {node.op} {y}))"), True

    def unary(self, node: Unary) -> V:
        value = self.expr(node.operand)
        if node.op == "not":
            if isinstance(value.kind, Bool):
                return V(Bool(), f"(!{value.c})")
            if isinstance(value.kind, Int):
                return V(Bool(), f"({value.c} == 0)")
            if isinstance(value.kind, Float):
                return V(Bool(), f"({value.c} == 0.0)")
            _refuse(f"not of a {_kind_name(value.kind)}")
        if isinstance(value.kind, Float):
            if node.op == "-":
                return V(Float(), f"(-{value.c})")
            _refuse("~ of a REAL")
        number = _as_int(value)
        assert isinstance(number.kind, Int)
        lo, hi = number.kind.lo, number.kind.hi
        result = Int(-hi, -lo) if node.op == "-" else Int(-hi - 1, -lo - 1)
        result = replace(result, stand_in=number.kind.stand_in)
        if not result.fits128:
            _refuse("an integer beyond 128 bits")
        wide = "padt_i128" if "padt_i128" in (number.kind.ctype, result.ctype) else "int64_t"
        operand = number.c if number.kind.ctype == wide else f"(({wide}){number.c})"
        text = f"({node.op}{operand})"
        return V(result, text if wide == result.ctype else f"(({result.ctype}){text})")

    def compare(self, op: str, nodes: tuple[Expr, ...]) -> V:
        """`a op b`, or the chain `a op b op c`: b evaluated once, c only while the
        comparisons before hold."""
        if op not in _RELATIONS:
            _refuse(f"a comparison {op}")
        left, right = (self.null() if _is_none(n) else self.expr(n) for n in nodes[:2])
        if isinstance(left.kind, Ref) and isinstance(right.kind, Ref) and len(nodes) == 2:
            if op not in ("==", "!="):
                _refuse(f"references compared with {op}")
            if "Py_None" in (left.c, right.c):  # with NULL: whether it is None
                return V(Bool(), f"({left.c} {op} {right.c})")
            both = (Text(), left.c), (Text(), right.c)  # the same place (Reference.__eq__)
            left, right = (V(kind, c) for kind, c in both)
        if isinstance(left.kind, Text) and isinstance(right.kind, Text) and len(nodes) == 2:
            # str's own order, by code points, as Python compares them
            flag = self.temp("int")
            self.line(f"{flag} = PyObject_RichCompareBool({left.c}, {right.c}, {_PY_OPS[op]});")
            self.line(f"if (PADT_UNLIKELY({flag} < 0)) goto padt_error;")
            return V(Bool(), flag)
        left, right = self.comparable(left), self.comparable(right)
        if len(nodes) == 2:
            return V(Bool(), _comparison(left, op, right))
        right = self.held(right)
        flag = self.temp("int")
        self.line(f"{flag} = {_comparison(left, op, right)};")
        left = right
        rest = nodes[2:]
        for n, right_node in enumerate(rest):
            self.line(f"if ({flag}) {{")
            with self.captured() as lines:
                right = self.comparable(self.expr(right_node))
                if n < len(rest) - 1:
                    right = self.held(right)
                self.line(f"{flag} = {_comparison(left, op, right)};")
            self.out.extend(lines)
            self.line("}")
            left = right
        return V(Bool(), flag)

    def held(self, value: V) -> V:
        """The value in a temporary, unless it is one already (or a constant)."""
        if value.c.isidentifier() or value.c.strip("()-").isdigit():
            return value
        held = self.temp(_ctype(value.kind))
        self.line(f"{held} = {value.c};")
        return V(value.kind, held)

    def comparable(self, value: V) -> V:
        if isinstance(value.kind, Int | Bool | Float):
            return value
        _refuse(f"a comparison of a {_kind_name(value.kind)}")

    def identity(self, node: Binary) -> V:
        if not _is_none(node.right):
            _refuse("`is` with something else than None")
        value = self.expr(node.left)
        if not isinstance(value.kind, Hook | Ref):
            _refuse(f"`is None` of a {_kind_name(value.kind)}")
        symbol = "==" if node.op == "is" else "!="
        return V(Bool(), f"({value.c} {symbol} Py_None)")

    def logic(self, node: Logic) -> V:
        first = self.expr(node.values[0])
        if not isinstance(first.kind, Bool):
            _refuse("and/or of something else than BOOL")
        flag = self.temp("int")
        self.line(f"{flag} = {first.c};")
        for operand in node.values[1:]:
            self.line(f"if ({flag if node.op == 'and' else '!' + flag}) {{")
            with self.captured() as lines:
                value = self.expr(operand)
                if not isinstance(value.kind, Bool):
                    _refuse("and/or of something else than BOOL")
                self.line(f"{flag} = {value.c};")
            self.out.extend(lines)
            self.line("}")
        return V(Bool(), flag)

    def choice(self, node: Choice) -> V:
        test = self.condition(node.test)
        with self.captured() as body_lines, self.refined(node.test):
            body = self.expr(node.then)
        with self.captured() as else_lines:
            orelse = self.expr(node.orelse)
        if isinstance(body.kind, Bool) and isinstance(orelse.kind, Bool):
            kind: Kind = Bool()
        elif isinstance(body.kind, Int) and isinstance(orelse.kind, Int):
            kind = join(body.kind, orelse.kind) or body.kind
        elif isinstance(body.kind, Float) and isinstance(orelse.kind, Float):
            kind = Float()
        else:
            _refuse("a conditional expression of two kinds")
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

    # -- FUNCTIONs and methods: their C bodies, called directly (function_body.py)
    instance_ctype = "PyObject *"  # what a method's C body takes as its instance

    def direct_call(self, node: Call) -> V | None:
        """A call of a FUNCTION, or of a method of an instance, whose body may be C: every
        parameter, its result and its outputs numbers, BOOLs or texts, or a FUNCTION's
        structures too, and on slots its arrays (`FunctionInfo.native`, `in_image`); None
        (and nothing emitted) for any other call."""
        callee = node.callee
        if isinstance(callee, str):
            info = self.module.functions.get(callee)
            if info is None or not info.native or not (info.in_image or self.objects_direct):
                return None
            return self.direct_function_call(node, info, None)
        if not (
            isinstance(callee, Member)
            and not isinstance(callee.base, Named)  # SUPER^.X(): the base's, by its class
            and METHOD_NAME.match(callee.name) is not None
        ):
            return None
        with self.captured():  # the kind of the instance only: read below
            kind = self.expr(callee.base).kind
        found = self.module.classes.get(kind.cls) if isinstance(kind, Instance) else None
        info = found.methods.get(callee.name) if found is not None else None
        if info is None or not info.native:
            return None
        return self.direct_function_call(node, info, self.expr(callee.base))

    def runs_on(self, owner: V, info: FunctionInfo) -> str | None:
        """Whether a method's C body (of class `info.owner`, found on the class the
        instance `owner` is declared of) may run on it: None never, else the condition in
        C, checked at each call. On objects the instance may be of a derived block (an
        in-out, a reference's), which may override the method: the C is taken where the
        object's class is exactly the declared one (a derived block's instance inherits
        the base's slots first, at the base's offsets), else the method is looked up as
        Python does."""
        assert isinstance(owner.kind, Instance)
        return f"Py_IS_TYPE({owner.c}, (PyTypeObject *){self.module.type_ref(owner.kind.cls)})"

    def direct_function_call(self, node: Call, info: FunctionInfo, owner: V | None) -> V:
        """A call of a FUNCTION (or of a method of `owner`) of numbers, BOOLs and texts (or,
        a FUNCTION's, structures, and on slots arrays): its C body where it has one (found
        once per call site in the binding's table of FUNCTIONs), where every argument is of
        its parameter's kind and the instance one it may run on (`runs_on`), else its
        Python, with the values boxed; either way its result and outputs as C values
        (`Results` where Python has a tuple): a text, and on slots a structure or array, as
        an object a temporary owns; in native memory a structure as bytes of the frame
        (`out_temp`)."""
        name = _callee_text(node)
        if len(node.args) > len(info.params):
            _refuse(f"a call of {name} with more arguments than it takes")
        passed = [
            *zip((param.name for param in info.params), node.args, strict=False),
            *node.keywords,
        ]
        params = {param.name: param for param in info.params}
        if len({keyword for keyword, _ in passed}) < len(passed) or not all(
            keyword in params for keyword, _ in passed
        ):
            _refuse(f"a call of {name} with arguments it does not take")
        given: dict[str, V] = {}
        for keyword, arg in passed:  # in the call's order, each held as Python holds it
            value = self.expr(arg)
            if isinstance(value.kind, Int | Bool | Float):
                held = self.temp(_ctype(value.kind))
                self.line(f"{held} = {value.c};")
                value = V(value.kind, held)
            elif isinstance(value.kind, Text) or (self.objects_direct and _is_object(value.kind)):
                # an argument of its own (in native memory a structure is bytes, not this)
                held = self.temp("PyObject *", "NULL")
                self.line(f"Py_XSETREF({held}, Py_NewRef({value.c}));")
                value = V(value.kind, held)
            given[keyword] = value
        items = returned_items(info)
        outs = [self.out_temp(kind) if _valued(kind) else "" for kind in items]
        direct = all(
            _fits(given[p.name].kind, p.kind) if p.name in given else p.default is not None
            for p in info.params
        )
        guard = self.runs_on(owner, info) if owner is not None else ""
        direct = direct and guard is not None
        if direct:
            site = self.module.function_site()
            args = [
                given[p.name].c
                if p.name in given
                else self.text_constant(p.default).c
                if isinstance(p.default, str)
                else _constant(Const(p.default, "")).c
                for p in info.params
            ]
            instance = [self.instance_ctype] if owner is not None else []
            ctypes = ", ".join(
                ["padt_mctx *", *instance, *(self.param_ctype(p.kind) for p in info.params)]
                + [self.out_ctype(kind) for kind in items if _valued(kind)]
            )
            call = f"((int (*)({ctypes})){site}.function)"
            first = [self.context, *([owner.c] if owner is not None else [])]
            pointers = [self.out_arg(kind, out) for kind, out in zip(items, outs, strict=True)]
            everything = ", ".join([*first, *args, *(p for p in pointers if p)])
            self.check(f"padt_function_site(&{site}, {self.module.key(info.native)})")
            found = f"{site}.function != NULL" + (f" && {guard}" if guard else "")
            self.line(f"if (PADT_LIKELY({found})) {{")
            self.line(f"    if (PADT_UNLIKELY({call}({everything}) < 0)) goto padt_error;")
            self.line("} else {")
            self.depth += 1
        boxed = [self.boxed(value, name) for value in given.values()]
        keywords = self.module.names(tuple(given)) if given else "NULL"
        if owner is None:
            array = f"(PyObject *[]){{{', '.join(boxed)}}}" if boxed else "NULL"
            call = f"padt_call_function({self.module.key(info.name)}, {array}, 0, {keywords})"
        else:
            array = f"(PyObject *[]){{{', '.join([self.instance_object(owner), *boxed])}}}"
            call = f"padt_call_method({self.module.key(info.name)}, {array}, 1, {keywords})"
        returned = self.owned_object(call)
        if info.outputs is not None:
            self.line(f"PADT_CHECK_TUPLE({returned}, {len(items)});")
            for n, (kind, out) in enumerate(zip(items, outs, strict=True)):
                if out:
                    obj = f"PyTuple_GET_ITEM({returned}, {n})"
                    self.given_back(out, obj, kind, f"an output of {name}")
        elif outs:
            self.given_back(outs[0], returned, items[0], f"the result of {name}")
        if direct:
            self.depth -= 1
            self.line("}")
        parts = tuple(V(kind, out or "0") for kind, out in zip(items, outs, strict=True))
        if info.outputs is not None or not parts:
            return V(Results(items), "", parts=parts)
        return parts[0]

    def out_temp(self, kind: Kind) -> str:
        """The temporary a FUNCTION's C writes a result or output of `kind` into."""
        return self.temp(_ctype(kind), "NULL" if _is_object(kind) else "0")

    def param_ctype(self, kind: Kind) -> str:
        """The C type a FUNCTION's C takes a parameter of `kind` as."""
        return _ctype(kind)

    def out_ctype(self, kind: Kind) -> str:
        """The C type of the pointer a FUNCTION's C writes a result or output through."""
        return f"{_ctype(kind)} *"

    def out_arg(self, kind: Kind, out: str) -> str:
        """That pointer, to the temporary `out` ("" where the call gives no value)."""
        return f"&{out}" if out else ""

    def given_back(self, out: str, obj: str, kind: Kind, what: str) -> None:
        """What a FUNCTION's Python gave (`obj`) into the temporary its C would have
        written."""
        value = self.unboxed(obj, kind, what)
        if _is_object(value.kind):
            self.line(f"Py_XSETREF({out}, Py_NewRef({value.c}));")
        else:
            self.line(f"{out} = {value.c};")

    def call_value(self, node: Call) -> V:
        direct = self.direct_call(node)
        if direct is not None:
            return direct
        name = node.callee if isinstance(node.callee, str) else None
        if name is not None and not node.args and not node.keywords:
            made = self.module.classes.get(name)
            if made is not None and made.structure:
                return self.new_structure(made.name)
        if (name is not None and name in self.module.functions) or self.is_method_call(node):
            info, returned = self.function_call(node)
            called = _callee_text(node)
            if info.outputs is not None:  # a tuple of the result and the outputs
                if not info.outputs.items:
                    _refuse(f"a call of {called}, whose returns differ in shape")
                self.line(f"PADT_CHECK_TUPLE({returned}, {len(info.outputs.items)});")
                return V(info.outputs, returned)
            if not isinstance(info.result, Int | Bool | Float | Text):
                why = "a FUNCTION whose result the tier leaves to Python"
                _refuse(f"a call of {called}, {why}")
            return self.unboxed(returned, info.result, f"the result of {called}")
        if node.keywords:
            _refuse(f"a call of {_callee_text(node)} with keywords")
        if name == IX.name and len(node.args) == len(IX.params):
            index = self.int_value(node.args[0])
            low, high = (_constant_int(arg) for arg in node.args[1:])
            if low is None or high is None:
                _refuse(f"{IX.name} with bounds that are not constants")
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
            a, b = (self.division_operand(arg) for arg in node.args)
            assert isinstance(a.kind, Int) and isinstance(b.kind, Int)
            top = max(abs(a.kind.lo), abs(a.kind.hi))
            if name == IMOD.name:  # smaller than the divisor
                top = min(top, max(0, max(abs(b.kind.lo), abs(b.kind.hi)) - 1))
            result = Int(-top, top)  # the smallest 64-bit integer / -1: 2**63, in 128 bits
            if not result.fits128:
                _refuse("an integer beyond 128 bits")
            if not (a.kind.fits64 and b.kind.fits64):  # ULINT, LWORD: in 128 bits
                helper = "padt_idiv_wide" if name == IDIV.name else "padt_imod_wide"
                held = self.temp("padt_i128")  # what the helper writes, whatever the result
                self.check(f"{helper}({a.c}, {b.c}, &{held})")
                # a remainder by a small divisor fits 64 bits: in the C type of its kind
                return V(result, held if not result.fits64 else f"((int64_t){held})")
            held = self.temp(result.ctype)
            helper = f"padt{name}" if result.fits64 else "padt_idiv128"  # padt_idiv, padt_imod
            self.check(f"{helper}({a.c}, {b.c}, &{held})")
            return V(result, held)
        if name in (F32.name, "float") and len(node.args) == 1:
            number = _as_float(self.expr(node.args[0]))
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
            if isinstance(value.kind, Bool | Int):  # an integer already (BOOL_TO_INT: 0, 1)
                return _as_int(value)
        if name == COPY.name and len(node.args) == len(COPY.params):
            return self.copy(node.args[0])
        if name in (ROL.name, ROR.name) and len(node.args) == len(ROL.params):
            return self.rotation(name, node)
        if name == POW.name and len(node.args) == len(POW.params):
            a, b = (_as_float(self.expr(arg)) for arg in node.args)
            return V(Float(), f"padt_pow({a.c}, {b.c})")
        if name == SAFE_MATH.name and len(node.args) == len(SAFE_MATH.params):
            match node.args[0]:
                case Named(name=function) if (
                    function.startswith("_math.") and function[6:] in MATH_FUNCTIONS
                ):  # the C function of the same name, which Python's calls
                    value = _as_float(self.expr(node.args[1]))
                    return V(Float(), f"padt_safe_math({function[6:]}, {value.c})")
        if name == FDIV.name and len(node.args) == len(FDIV.params):
            a, b = (_as_float(self.expr(arg)) for arg in node.args)
            return V(Float(), f"padt_fdiv({a.c}, {b.c})")
        if name == "abs" and len(node.args) == 1:
            value = self.expr(node.args[0])
            if isinstance(value.kind, Float):
                return V(Float(), f"fabs({value.c})")
            if isinstance(value.kind, Int) and not value.kind.stand_in:
                return self.absolute(self.held(value))
        if name in ("min", "max") and len(node.args) >= 2:
            return self.extreme(name, node)
        if name == REF.name:
            return self.reference(node)
        if name == DEREF.name and len(node.args) == 1:
            return self.dereference(node.args[0])
        if (name in _HELPER_RESULTS or name == MUX.name) and node.args:
            return self.helper_call(name, node)
        if name == "str" and len(node.args) == 1:  # INT_TO_STRING and the like
            value = self.expr(node.args[0])
            if isinstance(value.kind, Int):
                return self.owned(Text(), f"PyObject_Str({self.boxed(value, name)})")
        if name == "len" and len(node.args) == 1:
            target = self.expr(node.args[0])
            if isinstance(target.kind, Range):
                return self.range_length(target)
            if isinstance(target.kind, Text):
                return V(Int(0, INT64_MAX), f"((int64_t)PyUnicode_GET_LENGTH({target.c}))")
        _refuse(f"a call of {_callee_text(node)}")

    def new_structure(self, cls: str) -> V:
        """`STRUCT_X()`: a structure at its initial values, a new object."""
        return self.owned(Instance(cls), f"PyObject_CallNoArgs({self.module.type_ref(cls)})")

    def text_constant(self, text: str) -> V:
        """A text of the program: a str made once as the module is bound (a C string
        literal, which ends at a NUL and is read as UTF-8, which has no surrogates)."""
        if "\0" in text or any("\ud800" <= ch <= "\udfff" for ch in text):
            _refuse("a text with a NUL or a surrogate")
        return V(Text(), self.module.key(text))

    def cut(self, value: V, stop: int) -> V:
        """`text[:stop]`: a STRING cut to its length (the same object where it fits)."""
        if not isinstance(value.kind, Text) or not 0 <= stop <= INT64_MAX:
            _refuse(f"a slice of a {_kind_name(value.kind)}")
        return self.owned(Text(), f"padt_cut({value.c}, {c_int(stop)})")

    def owned(self, kind: Kind, call: str) -> V:
        """The new object `call` makes, a value of `kind`, in a temporary that owns it."""
        return V(kind, self.owned_object(call))

    def owned_object(self, call: str) -> str:
        """The temporary that owns the new object `call` makes (NULL: an error)."""
        held = self.temp("PyObject *", "NULL")
        self.line(f"Py_XSETREF({held}, {call});")
        self.line(f"if (PADT_UNLIKELY({held} == NULL)) goto padt_error;")
        return held

    def copy(self, node: Expr) -> V:
        """`_copy(x)`: an array or structure assigned as a whole, copied by the Python helper
        (a new object, which the temporary owns)."""
        value = self.expr(node)
        if not isinstance(value.kind, Instance | Array):
            _refuse(f"{COPY.name} of a {_kind_name(value.kind)}")
        return self.owned(value.kind, _vector_call(self.module.key(COPY.name), [value.c]))

    def rotation(self, name: str, node: Call) -> V:
        """`_rol(value, n, bits)`: the compiler's value is masked to its width already."""
        value = _as_int(self.expr(node.args[0]))  # of up to 64 bits: an LWORD's in 128
        count = self.int_value(node.args[1])
        bits = _constant_int(node.args[2])
        assert isinstance(value.kind, Int) and isinstance(count.kind, Int)
        if bits is None or not 1 <= bits <= 64:
            _refuse(f"{name} over a width other than a constant of 1 to 64 bits")
        mask = (1 << bits) - 1
        if value.kind.stand_in or count.kind.stand_in or not value.kind.within(Int(0, mask)):
            _refuse(f"{name} of a value not within its width")
        helper = "padt_rol" if name == ROL.name else "padt_ror"
        if bits == 64:  # LWORD: a padt_i128 (padt_rol64, padt_ror64)
            return V(Int(0, mask), f"{helper}64({value.c}, {count.c})")
        return V(Int(0, mask), f"{helper}({value.c}, {count.c}, {bits})")

    def is_method_call(self, node: Call) -> bool:
        """`x.M__X(...)`: a method or property accessor of a generated object; or
        `POU_BASE.M__X(s, ...)`, SUPER^.X(): the base's own, on this instance; or
        `s._ac_X.update(now, N=...)`: an SFC action's control block told its step flags."""
        match node.callee:
            case Member(base=Named(), name=name):
                return METHOD_NAME.match(name) is not None and _is_super_call(node)
            case Member(base=Member(base=This(), name=slot), name="update"):
                return slot.startswith("_ac_")
            case Member(name=name):
                return METHOD_NAME.match(name) is not None
        return False

    def function_call(self, node: Call) -> tuple[FunctionInfo, str]:
        """A FUNCTION of the artifact, or a method of an object, called as Python calls it,
        with the values boxed; the result in a temporary that owns it. A method is looked
        up on the object as Python does (an override of a derived block's)."""
        callee, passed = node.callee, node.args
        if isinstance(callee, Member) and isinstance(callee.base, Named):  # SUPER^.X()
            name, base = callee.name, callee.base.name
            info = self.method_info(V(Instance(base), "s"), name)
            first, passed = [self.instance_object(V(Instance(self.cls.name), "s"))], passed[1:]
            caller = f"padt_call_in_class({self.module.type_ref(base)}, "
        elif isinstance(callee, Member):
            owner = self.expr(callee.base)
            name = callee.name
            info = self.method_info(owner, name)
            first, caller = [self.instance_object(owner)], "padt_call_method("
        else:
            assert isinstance(callee, str)
            name = callee
            info, first, caller = self.module.functions[name], [], "padt_call_function("
        values = [*passed, *(value for _, value in node.keywords)]
        boxed = first + [self.boxed(self.expr(value), name) for value in values]
        keywords = tuple(keyword for keyword, _ in node.keywords)
        names = self.module.names(keywords) if keywords else "NULL"
        args = f"(PyObject *[]){{{', '.join(boxed)}}}" if boxed else "NULL"
        positional = len(first) + len(passed)
        result = self.temp("PyObject *", "NULL")
        self.line(
            f"Py_XSETREF({result}, {caller}{self.module.key(name)}, {args}, "
            f"{positional}, {names}));"
        )
        self.line(f"if (PADT_UNLIKELY({result} == NULL)) goto padt_error;")
        return info, result

    def instance_object(self, value: V) -> str:
        """The Python object of an instance a method is called on (borrowed or owned by a
        temporary of the statement)."""
        return value.c

    def method_info(self, owner: V, name: str) -> FunctionInfo:
        if isinstance(owner.kind, Implementer):  # through an interface
            cls = interface_key(owner.kind.name)
        elif isinstance(owner.kind, Instance):
            cls = owner.kind.cls
        else:
            _refuse(f"a call of {name} of a {_kind_name(owner.kind)}")
        info = self.module.classes.get(cls)
        method = info.methods.get(name) if info is not None else None
        if method is None:
            _refuse(f"a call of {name}, which {cls} does not have alike")
        return method

    def boxed(self, value: V, callee: str) -> str:
        """`value` as the Python object a call of `callee` takes, in a temporary that owns it."""
        kind = value.kind
        if isinstance(kind, Int) and kind.fits64 and not kind.stand_in:
            box = f"PyLong_FromLongLong({value.c})"
        elif isinstance(kind, Int) and kind.fits128 and not kind.stand_in:  # ULINT, LWORD
            box = f"padt_box128({value.c})"
        elif isinstance(kind, Bool):
            box = f"PADT_BOOL_OBJECT({value.c})"
        elif isinstance(kind, Float):
            box = f"PyFloat_FromDouble({value.c})"
        elif isinstance(kind, Text | Ref | Instance | Array):  # the object itself, as Python
            box = f"Py_NewRef({value.c})"
        else:
            _refuse(f"an argument of {callee} that holds a {_kind_name(kind)}")
        return self.owned_object(box)

    def dereference(self, node: Expr) -> V:
        """`_deref(r)`: what a reference refers to, read by the runtime's helper (NULL its
        fault), of the kind of the place it refers to."""
        reference = self.expr(node)
        if not isinstance(reference.kind, Ref) or reference.kind.target is None:
            _refuse(f"{DEREF.name} of a {_kind_name(reference.kind)}")
        referred = reference.kind.target
        read = self.owned(referred, _vector_call(self.module.key(DEREF.name), [reference.c]))
        return self.unboxed(read.c, referred, "what a reference refers to")

    def null(self) -> V:
        """NULL: None, where a reference is stored or compared."""
        return V(Ref(None), "Py_None")

    def reference(self, node: Call) -> V:
        """`_ref(root, (steps...), label[, whole])`: REF(x), made by the runtime's helper
        (which checks the root and the steps); of the kind of the place the steps reach."""
        if not 3 <= len(node.args) <= 4:
            _refuse(f"{REF.name} of {len(node.args)} arguments")
        root_node, steps_node, *rest = node.args
        if isinstance(root_node, Named) and root_node.name == "_G":
            if self.module.globals_class is None:
                _refuse("_G without globals")
            self.uses_globals = True
            self.module.type_ref(self.module.globals_class)
            root = V(Instance(self.module.globals_class), "padt_g")
        else:
            root = self.expr(root_node)
        if not isinstance(steps_node, Sequence) or not steps_node.as_tuple:
            _refuse(f"{REF.name} of steps that are no tuple")
        kind: Kind | None = root.kind
        steps: list[str] = []
        for step in steps_node.items:
            if (
                isinstance(kind, Instance)
                and isinstance(step, Const)
                and isinstance(step.value, str)
            ):
                kind = self.member_kind(kind, step.value)
                steps.append(self.module.key(step.value))
            elif isinstance(kind, Array):
                steps.append(self.boxed(self.int_value(step), REF.name))
                kind = kind.element
            else:
                _refuse(f"{REF.name} through a {_kind_name(kind)}")
        if not isinstance(root.kind, Instance | Array):
            _refuse(f"{REF.name} into a {_kind_name(root.kind)}")
        packed = self.owned_object(f"PyTuple_Pack({len(steps)}{''.join(', ' + c for c in steps)})")
        label = [self.boxed(self.expr(value), REF.name) for value in rest]
        made = _vector_call(self.module.key(REF.name), [root.c, packed, *label])
        return self.owned(Ref(kind), made)

    def helper_call(self, name: str, node: Call) -> V:
        """A function of the runtime's (`_left`, `_find`, `_mux`, ...), called from C as
        the Python tier calls it, the arguments boxed; its result read with the type check
        of a slot (MUX's as the kind of the inputs it chooses from)."""
        values = [self.expr(arg) for arg in node.args]
        if name == MUX.name:
            kinds = {type(v.kind) for v in values[1:]}
            if len(kinds) != 1 or not kinds <= {Int, Bool, Float, Text}:
                _refuse(f"{name} of inputs of different kinds")
            kind = values[1].kind
            for value in values[2:]:
                kind = join(kind, value.kind) or kind
        else:
            kind = _HELPER_RESULTS[name]
        args = [self.boxed(value, name) for value in values]
        result = self.owned(kind, _vector_call(self.module.key(name), args))
        return self.unboxed(result.c, result.kind, f"the result of {name}")

    def absolute(self, value: V) -> V:
        kind = value.kind
        assert isinstance(kind, Int)
        top = max(abs(kind.lo), abs(kind.hi))
        result = Int(0 if kind.lo <= 0 <= kind.hi else min(abs(kind.lo), abs(kind.hi)), top)
        wide = "padt_i128" if "padt_i128" in (kind.ctype, result.ctype) else "int64_t"
        x = value.c if kind.ctype == wide else f"(({wide}){value.c})"
        return V(result, f"(({result.ctype})({x} < 0 ? -{x} : {x}))")

    def extreme(self, name: str, node: Call) -> V:
        """min() and max() of REALs or of integers, as Python takes them: the first
        argument, replaced by each later one that is smaller (larger); NaN as it does."""
        values = [self.held(self.expr(arg)) for arg in node.args]
        relation = "<" if name == "min" else ">"
        if all(isinstance(v.kind, Float) for v in values):
            kind: Kind = Float()
        elif all(_exact128(v.kind) for v in values) or _one_stand_in(values):
            # integers of up to 128 bits (a ULINT's), or a REAL's or a text's integer with
            # 64-bit ones (STRING_TO_ULINT: max(_str_to_int(s), 0)), which a stand-in is
            # compared with as the true value is (_comparison)
            bounds = [v.kind for v in values if isinstance(v.kind, Int)]
            pick = min if name == "min" else max
            stand_in = any(k.stand_in for k in bounds)
            kind = Int(pick(k.lo for k in bounds), pick(k.hi for k in bounds), stand_in)
        else:
            _refuse(f"{name}() of mixed or wide values")
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


def _is_super_call(node: Call) -> bool:
    """`POU_BASE.M__X(s, ...)`: a base's method called on the instance the code runs on."""
    match node.callee, node.args:
        case Member(base=Named(name=base)), (This(), *_):
            return CLASS_NAME.match(base) is not None
    return False


def _vector_call(function_key: str, args: list[str]) -> str:
    """A call of the namespace's function `function_key` with the objects `args` (a new
    reference, NULL on an error)."""
    vector = f"(PyObject *[]){{{', '.join(args)}}}"
    return f"padt_call_function({function_key}, {vector}, {len(args)}, NULL)"


def _callee_text(call: Call) -> str:
    return call.callee if isinstance(call.callee, str) else python_text(call.callee)


def _is_none(node: Expr) -> bool:
    return isinstance(node, Const) and node.value is None


def _constant(node: Const) -> V:
    value = node.value
    if isinstance(value, bool):
        return V(Bool(), "1" if value else "0")
    if isinstance(value, int):
        return _int_constant(value)
    if isinstance(value, float) and math.isfinite(value):
        return V(Float(), f"({value.hex()})")  # exact: C99 reads hexadecimal doubles
    _refuse(f"a constant {type(value).__name__}")


def _int_constant(value: int) -> V:
    kind = Int(value, value)
    if not kind.fits128:
        _refuse("an integer constant beyond 128 bits")
    text = c_int(value)
    # in parentheses: no operator before it may take its sign for a `--`
    return V(kind, f"({text})" if value < 0 and not text.startswith("(") else text)


def _constant_int(node: Expr) -> int | None:
    if isinstance(node, Const) and type(node.value) is int:
        return node.value
    if isinstance(node, Unary) and node.op == "-":
        operand = _constant_int(node.operand)
        return None if operand is None else -operand
    return None


def _bounds_test(test: Expr) -> tuple[str, int, int] | None:
    """`lo <= x <= hi` (also with `x := ...`, and `<`): the name and its inclusive bounds."""
    if not isinstance(test, Chain) or len(test.values) != 3 or test.op not in ("<=", "<"):
        return None
    low, high = _constant_int(test.values[0]), _constant_int(test.values[2])
    middle = test.values[1]
    named = isinstance(middle, Assigned) or (isinstance(middle, Var) and middle.where == "local")
    if low is None or high is None or not named:
        return None
    assert isinstance(middle, Assigned | Var)
    strict = test.op == "<"
    return middle.name, low + strict, high - strict


def _plain64(kind: Kind) -> bool:
    return isinstance(kind, Int) and kind.fits64 and not kind.stand_in


def _exact128(kind: Kind) -> bool:
    return isinstance(kind, Int) and kind.fits128 and not kind.stand_in


def _one_stand_in(values: list[V]) -> bool:
    """One stand-in among integers of 64 bits: each pair compares as the true values do."""
    stand_ins = [v for v in values if isinstance(v.kind, Int) and v.kind.stand_in]
    return len(stand_ins) == 1 and all(_plain64(v.kind) for v in values if v not in stand_ins)


def _narrowed(kind: Int, lo: int, hi: int) -> Int:
    """`kind` known to lie in lo..hi: exact there when that is short of the stand-ins."""
    exact = lo > -STAND_IN_FROM and hi < STAND_IN_FROM
    return Int(max(lo, kind.lo), min(hi, kind.hi), kind.stand_in and not exact)


def _as_int(value: V) -> V:
    if isinstance(value.kind, Bool):
        return V(Int(0, 1), f"((int64_t){value.c})")
    if isinstance(value.kind, Int):
        return value
    _refuse(f"arithmetic on a {_kind_name(value.kind)}")


def _bits(kind: Int) -> int:
    """The smallest k with -2**k <= lo and hi < 2**k."""
    k = 0
    while not (-(1 << k) <= kind.lo and kind.hi < (1 << k)):
        k += 1
    return k


def _result_range(op: str, a: Int, b: Int) -> Int:
    if op == "+":
        return Int(a.lo + b.lo, a.hi + b.hi)
    if op == "-":
        return Int(a.lo - b.hi, a.hi - b.lo)
    if op == "*":
        products = (a.lo * b.lo, a.lo * b.hi, a.hi * b.lo, a.hi * b.hi)
        return Int(min(products), max(products))
    if op in _BIT_OPS:
        if op == "&" and (a.lo >= 0 or b.lo >= 0):
            highs = [k.hi for k in (a, b) if k.lo >= 0]
            return Int(0, min(highs))
        if a.lo >= 0 and b.lo >= 0:
            return Int(0, (1 << max(_bits(a), _bits(b))) - 1)
        k = max(_bits(a), _bits(b))
        return Int(-(1 << k), (1 << k) - 1)
    if op in ("<<", ">>"):
        if b.lo < 0:
            _refuse("a shift by a count that may be negative")
        if op == ">>":
            return Int(min(a.lo, a.lo >> b.hi), max(a.hi >> b.hi, a.hi >> b.lo))
        if b.hi > 127:
            _refuse("a shift left by more than 127")
        ends = (a.lo << b.lo, a.lo << b.hi, a.hi << b.lo, a.hi << b.hi)
        return Int(min(ends), max(ends))
    _refuse(f"the operator {op}")


def _fits(value: Kind, param: Kind) -> bool:
    """A value of kind `value` is one the parameter's C type and kind hold, as Python would
    pass it (an integer within the declared range; a BOOL, a REAL, a text, a structure of
    the parameter's class as itself)."""
    if isinstance(param, Int):
        return isinstance(value, Int) and not value.stand_in and value.within(param)
    if isinstance(param, Instance | Array):
        return value == param
    return type(value) is type(param)


def _is_object(kind: Kind) -> bool:
    """A text, a structure or an array: a FUNCTION's C takes and gives the Python object."""
    return isinstance(kind, Text | Instance | Array)


def returned_items(
    info: FunctionInfo,
) -> tuple[Int | Bool | Float | Text | Instance | Array | Nothing, ...]:
    """What a call of a FUNCTION or method whose body may be C gives, in order: its result
    (Nothing where it has none but outputs), then its outputs and in-outs."""
    given = Int | Bool | Float | Text | Instance | Array
    if info.outputs is not None:
        return tuple(k for k in info.outputs.items if isinstance(k, given | Nothing))
    return (info.result,) if isinstance(info.result, given) else ()


def _valued(kind: Kind) -> bool:
    """An item a call gives as a C value (not Nothing)."""
    return not isinstance(kind, Nothing)


def _comparison(left: V, op: str, right: V) -> str:
    for one, other in ((left, right), (right, left)):
        # a stand-in is beyond 2**126 where the true value is: on the same side of any
        # 64-bit value, but not of another stand-in
        if (
            isinstance(one.kind, Int)
            and one.kind.stand_in
            and not (isinstance(other.kind, Bool) or _plain64(other.kind))
        ):
            _refuse("a REAL's integer compared with more than 64 bits")
    floats = isinstance(left.kind, Float) or isinstance(right.kind, Float)
    for side in (left, right):
        if floats and isinstance(side.kind, Int) and not side.kind.within(EXACT_IN_DOUBLE):
            # Python compares an integer with a REAL exactly; C would round it first
            _refuse("an integer beyond 2**53 compared with a REAL")
    return f"({left.c} {op} {right.c})"


def _ctype(kind: Kind) -> str:
    if isinstance(kind, Int):
        return kind.ctype
    if _is_object(kind):
        return "PyObject *"
    return "double" if isinstance(kind, Float) else "int"


def _as_float(value: V) -> V:
    """A number as Python turns it into a float: an integer is converted (exactly as C
    does within 64 bits: to the nearest double, ties to even)."""
    if isinstance(value.kind, Float):
        return value
    if isinstance(value.kind, Bool) or (isinstance(value.kind, Int) and value.kind.fits64):
        return V(Float(), f"((double){value.c})")
    if isinstance(value.kind, Int) and value.kind.within(UNSIGNED64):
        # a ULINT: C converts an unsigned 64-bit integer to the nearest double, ties to
        # even, as Python converts an int
        return V(Float(), f"((double)(uint64_t){value.c})")
    if isinstance(value.kind, Int) and value.kind.within(Int(-UNSIGNED64.hi, UNSIGNED64.hi)):
        # a ULINT's remainder or difference: its magnitude so, the sign put back
        return V(Float(), f"padt_double_wide({value.c})")
    _refuse(f"a {_kind_name(value.kind)} in REAL arithmetic")


def _kind_name(kind: Kind | None) -> str:
    return "kind the tier leaves to Python" if kind is None else type(kind).__name__


# ---- a unit --------------------------------------------------------------------------------------


def _translate_body(module: _Module, cls: ClassInfo, func: _Numbered, mode: Mode) -> str:
    """The C function of one `__call__`; NotTranslated when it cannot be. The statics it
    needs join `module` only when it is translated."""
    if func.function.params or not func.function.method:
        _refuse("a body with arguments")
    return mode.function_text(settled(module, cls, func, mode.body, {}), func)


def settled(
    module: _Module,
    cls: ClassInfo,
    func: _Numbered,
    make: Callable[[_Module, ClassInfo, _Numbered, dict[str, Kind]], _Body],
    given: dict[str, Kind],
) -> _Body:
    """The body translated once the kinds of its locals settle (`given`: those known
    before, a FUNCTION's parameters), pass after pass; its statics joined to `module`."""
    kinds = dict(given)
    for attempt in range(2 * WIDEN_AFTER + 2):
        trial = replace(  # what a refused body asked for goes with it
            module,
            types=dict(module.types),
            offsets=dict(module.offsets),
            keys=dict(module.keys),
            kwnames=dict(module.kwnames),
        )
        body = make(trial, cls, func, kinds)
        try:
            body.body()
        except NotTranslated as refused:
            raise NotTranslated(refused.reason, body.st_line) from None
        merged = dict(kinds)
        for name, kind in body.assigned.items():
            known = merged.get(name)
            joined = kind if known is None else join(known, kind)
            if joined is None:
                _refuse(f"local {name} holds values of different kinds")
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
            module.kwnames = trial.kwnames
            module.sites, module.function_sites = trial.sites, trial.function_sites
            return body
        kinds = merged
    _refuse("the kinds of the locals do not settle")


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


def _function_text(body: _Body, func: _Numbered) -> str:
    """The body as C: a function per chunk of statements (never inlined: one function of
    the whole body would take the compiler minutes), and the body's own, which calls them
    in turn. The Python locals are in a frame the chunks share."""
    name = body.c_name
    head = f"static PyObject *\n{name}(PyObject *s, PyObject *Py_UNUSED(ignored))"
    entry = ["    if (padt_stack_check() < 0) return NULL;"]  # a recursion (padt_native.h)
    return slot_function_text(body, func, head, [], entry, ("Py_RETURN_NONE;", "return NULL;"))


def slot_function_text(
    body: _Body,
    func: _Numbered,
    head: str,
    fields: list[str],
    entry: list[str],
    returns: tuple[str, str],
) -> str:
    """The C of a body in slot mode, `head` its declaration (which declares `s`), with
    `fields` in its frame, set by `entry` as it begins; `returns` as body_function's."""
    name = body.c_name
    module = body.module
    frame = _frame(body, name, ["PyObject *g, *sys;", *fields])
    chunk_names, chunk_texts = _chunk_functions(
        body, name, "PyObject *s", ["PyObject *padt_g = f->g, *padt_sys = f->sys;"]
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
    main = body_function(body, func, head, [*entry, *setup], chunk_names, cleanup, returns)
    return "\n".join([*frame, *chunk_texts, *main])


def body_function(
    body: _Body,
    func: _Numbered,
    head: str,
    setup: list[str],
    chunk_names: list[str],
    cleanup: list[str],
    returns: tuple[str, str],
) -> list[str]:
    """The body's own C function (`head` its declaration): the frame, `setup`, its chunks
    in turn, `cleanup`, then `returns` (on success, on an error: the traceback names the
    line the frame holds)."""
    name = body.c_name
    return [
        *head.split("\n"),
        "{",
        f"    {name}_frame frame;",
        f"    {name}_frame *f = &frame;",
        "    int done = 0;",
        "    memset(f, 0, sizeof frame);",
        f"    f->line = {func.line};",
        *setup,
        *(f"    if ((done = {chunk}(s, f)) != 0) goto padt_end;" for chunk in chunk_names),
        "padt_end:",
        "    if (done < 0) goto padt_error;",
        *cleanup,
        f"    {returns[0]}",
        "padt_error:",
        f"    _PyTraceback_Add({c_string(body.qualname)}, "
        f"{c_string(body.module.filename)}, f->line);",
        *cleanup,
        f"    {returns[1]}",
        "}",
    ]


def _frame(body: _Body, name: str, fields: list[str]) -> list[str]:
    """The frame the chunks of a body share: the line, `fields`, the Python locals."""
    return [
        "typedef struct {",
        "    int line;",
        *(f"    {field}" for field in fields),
        *(f"    {field}" for field in body.frame.values()),
        f"}} {name}_frame;",
        "",
    ]


def _chunk_functions(
    body: _Body, name: str, instance: str, prologue: list[str]
) -> tuple[list[str], list[str]]:
    """The names and C texts of a body's chunks, each taking the instance (`instance`, its
    C declaration) and the frame, and beginning with `prologue`; each returns 0 to go on,
    1 where the body returned, -1 on an error (the line in the frame)."""
    names: list[str] = []
    texts: list[str] = []
    for n, lines in enumerate(_chunks(body)):
        used = set(_TEMP.findall("\n".join(lines)))
        temps = [decl for temp, decl in body.decls.items() if temp in used]
        owned = [temp for temp in body.objects if temp in used]
        cleanup = [f"    Py_XDECREF({temp});" for temp in owned]
        chunk = f"{name}_{n}"
        names.append(chunk)
        texts.append(
            "\n".join(
                [
                    "static __attribute__((noinline)) int",
                    f"{chunk}({instance}, {name}_frame *f)",
                    "{",
                    "    int padt_line = f->line;",
                    "    int padt_breath = PADT_BREATH;",
                    *(f"    {line}" for line in prologue),
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
    return names, texts


def _function_name(class_name: str) -> str:
    return f"F_{_identifier(class_name)}"


@dataclass(frozen=True)
class Mode:
    """How the C of a unit is made: slot mode's (here: bodies on the slots of Python
    objects) or image mode's (image_body.py: bodies on a memory image)."""

    body: type[_Body]
    function_text: Callable[[_Body, _Numbered], str]
    module_text: Callable[[_Module, list[tuple[str, str]]], str]


def translate_unit(
    unit: PouCode,
    form: Unit,
    classes: dict[str, ClassInfo],
    globals_class: str | None,
    functions: dict[str, FunctionInfo] | None = None,
) -> Translated:
    """The C module of one unit, of typed form `form` (`unit.unit`): the `__call__` of its
    class when it can be translated (calling the FUNCTIONs of `functions` as Python code)."""
    module = _Module(
        classes, code_filename(unit), globals_class=globals_class, functions=functions or {}
    )
    return translate_with(unit, form, module, SLOT_MODE)


def translate_with(unit: PouCode, form: Unit, module: _Module, mode: Mode) -> Translated:
    """The C module of one unit in `mode`, its statics in `module`."""
    bodies: list[tuple[str, str]] = []  # (class name, C text)
    left: list[tuple[str, str]] = []
    functions_of = form.functions if isinstance(form, Class) else ()
    for call in (f for f in functions_of if isinstance(f, Function) and f.name == "__call__"):
        assert isinstance(form, Class)
        body_name = f"{form.name}.__call__"
        info = module.classes.get(form.name)
        if info is None:
            left.append((body_name, "a class the artifact does not describe"))
            continue
        try:
            bodies.append((form.name, _translate_body(module, info, _numbered(form, call), mode)))
        except NotTranslated as reason:
            left.append((body_name, str(reason)))
        except RecursionError:
            left.append((body_name, "an expression nested too deep"))
    if not bodies:
        return Translated(unit.name, "", "", (), tuple(left))
    source = mode.module_text(module, bodies)
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
    writer = "native code of {}: written by runtime/code/native/translate.py"
    lines = module_start(module, writer, functions)
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
        "    PyObject *ns, *breathe, *functions, *bodies;",
        '    if (!PyArg_ParseTuple(args, "OOO", &ns, &breathe, &functions)) return NULL;',
        "    if (padt_bind_common(ns, breathe) < 0 || padt_bind_functions(functions) < 0)",
        "        return NULL;",
        *module.binding(),
        "    if ((bodies = PyDict_New()) == NULL) return NULL;",
    ]
    for n, (cls, _) in enumerate(functions):
        lines.append(
            f"    if (padt_add_method(bodies, {c_string(cls)}, &M{n}) < 0) "
            "{ Py_DECREF(bodies); return NULL; }"
        )
    return "\n".join(lines + module_end())


def module_start(module: _Module, what: str, functions: list[tuple[str, str]]) -> list[str]:
    """The beginning of a module's text: what it is (`what`: the code and who writes it),
    its statics, its bodies' functions."""
    lines = [
        c_comment(what.format(module.filename)),
        '#include "padt_native.h"',
        "",
        *module.statics(),
        "",
    ]
    for _, text in functions:
        lines += [text, ""]
    return lines


def module_end() -> list[str]:
    """The end of a module's text: `bind` returns the bodies, and the module itself."""
    return [
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


SLOT_MODE = Mode(_Body, _function_text, _module_text)
