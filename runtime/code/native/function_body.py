"""A FUNCTION's (or a method's) own body as C, on slots and in image mode (issue 34, step
6: docs/native-code.md, "FUNCTION bodies as C").

A FUNCTION whose inputs, in-outs, result and outputs are all numbers, BOOLs, texts,
structures or arrays of fixed bounds (`FunctionInfo.native`; in image mode not arrays,
`in_image`) gets a C function of its body,

    int F(padt_mctx *ctx, <its parameters as C values>, <a pointer per result and output>)

where a text, and on slots a structure or an array, is a Python object, and in image mode
a structure the address of its bytes. Its module puts it into the registry by the
FUNCTION's name and C signature (`kinds.native_key`). A call site of C finds it once and
calls it directly
(translate.py, `direct_function_call`): no boxing, no tuple, no Python frame. Python code
(the Python tier, a body left to Python, a debugged resource) still calls the FUNCTION's
Python, which stays the reference: both are made from the same typed form.

The body is image mode's translation (its locals C values in its frame; `_tick`, `_SYS`
and the globals from the caller's context), but for three things: the parameters begin as
the values given, of their declared kinds; a `return` writes the result and outputs
through the pointers; a fault adds the FUNCTION's own frame to the traceback, so that it
names the FUNCTION's ST line, as on the Python tier.
"""

from __future__ import annotations

import hashlib

from runtime.code.fault_location import code_filename
from runtime.code.native.image_body import (
    NOT_YET,
    _ImageBody,
    _ImageModule,
    image_function_text,
)
from runtime.code.native.kinds import (
    Array,
    Bool,
    ClassInfo,
    Float,
    FunctionInfo,
    Instance,
    Int,
    Kind,
    Nothing,
    Text,
    kind_of_type,
)
from runtime.code.native.translate import (
    NAME_PLACEHOLDER,
    NotTranslated,
    Translated,
    V,
    _Body,
    _ctype,
    _identifier,
    _is_none,
    _is_object,
    _kind_name,
    _Module,
    _Numbered,
    _numbered,
    _refuse,
    c_string,
    module_end,
    module_start,
    returned_items,
    settled,
    slot_function_text,
)
from runtime.contract.artifact import PouCode
from runtime.contract.code.statements import Assign, ForEach, If, Return, Stmt, While
from runtime.contract.code.typed_form import Expr, Sequence, Var
from runtime.contract.code.units import Class, Function, Unit
from runtime.contract.layout import Layouts, Nested

LEFT = (
    "a FUNCTION whose parameters, result or outputs are not all numbers, BOOLs, texts, "
    "structures or arrays of fixed bounds"
)
# in native memory an array is bytes of the image, which the C of a FUNCTION there does not
# take or give yet (never a reason to leave the image: `_refusal`)
IMAGE_LEFT = "a FUNCTION of arrays in native memory (not yet C)"


