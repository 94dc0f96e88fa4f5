"""Image mode of the translator (issue 34, step 5: docs/native-code.md, "Variables in
native memory"): the C of a body that reads and writes its variables in a memory image, at
the offsets of the layouts (runtime/contract/layout.py), instead of the slots of Python
objects.

Everything but the variables is translate.py's: the same kinds, the same proofs that every
integer fits its C type, the same faults at the same printed lines. What differs:

- an instance is the address of its bytes (`char *`); a member is read and written at its
  offset, as its C type (a BOOL one byte, an INT an `int16_t`...), with no check on the
  way in (every bit pattern of the image is a value), and a store is range-checked where
  the value is not proven in range, as in slot mode;
- a STRING is read as a str and written back with its length and characters checked
  (padt_image.h); an array's element is at its offset, out of bounds the fault a Python
  list gives (a negative index counted from the end, as a list counts it); a structure or
  array assigned whole is copied with `memmove` (`_copy` copies nothing more);
- a block's call goes to the callee's C body (found once per call site in the registry of
  bodies), or to the `__call__` of a view of it where its body is Python.

An instance given to Python (a method or property accessor called on it, a FUNCTION or a
helper of the runtime's it is passed to) is a view of it; an SFC step's time and entry and
an action control block's update are C on their bytes (padt_native.h, asserted to match
the runtime's fixed layouts), as the runtime's Python classes do them.

Not yet in image mode (the body is left to Python, with the reason): references,
interfaces and in-outs of aggregates, and an array passed to Python code.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

from runtime.code.fault_location import code_filename
from runtime.code.native.kinds import (
    FULL64,
    Array,
    Bool,
    ClassInfo,
    Float,
    FunctionInfo,
    Instance,
    Int,
    Kind,
    Outputs,
    Results,
    Text,
)
from runtime.code.native.layout_c import C_TYPES
from runtime.code.native.translate import (
    Mode,
    Translated,
    V,
    _Body,
    _chunk_functions,
    _frame,
    _function_name,
    _identifier,
    _is_super_call,
    _kind_name,
    _Module,
    _Numbered,
    _refuse,
    _vector_call,
    body_function,
    c_comment,
    c_string,
    module_end,
    module_start,
    translate_with,
)
from runtime.contract.artifact import PouCode
from runtime.contract.code.typed_form import Call, Expr, Index, Member, Named
from runtime.contract.code.units import Unit
from runtime.contract.intrinsic_table import COPY, FILL
from runtime.contract.layout import (
    ACTION_CONTROL,
    NULLABLE_TIME,
    RUNTIME_CLASSES,
    SFC_STEP,
    Bound,
    Chars,
    Elements,
    Layout,
    Layouts,
    Nested,
    Scalar,
    Shape,
    size_and_align,
)
from runtime.contract.layout import Member as LayoutMember

# what the reason of a body left to Python says when image mode is the cause: slot mode
# makes such a body C, so a configuration with one stays on slots (tier.py)
NOT_YET = "not yet in image mode"


@dataclass
class _ImageModule(_Module):
    layouts: Layouts = field(default_factory=dict)
    view_classes: dict[str, str] = field(default_factory=dict)  # class -> C static
    # classes laid out as the runtime's SFC classes, whose C struct (padt_native.h) the
    # module asserts to match the layout
    asserted: set[str] = field(default_factory=set)
    initials: dict[str, str] = field(default_factory=dict)  # structure class -> C static

    def size(self, shape: Shape) -> int:
        return size_and_align(shape, self.layouts.__getitem__)[0]

    def layout(self, cls: str) -> Layout:
        found = self.layouts.get(cls)
        if found is None:
            _refuse(f"the class {cls}, which has no layout")
        return found

    def view_class(self, cls: str) -> str:
        """The C static of the view class of `cls`, bound with the module."""
        self.layout(cls)
        return self.view_classes.setdefault(cls, f"V{len(self.view_classes)}")

    def initial(self, cls: str) -> str:
        """The C static of the bytes of a structure of `cls` made afresh, made as the module
        binds (padt_instance_initial)."""
        self.view_class(cls)
        return self.initials.setdefault(cls, f"INIT{len(self.initials)}")

    def statics(self) -> list[str]:
        lines = [
            line.replace("static padt_site ", "static padt_msite ") for line in super().statics()
        ]
        views = self.view_classes.items()
        lines += [f"static PyObject *{ref}; {c_comment(cls)}" for cls, ref in views]
        lines += [
            f"static _Alignas(8) unsigned char {ref}[{self.size(Nested(cls))}]; {c_comment(cls)}"
            for cls, ref in self.initials.items()
        ]
        for cls in sorted(self.asserted):
            layout = self.layouts[cls]
            struct = _RUNTIME_STRUCTS[tuple(m.name for m in layout.members)]
            lines += [
                f"_Static_assert(offsetof({struct}, {m.name}) == {m.offset}, {c_string(cls)});"
                for m in layout.members
            ]
            lines.append(f"_Static_assert(sizeof({struct}) == {layout.size}, {c_string(cls)});")
        return lines

    def binding(self) -> list[str]:
        return (
            super().binding()
            + [
                f"    if (({ref} = PyDict_GetItemString(padt_views, {c_string(cls)})) == NULL) {{"
                f' PyErr_SetString(PyExc_TypeError, "native code: no view class {cls}");'
                " return NULL; }"
                for cls, ref in self.view_classes.items()
            ]
            + [
                f"    if (padt_instance_initial({self.view_classes[cls]}, {c_string(cls)},"
                f" (char *){ref}, {self.size(Nested(cls))}) < 0) return NULL;"
                for cls, ref in self.initials.items()
            ]
        )


# an action control block's flags and times, in padt_action_update's order
_FLAGS = ("N", "R", "S", "P", "P0", "P1", "L", "D", "SD", "DS", "SL")
_TIMES = ("TL", "TD", "TSD", "TDS", "TSL")
_RUNTIME_MEMBERS = {
    name: [member for member, _ in fields] for name, fields in RUNTIME_CLASSES.items()
}
_RUNTIME_STRUCTS = {
    tuple(_RUNTIME_MEMBERS[SFC_STEP]): "padt_sfc_step",
    tuple(_RUNTIME_MEMBERS[ACTION_CONTROL]): "padt_action_control",
}


class _ImageBody(_Body):
    module: _ImageModule
    context = "padt_ctx"
    objects_direct = False  # a structure here is bytes of the image, not an object
    instance_ctype = "char *"

    def runs_on(self, owner: V, info: FunctionInfo) -> str | None:
        """A method's C body works on the bytes of an instance of its class, or of a
        block that extends it (whose bytes begin with its members): an instance variable
        in native memory holds one of its declared type, so the call checks nothing ("");
        not on this body's own instance where a derived block overrides a method (whose
        bytes may be a derived instance's, `instance_object`)."""
        assert isinstance(owner.kind, Instance)
        if owner.c == "s" and self.cls.overridden:
            return None
        if owner.kind.cls == info.owner:
            return ""
        own, theirs = self.module.layouts.get(owner.kind.cls), self.module.layouts.get(info.owner)
        if own is None or theirs is None:
            return None
        return "" if own.members[: len(theirs.members)] == theirs.members else None

    # -- reading and writing the image
    def member_value(self, owner: V, attr: str) -> V:
        assert isinstance(owner.kind, Instance)
        member = self.member(owner.kind.cls, attr)
        kind = self.member_kind(owner.kind, attr)
        return self.read(f"({owner.c} + {member.offset})", member.shape, kind, attr)

    def store_member(self, owner: V, attr: str, value: V) -> None:
        assert isinstance(owner.kind, Instance)
        member = self.member(owner.kind.cls, attr)
        kind = self.member_kind(owner.kind, attr)
        at = f"({owner.c} + {member.offset})"
        self.write(at, member.shape, kind, value, f"{owner.kind.cls}.{attr}")

    def member(self, cls: str, attr: str) -> LayoutMember:
        layout = self.module.layout(cls)
        for member in layout.members:
            if member.name == attr:
                return member
        _refuse(f"the variable {attr}, which {cls}'s layout does not have")

    def read(self, at: str, shape: Shape, kind: Kind, what: str) -> V:
        """The value of `kind` whose bytes, of `shape`, are at `at`."""
        match shape, kind:
            case Scalar(code=code), Bool() if code == "?":
                return V(kind, f"(*(uint8_t *){at} != 0)")
            case Scalar(code=code), Int() if code not in ("?", "f", "d", NULLABLE_TIME):
                return V(kind, f"(({kind.ctype})*({C_TYPES[code]} *){at})")
            case Scalar(code=code), Float() if code in ("f", "d"):
                return V(kind, f"((double)*({C_TYPES[code]} *){at})")
            case Chars(length=length, wide=wide), Text():
                return self.owned(kind, f"padt_chars_get({at}, {length}, {int(wide)})")
            case Nested(cls=cls), Instance() if cls == kind.cls:
                return V(kind, at)
            case Elements(), Array():
                return V(kind, at, shape)
            case Bound(target=target), (Instance() | Array()):
                return self.read(self.bound_address(at, target), target, kind, what)
        _refuse(f"{what}, a {_kind_name(kind)} laid out as {type(shape).__name__}")

    def bound_address(self, at: str, target: Shape) -> str:
        """Where the block's in-out at `at` is bound: the variable of the image a call bound
        it to, or its own storage (layout.Bound)."""
        size, _ = size_and_align(target, self.module.layouts.__getitem__)
        offset = self.temp("uint32_t")
        self.line(f"{offset} = *(uint32_t *){at};")
        self.line(f"if (PADT_UNLIKELY({offset} == 0 || {offset} > padt_ctx->size - {size})) {{")
        self.line("    padt_unbound_error();")
        self.line("    goto padt_error;")
        self.line("}")
        return f"(padt_ctx->base + {offset})"

    def write(self, at: str, shape: Shape, declared: Kind, value: V, what: str) -> None:
        """`value` into the bytes, of `shape`, at `at` of a variable of `declared`."""
        match shape, declared, value.kind:
            case Scalar(code="?"), Bool(), Bool():
                self.line(f"*(uint8_t *){at} = (uint8_t)(({value.c}) != 0);")
                return
            case Scalar(code=code), Float(), Float() if code in ("f", "d"):
                self.line(f"*({C_TYPES[code]} *){at} = ({C_TYPES[code]})({value.c});")
                return
            case Scalar(code=code), Int(), Int() if code not in ("?", "f", "d", NULLABLE_TIME):
                self.storable(value, declared, what)
                self.line(f"*({C_TYPES[code]} *){at} = ({C_TYPES[code]})({value.c});")
                return
            case Chars(length=length, wide=wide), Text(), Text():
                self.check(f"padt_chars_set({at}, {length}, {int(wide)}, {value.c})")
                return
            case Elements(), Array(), Array() if value.kind == declared and value.shape is None:
                # an array Python code gave back (an in-out's value after the call)
                described = self.list_shape(shape)
                if described is None:
                    _refuse(f"{what}, an array of instances from Python ({NOT_YET})")
                self.check(f"padt_list_into({at}, {c_string(described)}, {value.c})")
                return
            case Bound(target=target), (Instance() | Array()), _ if value.kind == declared:
                if value.shape is None and isinstance(value.kind, Array):
                    _refuse(f"{what}, an in-out bound to an array from Python ({NOT_YET})")
                if not value.copied:  # a call binding the in-out to a variable of the image
                    self.line(f"*(uint32_t *){at} = (uint32_t)({value.c} - padt_ctx->base);")
                    return
                # a copy given to a block's in-out of a block (`fb.m := other`): into its
                # own storage, bound there, as the slot tier binds it to the copy's object
                own = f"({at} + {shape.own(self.module.layouts.__getitem__)})"
                self.write(own, target, declared, value, what)
                self.line(f"*(uint32_t *){at} = (uint32_t)({own} - padt_ctx->base);")
                return
            case ((Nested() | Elements()), (Instance() | Array()), _) if value.kind == declared:
                # a structure or array assigned whole: the bytes copied (they may overlap)
                if self.holds_in_out(shape):  # whose offsets would point at the source's
                    _refuse(f"{what}, an instance with in-outs assigned whole ({NOT_YET})")
                size, _ = size_and_align(shape, self.module.layouts.__getitem__)
                self.line(f"memmove({at}, {value.c}, {size});")
                return
        _refuse(f"a {_kind_name(value.kind)} stored into {_kind_name(declared)}")

    def holds_in_out(self, shape: Shape) -> bool:
        """Whether a value of `shape` holds a block's in-out (`Bound`): a copy of its bytes
        would be bound where the original is, or to the original's own storage."""
        match shape:
            case Bound():
                return True
            case Elements(element=element):
                return self.holds_in_out(element)
            case Nested(cls=cls):
                return any(self.holds_in_out(m.shape) for m in self.module.layout(cls).members)
        return False

    def subscript(self, node: Index) -> V:
        array = self.expr(node.base)
        if isinstance(array.kind, Outputs | Results):
            return super().subscript(node)
        at, shape, kind = self.element(array, node.offset)
        return self.read(at, shape, kind, "an array element")

    def store_element(self, array: V, index_node: Expr, value: V) -> None:
        at, shape, kind = self.element(array, index_node)
        self.write(at, shape, kind, value, "an array element")

    def element(self, array: V, index_node: Expr) -> tuple[str, Shape, Kind]:
        """Where an element of `array` is, its shape and its kind; out of bounds the fault
        of a Python list (a negative offset counted from the end first, as a list does)."""
        if isinstance(array.kind, Array) and array.shape is None:  # a list from Python
            _refuse(f"an index into an array from Python ({NOT_YET})")
        if (
            not isinstance(array.kind, Array)
            or array.kind.element is None
            or not isinstance(array.shape, Elements)
        ):
            _refuse("an index into something else than an array the tier knows")
        count = array.shape.count
        stride, _ = size_and_align(array.shape.element, self.module.layouts.__getitem__)
        index = self.int_value(index_node)
        assert isinstance(index.kind, Int)
        offset = index.c
        if not index.kind.within(Int(0, count - 1)):
            offset = self.temp("int64_t")
            self.line(f"{offset} = {index.c};")
            self.line(f"if ({offset} < 0) {offset} += {count};")
            self.line(f"if (PADT_UNLIKELY((uint64_t){offset} >= {count}U)) {{")
            self.line("    padt_index_error();")
            self.line("    goto padt_error;")
            self.line("}")
        at = f"({array.c} + {offset} * {stride})"
        return at, array.shape.element, array.kind.element

    def new_structure(self, cls: str) -> V:
        """`STRUCT_X()`: the bytes of a fresh one, made once as the module binds; a value
        to copy (`copied`), never to write into."""
        return V(Instance(cls), f"((char *){self.module.initial(cls)})", copied=True)

    def list_literal(self, items: tuple[Expr, ...], declared: str) -> V:
        _refuse("a list of values (an object, not bytes of the image)")

    def repeated(self, item: Expr, count: int, declared: str) -> V:
        _refuse("a list of values (an object, not bytes of the image)")

    def copy(self, node: Expr) -> V:
        """`_copy(x)`: the store copies the bytes of what is assigned whole."""
        value = self.expr(node)
        if not isinstance(value.kind, Instance | Array):
            _refuse(f"a copy of a {_kind_name(value.kind)}")
        return replace(value, copied=True)

    def system_value(self, name: str) -> V:
        """`_SYS.now_ns` read once per call from Python (every timer of a program reads
        it), and again after the slice meter, which may resume the program later."""
        if name != "now_ns":
            return super().system_value(name)
        held = self.temp("int64_t")
        self.check(f"padt_mnow(padt_ctx, padt_sys, {self.module.key(name)}, &{held})")
        return V(FULL64, held)

    def tick_read(self, key: str) -> str:
        """`_tick` read once per call (every loop reads it: a dictionary lookup each, a
        third of the benchmark program's body), and again after the slice meter."""
        return f"padt_mtick(padt_ctx, {key})"

    def call_hook(self, hook: V) -> None:
        super().call_hook(hook)
        self.line("padt_ctx->now_known = padt_ctx->tick_known = 0;")

    def call_statement(self, call: Expr) -> None:
        """SUPER^(): the base's body on this very instance, whose bytes begin with the
        base's members (layout.py), as C where the base's body is C."""
        if (
            isinstance(call, Call)
            and _is_super_call(call)
            and isinstance(call.callee, Member)
            and isinstance(call.callee.base, Named)
            and call.callee.name == "__call__"
            and len(call.args) == 1
        ):
            base = call.callee.base.name
            own, theirs = self.module.layout(self.cls.name), self.module.layout(base)
            if own.members[: len(theirs.members)] != theirs.members:
                _refuse(f"{self.cls.name} does not begin with the members of {base}")
            site, key = self.module.site(), self.module.key(base)
            self.check(f"padt_mcall(&{site}, {key}, s, padt_ctx)")
            return
        super().call_statement(call)

    def call_instance(self, target: V) -> None:
        assert isinstance(target.kind, Instance)
        self.module.layout(target.kind.cls)
        key = self.module.key(target.kind.cls)
        self.check(f"padt_mcall(&{self.module.site()}, {key}, {target.c}, padt_ctx)")

    # -- locals that hold an instance: its address
    def local_ref(self, name: str) -> str:
        kind = self.local_kind(name)
        if isinstance(kind, Instance):
            c = f"l_{_identifier(name)}"
            self.frame.setdefault(c, f"char *{c};")
            return f"f->{c}"
        if isinstance(kind, Array):  # bytes of the image, which a local does not hold yet
            _refuse(f"local {name} holds an array")
        return super().local_ref(name)

    def keep(self, local: str, value: V) -> None:
        """An instance into a local: where it is (an instance of the image, an alias), or,
        a value of its own (a copy, a fresh structure, a FUNCTION's result), its bytes into
        the local's own bytes of the frame (a FUNCTION's structure, function_body.py)."""
        if isinstance(value.kind, Instance) and value.copied:
            size = self.module.size(Nested(value.kind.cls))
            own = self.frame_buffer(local.removeprefix("f->"), size)
            self.line(f"memmove({own}, {value.c}, {size});")
            self.line(f"{local} = {own};")
            return
        if isinstance(value.kind, Instance):
            self.line(f"{local} = {value.c};")
            return
        super().keep(local, value)

    def frame_buffer(self, name: str, size: int) -> str:
        """Bytes of the frame, aligned as the image's, that a structure of a FUNCTION's own
        lives in (a parameter's copy, a local, a call's result)."""
        c = f"b_{_identifier(name)}"
        self.frame.setdefault(c, f"_Alignas(8) unsigned char {c}[{size}];")
        return f"((char *)f->{c})"

    # -- a FUNCTION's structures: bytes, not objects (function_body.py)
    def out_temp(self, kind: Kind) -> str:
        if isinstance(kind, Instance):  # bytes of the frame, which the callee writes
            return self.frame_buffer(f"r{len(self.frame)}", self.module.size(Nested(kind.cls)))
        return super().out_temp(kind)

    def param_ctype(self, kind: Kind) -> str:
        return "char *" if isinstance(kind, Instance) else super().param_ctype(kind)

    def out_ctype(self, kind: Kind) -> str:
        return "char *" if isinstance(kind, Instance) else super().out_ctype(kind)

    def out_arg(self, kind: Kind, out: str) -> str:
        return out if isinstance(kind, Instance) else super().out_arg(kind, out)

    def given_back(self, out: str, obj: str, kind: Kind, what: str) -> None:
        """A structure a FUNCTION's Python gave: into the bytes its C would have written,
        each member checked as a store is."""
        if isinstance(kind, Instance):
            view_class = self.module.view_class(kind.cls)
            size = self.module.size(Nested(kind.cls))
            self.check(f"padt_instance_into({view_class}, {out}, {size}, {obj})")
            return
        super().given_back(out, obj, kind, what)

    # -- the runtime's SFC classes, in C on their bytes (padt_native.h)
    def helper_call(self, name: str, node: Call) -> V:
        if name == "_step_time" and len(node.args) == 2:
            step, now = self.sfc_instance(node.args[0], SFC_STEP), self.int_value(node.args[1])
            return V(FULL64, f"padt_step_time({step}, {now.c})")
        return super().helper_call(name, node)

    def helper_statement(self, callee: str, call: Call) -> None:
        if callee == "_step_enter" and len(call.args) == 1:
            self.line(f"padt_step_enter({self.sfc_instance(call.args[0], SFC_STEP)});")
            return
        if callee == FILL.name and len(call.args) == 2:
            # `_fill(x, v)`: v's bytes into x's (where a block's in-out is bound, there)
            target, value = self.expr(call.args[0]), self.expr(call.args[1])
            shape = Nested(target.kind.cls) if isinstance(target.kind, Instance) else target.shape
            if shape is None:
                _refuse(f"{FILL.name} of a {_kind_name(target.kind)}")
            self.write(target.c, shape, target.kind, value, "an array or structure written whole")
            return
        super().helper_statement(callee, call)

    def function_call(self, node: Call) -> tuple[FunctionInfo, str]:
        callee = node.callee
        if isinstance(callee, Member) and callee.name == "update" and len(node.args) == 1:
            control = self.sfc_instance(callee.base, ACTION_CONTROL)
            now = self.int_value(node.args[0])
            given = dict(node.keywords)
            if not given.keys() <= set(_FLAGS + _TIMES):
                _refuse(f"an action control block told {sorted(given)}")
            flags = [self.flag(given[name]) if name in given else "0" for name in _FLAGS]
            times = [self.int_value(given[name]).c if name in given else "0" for name in _TIMES]
            args = ", ".join([control, now.c, *flags, *times])
            self.line(f"padt_action_update({args});")
            return FunctionInfo("update", None), "Py_None"
        return super().function_call(node)

    def sfc_instance(self, node: Expr, runtime_class: str) -> str:
        """Where an SFC step or action control block is (its layout the runtime's fixed
        one, which padt_native.h's struct is asserted to match)."""
        value = self.expr(node)
        if not isinstance(value.kind, Instance):
            _refuse(f"{runtime_class} of a {_kind_name(value.kind)}")
        layout = self.module.layout(value.kind.cls)
        if [m.name for m in layout.members] != _RUNTIME_MEMBERS[runtime_class]:
            _refuse(f"{value.kind.cls} laid out otherwise than the runtime's {runtime_class}")
        self.module.asserted.add(value.kind.cls)
        return value.c

    def flag(self, node: Expr) -> str:
        value = self.expr(node)
        if not isinstance(value.kind, Bool):
            _refuse("an action qualifier's flag that is no BOOL")
        return f"({value.c})"

    # -- instances given to Python: as views
    def instance_object(self, value: V) -> str:
        assert isinstance(value.kind, Instance)
        if value.c == "s" and self.cls.overridden:
            # this body may run on an instance of a derived block (its SUPER^()), whose
            # bytes do not say so: a view of this class would find this class's methods,
            # where the derived block overrides some
            method = sorted(self.cls.overridden)[0]
            why = f"its own instance given to Python, a derived block overriding {method}"
            _refuse(f"{why} ({NOT_YET})")
        view_class = self.module.view_class(value.kind.cls)
        size = self.module.size(Nested(value.kind.cls))
        return self.owned_object(f"padt_instance_object(padt_ctx, {view_class}, {value.c}, {size})")

    def boxed(self, value: V, callee: str) -> str:
        """An instance passed to Python code (a method, a FUNCTION, the runtime's SFC
        helpers) is a view of it; one the code passes as `_copy(x)` (a structure given as
        an input) a copy of its bytes, detached from the image, as Python's `_copy` gives
        a copy of the object: what the callee writes into it is its own."""
        if isinstance(value.kind, Instance):
            view = self.instance_object(value)
            if value.copied:
                return self.owned_object(_vector_call(self.module.key(COPY.name), [view]))
            return view
        if isinstance(value.kind, Array):
            shape = self.list_shape(value.shape) if value.copied else None
            if shape is None:
                _refuse(f"an array passed to {callee} ({NOT_YET})")
            return self.owned_object(f"padt_list_from({value.c}, {c_string(shape)})")
        return super().boxed(value, callee)

    def list_shape(self, shape: Shape | None) -> str | None:
        """What padt_list_of reads of an array of elementary values or texts (padt_image.h);
        None for any other (its elements instances: views would share the image's bytes)."""
        match shape:
            case Scalar(code=code) if code != NULLABLE_TIME:
                return code
            case Chars(length=length, wide=wide):
                return f"{'w' if wide else 's'}{length};"
            case Elements(element=element, count=count):
                inner = self.list_shape(element)
                if inner is None:
                    return None
                stride, _ = size_and_align(element, self.module.layouts.__getitem__)
                inner = f"[{inner}]" if isinstance(element, Elements) else inner
                return f"{count}x{stride}:{inner}"
        return None

    # -- what image mode does not do yet

    def unboxed(self, obj: str, kind: Kind, what: str) -> V:
        """An array from Python code is the list itself (no `shape`), which only a store of
        the whole array takes (`write`)."""
        if isinstance(kind, Array):  # owned: until the store has read it
            held = self.temp("PyObject *", "NULL")
            self.line(f"Py_XSETREF({held}, Py_XNewRef({obj}));")
            return V(kind, held)
        if isinstance(kind, Instance):
            _refuse(f"{what}, an instance from Python ({NOT_YET})")
        return super().unboxed(obj, kind, what)

    def reference(self, node: Call) -> V:
        _refuse(f"a reference ({NOT_YET})")

    def dereference(self, node: Expr) -> V:
        _refuse(f"a reference ({NOT_YET})")