class _FunctionParts(_Body):
    """What a FUNCTION's (or a method's) body translates otherwise than a block's, in
    either mode: `info` says what it takes and gives, `declared` the kinds of its
    variables."""

    def __init__(
        self,
        module: _Module,
        cls: ClassInfo,
        func: _Numbered,
        local_kinds: dict[str, Kind],
        info: FunctionInfo,
        declared: dict[str, Kind],
    ) -> None:
        super().__init__(module, cls, func, local_kinds)
        self.info = info
        self.declared = declared

    def assign_local(self, name: str, value_node: Expr) -> None:
        """A declared variable keeps its declared kind, as a block's slot does: a value
        not proven within its range is checked (the compiler's wraps keep it there), where
        an inferred local would take the value's kind, growing pass by pass."""
        declared = self.declared.get(name)
        if declared is None:
            super().assign_local(name, value_node)
            return
        value = self.expr(value_node)
        if _is_object(declared):  # a text, structure or array: the local holds the object
            if value.kind != declared:
                _refuse(f"{name}, a {_kind_name(declared)}, takes a {_kind_name(value.kind)}")
            self.note_assigned(name, declared)
            self.keep(self.local_ref(name), value)
            return
        if isinstance(declared, Int) and isinstance(value.kind, Int):
            self.storable(value, declared, name)
        elif type(value.kind) is not type(declared):
            _refuse(f"{name}, a {_kind_name(declared)}, takes a {_kind_name(value.kind)}")
        self.note_assigned(name, declared)
        self.line(f"{self.local_ref(name)} = {value.c};")

    @property
    def qualname(self) -> str:
        function = self.func.function
        return function.name if function.method else self.cls.name

    @property
    def c_name(self) -> str:
        function = self.func.function
        own = f"_{_identifier(function.name)}" if function.method else ""
        return super().c_name + own

    @property
    def items(self) -> tuple[Int | Bool | Float | Text | Instance | Array | Nothing, ...]:
        """The kinds of what a call gives: the result, then the outputs and in-outs."""
        return returned_items(self.info)

    def returned(self, value: Expr | None) -> None:
        """The result and outputs through the caller's pointers."""
        items = self.items
        if value is None or _is_none(value):
            if items:
                _refuse("a FUNCTION that returns nothing where it has a result")
            return
        if self.info.outputs is not None:
            if not isinstance(value, Sequence) or len(value.items) != len(items):
                _refuse("a FUNCTION's return of another shape than its outputs")
            nodes = value.items
        elif len(items) == 1:
            nodes = (value,)
        else:
            _refuse("a FUNCTION without result that returns a value")
        values = [
            self.expr(node) if not isinstance(declared, Nothing) or not _is_none(node) else None
            for node, declared in zip(nodes, items, strict=True)
        ]  # all, then the stores: as a tuple
        for n, (found, declared) in enumerate(zip(values, items, strict=True)):
            if found is None:  # None where it has no result
                continue
            if isinstance(declared, Nothing):
                _refuse("a FUNCTION's return of a value where it has no result")
            what = f"what {self.cls.name} gives"
            if _is_object(declared):
                if found.kind != declared:
                    _refuse(f"a {_kind_name(found.kind)} returned as a {_kind_name(declared)}")
                self.give_object(n, found)
                continue
            if isinstance(declared, Int) and isinstance(found.kind, Int):
                self.storable(found, declared, what)
            elif type(found.kind) is not type(declared):
                _refuse(f"a {_kind_name(found.kind)} returned as a {_kind_name(declared)}")
            self.line(f"*f->o{n} = ({_ctype(declared)})({found.c});")

    def give_object(self, n: int, found: V) -> None:
        """A text, structure or array given back: a new reference into the caller's
        temporary."""
        self.line(f"Py_XSETREF(*f->o{n}, Py_NewRef({found.c}));")


class _SlotFunction(_FunctionParts):
    """A FUNCTION's body in slot mode: its context only counts the nested calls."""

    context = "f->ctx"


class _ImageFunction(_FunctionParts, _ImageBody):
    """A FUNCTION's body in image mode: a structure it takes is copied into bytes of its
    frame as it begins, one it gives is written into bytes the caller's frame holds."""

    def give_object(self, n: int, found: V) -> None:
        if isinstance(found.kind, Instance):
            self.line(f"memmove(f->o{n}, {found.c}, {self.module.size(Nested(found.kind.cls))});")
            return
        super().give_object(n, found)


def translate_function(
    unit: PouCode,
    form: Unit,
    classes: dict[str, ClassInfo],
    globals_class: str | None,
    functions: dict[str, FunctionInfo],
    layouts: Layouts | None = None,
) -> Translated:
    """The C module of one FUNCTION, when its body can be translated: in slot mode, or in
    image mode at `layouts`' offsets."""
    info = functions.get(unit.class_name)
    if info is None or not info.native or not isinstance(form, Function):
        return Translated(unit.name, "", "", (), ((unit.name, LEFT),))
    if layouts is not None and not info.in_image:
        return Translated(unit.name, "", "", (), ((unit.name, IMAGE_LEFT),))
    module = _module(unit, classes, globals_class, functions, layouts)
    try:
        made = _function_text(module, form, form, info, ClassInfo(form.name, {}))
    except NotTranslated as refused:
        return Translated(unit.name, "", "", (), ((unit.name, _refusal(refused)),))
    except RecursionError:
        return Translated(unit.name, "", "", (), ((unit.name, "an expression nested too deep"),))
    return _translated(unit, module, "the FUNCTION", [(info.native, made)], (form.name,), ())


def translate_methods(
    unit: PouCode,
    form: Unit,
    classes: dict[str, ClassInfo],
    globals_class: str | None,
    functions: dict[str, FunctionInfo],
    layouts: Layouts | None = None,
) -> Translated:
    """The C module of the methods (and property accessors) of one block's class that
    take and give numbers, BOOLs and texts, on objects or in image mode at `layouts`'
    offsets: each registered by its class, name and C signature, for the call sites of C
    to call directly. `bodies` names the methods translated; the others stay Python, as a
    caller's `left` says nothing of."""
    cls = classes.get(form.name) if isinstance(form, Class) else None
    if cls is None or not isinstance(form, Class):
        return Translated(unit.name, "", "", (), ())
    module = _module(unit, classes, globals_class, functions, layouts)
    made: list[tuple[str, tuple[str, str]]] = []
    names: list[str] = []
    left: list[tuple[str, str]] = []
    for function in form.functions:
        if not isinstance(function, Function) or function.name == "__call__":
            continue
        info = cls.methods.get(function.name)
        if info is None or not info.native or info.owner != form.name:
            continue
        try:
            made.append((info.native, _function_text(module, form, function, info, cls)))
        except NotTranslated as refused:
            left.append((function.name, _refusal(refused)))
            continue
        except RecursionError:
            left.append((function.name, "an expression nested too deep"))
            continue
        names.append(function.name)
    if not made:
        return Translated(unit.name, "", "", (), tuple(left))
    return _translated(unit, module, "the methods of", made, tuple(names), tuple(left))


def _module(
    unit: PouCode,
    classes: dict[str, ClassInfo],
    globals_class: str | None,
    functions: dict[str, FunctionInfo],
    layouts: Layouts | None,
) -> _Module:
    """The statics of a unit's module: slot mode's, or image mode's at `layouts`."""
    filename = code_filename(unit)
    if layouts is None:
        return _Module(classes, filename, globals_class=globals_class, functions=functions)
    return _ImageModule(
        classes, filename, globals_class=globals_class, functions=functions, layouts=layouts
    )


def _refusal(refused: NotTranslated) -> str:
    """Why a FUNCTION's or method's body stays Python: never a reason to leave the image
    (tier.py leaves it for a block's body only, which slot mode makes C)."""
    return str(refused).replace(NOT_YET, "not yet C")


def _translated(
    unit: PouCode,
    module: _Module,
    what: str,
    made: list[tuple[str, tuple[str, str]]],
    bodies: tuple[str, ...],
    left: tuple[tuple[str, str], ...],
) -> Translated:
    source = _module_text(module, what, made)
    name = f"padt_{hashlib.sha256(source.encode()).hexdigest()[:24]}"
    return Translated(unit.name, name, source.replace(NAME_PLACEHOLDER, name), bodies, left)


def _function_text(
    module: _Module, form: Class | Function, function: Function, info: FunctionInfo, cls: ClassInfo
) -> tuple[str, str]:
    """The C function of a FUNCTION's or method's body: its name and text."""
    gives = info.result is not None or info.outputs is not None
    if gives and (not function.body or not isinstance(function.body[-1], Return)):
        _refuse("a FUNCTION that may end without its return")
    func = _numbered(form, function)
    given = _declared(function.body)
    given.update((param.name, param.kind) for param in info.params)
    image = isinstance(module, _ImageModule)
    kind = _ImageFunction if image else _SlotFunction
    body = settled(
        module,
        cls,
        func,
        lambda trial, c, f, kinds: kind(trial, c, f, kinds, info, given),
        given,
    )
    assert isinstance(body, _FunctionParts)
    instance = [f"{body.instance_ctype}s"] if function.method else []
    params = [f"{body.param_ctype(param.kind)} p{n}" for n, param in enumerate(info.params)]
    valued = [(n, kind) for n, kind in enumerate(body.items) if not isinstance(kind, Nothing)]
    outs = [f"{body.out_ctype(kind)}o{n}" for n, kind in valued]
    head = f"static int\n{body.c_name}({', '.join(['padt_mctx *ctx', *instance, *params, *outs])})"
    entry = (
        [] if function.method else ["    char *s = NULL;" if image else "    PyObject *s = NULL;"]
    )
    entry += [
        "    padt_mctx padt_own;  /* a slot-mode body calls with none: the nesting from here */",
        "    if (ctx == NULL) {",
        "        memset(&padt_own, 0, sizeof padt_own);",
        "        ctx = &padt_own;",
        "    }",
        "    if (padt_enter(ctx) < 0) return -1;",
    ]
    entry += [f"    f->o{n} = o{n};" for n, _ in valued]
    for n, param in enumerate(info.params):
        local = body.local_ref(param.name)
        if isinstance(body, _ImageFunction) and isinstance(param.kind, Instance):
            # the caller's bytes, copied into the frame
            size = body.module.size(Nested(param.kind.cls))
            own = body.frame_buffer(f"p{n}", size)
            entry += [f"    memcpy({own}, p{n}, {size});", f"    {local} = {own};"]
            continue
        # a structure of its class (its members at their offsets), an array a list
        if isinstance(param.kind, Instance):
            check = f"Py_IS_TYPE(p{n}, (PyTypeObject *){module.type_ref(param.kind.cls)})"
        elif isinstance(param.kind, Array):
            check = f"PyList_CheckExact(p{n})"
        else:
            check = ""
        if check:
            entry += [
                f"    if (PADT_UNLIKELY(!{check})) {{",
                "        padt_bad_read();",
                "        goto padt_error;",
                "    }",
            ]
        value = f"Py_NewRef(p{n})" if _is_object(param.kind) else f"p{n}"
        entry.append(f"    {local} = {value};")
    fields = [f"{body.out_ctype(kind)}o{n};" for n, kind in valued]
    returns = ("ctx->depth--; return 0;", "ctx->depth--; return -1;")
    if image:
        return body.c_name, image_function_text(body, func, head, fields, entry, returns)
    fields.append("padt_mctx *ctx;")
    entry.append("    f->ctx = ctx;")
    return body.c_name, slot_function_text(body, func, head, fields, entry, returns)