def _image_function_text(body: _Body, func: _Numbered) -> str:
    """The body as C in image mode: its chunks as in slot mode, and the body's own
    function, `int F(char *s, padt_mctx *ctx)`, which C callers call directly."""
    head = f"static int\n{_function_name(body.cls.name)}(char *s, padt_mctx *ctx)"
    entry = ["    if (padt_stack_check() < 0) return -1;"]  # a recursion (padt_native.h)
    return image_function_text(body, func, head, [], entry, ("return 0;", "return -1;"))


def image_function_text(
    body: _Body,
    func: _Numbered,
    head: str,
    fields: list[str],
    entry: list[str],
    returns: tuple[str, str],
) -> str:
    """The C of a body in image mode, `head` its declaration (which declares `s` and `ctx`),
    with `fields` in its frame, set by `entry` as it begins (before the frame takes `ctx`);
    `returns` as body_function's."""
    name = body.c_name
    frame = _frame(body, name, ["char *g;", "PyObject *sys;", "padt_mctx *ctx;", *fields])
    prologue = [
        "char *padt_g = f->g;",
        "PyObject *padt_sys = f->sys;",
        "padt_mctx *padt_ctx = f->ctx;",
        "(void)padt_ctx;",
    ]
    chunk_names, chunk_texts = _chunk_functions(body, name, "char *s", prologue)
    setup: list[str] = []
    if body.uses_globals:
        setup += [
            "    f->g = ctx->g;",
            "    if (f->g == NULL) {",
            '        PyErr_SetString(PyExc_TypeError, "native code: _G is no view of the image");',
            "        goto padt_error;",
            "    }",
        ]
    if any("padt_sys" in line for line in body.out):
        setup += [
            "    f->sys = ctx->sys;  /* borrowed: the namespace holds it during the call */",
            "    if (f->sys == NULL) {",
            '        PyErr_SetString(PyExc_NameError, "native code: no _SYS");',
            "        goto padt_error;",
            "    }",
        ]
    cleanup = [f"    Py_XDECREF(f->{o});" for o in body.frame_objects]
    setup[:0] = [*entry, "    f->ctx = ctx;"]
    main = body_function(body, func, head, setup, chunk_names, cleanup, returns)
    return "\n".join([*frame, *chunk_texts, *main])