def _declared(statements: tuple[Stmt, ...]) -> dict[str, Kind]:
    """The declared kinds of the FUNCTION's variables that are numbers or BOOLs, read off
    its assignments: a loop counter's range is then known from the first pass (a local's
    kind otherwise grows pass by pass, which a FOR's range cannot follow)."""
    found: dict[str, Kind] = {}
    for statement in statements:
        match statement:
            case Assign(target=Var(where="local", name=name, type=declared)) if (
                declared and not name.startswith("__")  # the compiler's temporaries: inferred
            ):
                kind = kind_of_type(declared, {})
                if isinstance(kind, Int | Bool | Float | Text):
                    found.setdefault(name, kind)
            case If(body=body, elifs=elifs, orelse=orelse):
                found.update(_declared(body))
                for branch in elifs:
                    found.update(_declared(branch.body))
                found.update(_declared(orelse))
            case While(body=body):
                found.update(_declared(body))
            case ForEach(body=body, orelse=orelse):
                found.update(_declared(body))
                found.update(_declared(orelse))
    return found


def _module_text(module: _Module, what: str, made: list[tuple[str, tuple[str, str]]]) -> str:
    """The module of C bodies `made` (key, (C name, text)), each put into the binding's
    table of FUNCTIONs by its key; it binds no class."""
    writer = f"C of {what} {{}}: written by runtime/code/native/function_body.py"
    lines = module_start(module, writer, [text for _, text in made])
    if isinstance(module, _ImageModule):
        binding = [
            "    PyObject *ns, *breathe, *views, *registry, *view_type, *bodies;",
            '    if (!PyArg_ParseTuple(args, "OOOOO", &ns, &breathe, &views, &registry,'
            " &view_type))",
            "        return NULL;",
            "    if (padt_bind_common(ns, breathe) < 0) return NULL;",
            "    if (padt_bind_image(views, registry, view_type) < 0) return NULL;",
        ]
    else:
        binding = [
            "    PyObject *ns, *breathe, *functions, *bodies;",
            '    if (!PyArg_ParseTuple(args, "OOO", &ns, &breathe, &functions)) return NULL;',
            "    if (padt_bind_common(ns, breathe) < 0 || padt_bind_functions(functions) < 0)",
            "        return NULL;",
        ]
    lines += [
        "static PyObject *",
        "padt_bind(PyObject *module, PyObject *args)",
        "{",
        *binding,
        *module.binding(),
        "    if ((bodies = PyDict_New()) == NULL) return NULL;",
    ]
    for key, (c_name, _) in made:
        lines += [
            f"    if (padt_register_function({c_string(key)}, (void *){c_name}) < 0)",
            "        { Py_DECREF(bodies); return NULL; }",
        ]
    return "\n".join(lines + module_end())