def translate_image_unit(
    unit: PouCode,
    form: Unit,
    classes: dict[str, ClassInfo],
    globals_class: str | None,
    layouts: Layouts,
    functions: dict[str, FunctionInfo] | None = None,
) -> Translated:
    """The C module of one unit in image mode: the `__call__` of its class, working on the
    image at `layouts`' offsets, when it can be translated."""
    module = _ImageModule(
        classes,
        code_filename(unit),
        globals_class=globals_class,
        functions=functions or {},
        layouts=layouts,
    )
    return translate_with(unit, form, module, IMAGE_MODE)


def _image_module_text(module: _Module, functions: list[tuple[str, str]]) -> str:
    writer = "image-mode code of {}: written by runtime/code/native/image_body.py"
    lines = module_start(module, writer, functions)
    # the view class of each body, bound once
    lines += [f"static PyObject *VC{n}; {c_comment(cls)}" for n, (cls, _) in enumerate(functions)]
    for n, (cls, _) in enumerate(functions):
        # the entry from Python: a view of the class, the context from it
        lines += [
            "static PyObject *",
            f"W{n}(PyObject *view, PyObject *ignored)",
            "{",
            "    padt_mctx ctx;",
            f"    if (!PyObject_TypeCheck(view, (PyTypeObject *)VC{n})) {{",
            f'        PyErr_SetString(PyExc_TypeError, "native code: a body of {cls} called on'
            ' another object");',
            "        return NULL;",
            "    }",
            "    if (padt_mctx_enter(&ctx, view) < 0) return NULL;",
            f"    if ({_function_name(cls)}(ctx.base + ((padt_view *)view)->offset, &ctx) < 0)",
            "        return NULL;",
            "    Py_RETURN_NONE;",
            "}",
            "",
            f'static PyMethodDef M{n} = {{"__call__", (PyCFunction)W{n}, METH_NOARGS, NULL}};',
            "",
        ]
    lines += [
        "static PyObject *",
        "padt_bind(PyObject *module, PyObject *args)",
        "{",
        "    PyObject *ns, *breathe, *views, *registry, *view_type, *bodies;",
        '    if (!PyArg_ParseTuple(args, "OOOOO", &ns, &breathe, &views, &registry, &view_type))',
        "        return NULL;",
        "    if (padt_bind_common(ns, breathe) < 0) return NULL;",
        "    if (padt_bind_image(views, registry, view_type) < 0) return NULL;",
        *module.binding(),
        "    if ((bodies = PyDict_New()) == NULL) return NULL;",
    ]
    for n, (cls, _) in enumerate(functions):
        lines += [
            f"    if ((VC{n} = PyDict_GetItemString(views, {c_string(cls)})) == NULL) {{",
            f'        PyErr_SetString(PyExc_TypeError, "native code: no view class {cls}");',
            "        Py_DECREF(bodies);",
            "        return NULL;",
            "    }",
            f"    if (padt_register({c_string(cls)}, {_function_name(cls)}) < 0"
            f" || padt_add_view_method(bodies, {c_string(cls)}, &M{n}) < 0)",
            "        { Py_DECREF(bodies); return NULL; }",
        ]
    return "\n".join(lines + module_end())


IMAGE_MODE = Mode(_ImageBody, _image_function_text, _image_module_text)
