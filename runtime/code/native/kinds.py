"""What the translator knows of a value: its kind, and for integers the range it lies in.

The ranges come from the declared types (the contract keeps every stored value in the range
of its type) and from the arithmetic between them, so the translator can prove that C's
64-bit (or 128-bit) integers compute exactly what Python's unbounded ones do.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field, replace

from runtime.contract.artifact import PouCode, VarInfo
from runtime.contract.code.names import IDENTIFIER
from runtime.contract.code.python_text import printed_lines
from runtime.contract.code.statements import Return
from runtime.contract.code.typed_form import Call, Const, Expr, Sequence
from runtime.contract.code.units import Class, Function, Inherited, Unit
from runtime.contract.intrinsic_table import F32
from runtime.contract.layout import starts_as_integers
from runtime.contract.values import array_shape, base_type, int_range, to_real32

INT64_MIN, INT64_MAX = -(1 << 63), (1 << 63) - 1
INT128_MIN, INT128_MAX = -(1 << 127), (1 << 127) - 1


@dataclass(frozen=True)
class Int:
    lo: int
    hi: int
    # a REAL taken to an integer: beyond +-2**126 the C value is a stand-in of that size,
    # equal to the true one modulo 2**64 (what a wrap to at most 64 bits keeps), so such a
    # value may only be added, multiplied, masked or compared with 64-bit values
    stand_in: bool = False

    @property
    def ctype(self) -> str:
        return "int64_t" if self.fits64 else "padt_i128"

    @property
    def fits64(self) -> bool:
        return self.lo >= INT64_MIN and self.hi <= INT64_MAX

    @property
    def fits128(self) -> bool:
        return self.lo >= INT128_MIN and self.hi <= INT128_MAX

    def within(self, other: Int) -> bool:
        return other.lo <= self.lo and self.hi <= other.hi


FULL64 = Int(INT64_MIN, INT64_MAX)
STAND_IN_FROM = 1 << 126
FROM_REAL = Int(-STAND_IN_FROM - (1 << 64), STAND_IN_FROM + (1 << 64), stand_in=True)


@dataclass(frozen=True)
class Bool:
    pass


@dataclass(frozen=True)
class Float:
    """REAL or LREAL: a C double (a REAL is rounded to 32 bits where the code says so)."""


@dataclass(frozen=True)
class Instance:
    """An object of a generated class (function block, structure, program, the globals)."""

    cls: str


@dataclass(frozen=True)
class Array:
    """A flat list, as generated code holds an ARRAY; `element` None: not translated."""

    element: Kind | None
    length: int


@dataclass(frozen=True)
class Text:
    """A STRING or WSTRING: a Python str, whose length the compiler's cuts keep."""


@dataclass(frozen=True)
class Ref:
    """A REF_TO or REFERENCE TO: None (NULL) or the runtime's Reference object, followed by
    its helpers; `target` the kind of what it refers to (None: one the tier leaves to
    Python)."""

    target: Kind | None


@dataclass(frozen=True)
class Outputs:
    """What a call of a FUNCTION with VAR_OUTPUT or VAR_IN_OUT gives: a tuple of its result
    and those values, each of its kind (None: one the tier leaves to Python)."""

    items: tuple[Kind | None, ...]


@dataclass(frozen=True)
class Hook:
    """A name of the namespace that holds None or something to call (`_tick`)."""


@dataclass(frozen=True)
class Range:
    """A `range(start, stop, step)` held in a local, with a constant step."""

    start: Int
    stop: Int
    step: int


@dataclass(frozen=True)
class Implementer:
    """What an interface variable's reference refers to: an instance of any class that
    conforms to the interface `name` (upper case), whose methods are looked up on the
    object as Python looks them up."""

    name: str


@dataclass(frozen=True)
class Nothing:
    """None where a method or FUNCTION without a result puts its result in the tuple of
    its outputs (`return (None, q)`): what a caller drops."""


@dataclass(frozen=True)
class Results:
    """What a call of a FUNCTION's C body gives (image mode, function_body.py): its result
    and outputs as C values, each of its declared kind, where Python has a tuple."""

    items: tuple[Int | Bool | Float | Text | Instance | Array | Nothing, ...]


Kind = (
    Int
    | Bool
    | Float
    | Text
    | Instance
    | Array
    | Ref
    | Outputs
    | Results
    | Nothing
    | Hook
    | Range
    | Implementer
)

# integers a double holds exactly: Python converts and compares beyond them exactly, C not
EXACT_IN_DOUBLE = Int(-(1 << 53), 1 << 53)

# the attributes of `_SYS` (runtime.code.intrinsics.SystemView): BOOL flags, the rest integers of
# at most 64 bits (TIME, UDINT, DWORD, DT)
SYSTEM_BOOLS = frozenset(
    {
        "COLDSTART", "WARMSTART", "START_CYCLE", "FORCE_DEACTIVATION", "RELOAD_DEACTIVATION",
        "READ_ONLY_IN_RUN", "EMERGENCY_STOP_1", "EMERGENCY_STOP_2", "EMERGENCY_STOP_3",
        "EMERGENCY_STOP_4",
    }
)  # fmt: skip
SYSTEM_INTS = frozenset(
    {
        "now_ns", "CYCLE_TIME_LAST", "CYCLE_TIME_MIN", "CYCLE_TIME_MAX", "CYCLE_TIME_MEAN",
        "WATCHDOG_TIME", "SYSTEM_TICK", "FORCE_TIME_REMAINING", "CONFIGURATION_CRC",
        "DATE_AND_TIME",
    }
)  # fmt: skip


def join(a: Kind, b: Kind) -> Kind | None:
    """The kind of a local that takes both; None when no one C type holds both."""
    if isinstance(a, Int) and isinstance(b, Int):
        return Int(min(a.lo, b.lo), max(a.hi, b.hi), a.stand_in or b.stand_in)
    return a if a == b else None


@dataclass(frozen=True)
class ClassInfo:
    name: str  # the class in the namespace
    members: dict[str, Kind | None]  # attribute -> kind (None: a type not translated)
    # its methods and property accessors, its own and inherited, by name (`M__X`)
    methods: dict[str, FunctionInfo] = field(default_factory=dict)
    # those of its methods a block that extends it overrides: on its own instance, a call
    # of one takes the derived block's where the instance is one (its SUPER^())
    overridden: frozenset[str] = frozenset()
    structure: bool = False  # a STRUCT's class: a value, made afresh by calling the class


Forms = dict[str, Unit]
"""The typed form of each unit of an artifact, by its class name: decoded once for all the
translation needs (a decode takes about half of a translation's time)."""


def class_table(units: list[PouCode], forms: Forms) -> dict[str, ClassInfo]:
    """Every generated class of an artifact with the kinds of its declared variables (and
    the action control blocks of its chart, when it has one); the runtime's action control
    block; per interface, the methods a call through it takes (`interface_key`)."""
    by_type = {unit.name.upper(): unit.class_name for unit in units if unit.kind != "FUNCTION"}
    extended = _extended_blocks(units, forms)
    own = {
        name: {
            f.name: _method_info(f, name, by_type)
            for f in form.functions
            if isinstance(f, Function)
        }
        for name, form in forms.items()
        if isinstance(form, Class)
    }
    table: dict[str, ClassInfo] = {}
    for unit in units:
        if unit.kind == "FUNCTION":
            continue
        form = forms.get(unit.class_name)
        starts = _integer_slots(form) if isinstance(form, Class) else set()
        members = {v.attr: _member_kind(v, by_type, extended, starts) for v in unit.variables}
        if isinstance(form, Class):
            members.update(dict.fromkeys(_action_controls(form), Instance(ACTION_CONTROL)))
        methods = dict(own.get(unit.class_name, {}))
        for inherited in form.functions if isinstance(form, Class) else ():
            found = (
                own.get(inherited.owner, {}).get(inherited.name)
                if isinstance(inherited, Inherited)
                else None
            )
            if found is not None:
                methods[inherited.name] = found
        methods.pop("__call__", None)
        table[unit.class_name] = ClassInfo(
            unit.class_name, members, methods, structure=unit.kind == "STRUCT"
        )
    _mark_overridden(table, forms, own, by_type)
    table[ACTION_CONTROL] = ACTION_CONTROL_INFO
    table.update(_interfaces(forms, table))
    return table


def _mark_overridden(
    table: dict[str, ClassInfo],
    forms: Forms,
    own: dict[str, dict[str, FunctionInfo]],
    by_type: dict[str, str],
) -> None:
    """Each class's `overridden`: its methods (its own and inherited) that the class of a
    block extending it, at any depth, defines anew."""
    found: dict[str, set[str]] = {}
    for name, form in forms.items():
        if not isinstance(form, Class):
            continue
        for kind in form.kinds:  # what it conforms to: itself, the blocks it extends
            ancestor = by_type.get(kind)
            if ancestor in table and ancestor != name:
                mine = own.get(name, {}).keys() - {"__call__"}
                found.setdefault(ancestor, set()).update(mine & table[ancestor].methods.keys())
    for name, methods in found.items():
        table[name] = replace(table[name], overridden=frozenset(methods))


def interface_key(name: str) -> str:
    """The entry of an interface in the class table (no class is named with a space)."""
    return f"{INTERFACE_PREFIX}{name}"


def _interfaces(forms: Forms, table: dict[str, ClassInfo]) -> dict[str, ClassInfo]:
    """Per interface some class conforms to, the methods a call through it may take: those
    every conforming class has alike (a call of another is left to Python)."""
    conforming: dict[str, list[ClassInfo]] = {}
    for name, form in sorted(forms.items()):
        if isinstance(form, Class) and name in table:
            for kind in form.kinds:
                conforming.setdefault(kind, []).append(table[name])
    found = {}
    for interface, infos in sorted(conforming.items()):
        # alike as a caller through the interface sees them (each class's own C aside)
        shared = set.intersection(
            *({(name, _as_seen(m)) for name, m in info.methods.items()} for info in infos)
        )
        key = interface_key(interface)
        found[key] = ClassInfo(key, {}, dict(sorted(shared)))
    return found


def _as_seen(method: FunctionInfo) -> FunctionInfo:
    """A method as a call through an interface sees it: what it gives, not whose C it is."""
    return replace(method, params=(), native="", owner="")


def _action_controls(form: Class) -> list[str]:
    """The slots of a class that start as an SFC action's control block."""
    return [slot.name for slot in form.slots if slot.initial == Call(ACTION_CONTROL, (), "")]


def _integer_slots(form: Class) -> set[str]:
    """The slots of a class that start as an integer constant, or a list of them."""
    return {slot.name for slot in form.slots if starts_as_integers(slot.initial)}


def _enumeration(type_name: str) -> bool:
    """A named type that is no elementary one."""
    return IDENTIFIER.match(type_name) is not None and int_range(type_name) is None


def _member_kind(
    variable: VarInfo, classes: dict[str, str], extended: set[str], integers: set[str]
) -> Kind | None:
    kind = kind_of_type(variable.type, classes)
    if variable.attr in integers:
        # an enumeration (its values are integers of the compiler's choosing), or an array
        # of them: any 64-bit integer, each read checked as every slot's is
        if kind is None and _enumeration(variable.type):
            return FULL64
        shape = array_shape(variable.type)
        if isinstance(kind, Array) and kind.element is None and shape is not None:
            return Array(FULL64, kind.length) if _enumeration(shape.element) else kind
    if variable.kind == "VAR_IN_OUT" and variable.type.upper() in extended:
        # the instance connected may be of a block derived from the declared one, whose
        # class has slots of its own: left to Python, which reads them by name
        return None
    return kind


def _extended_blocks(units: list[PouCode], forms: Forms) -> set[str]:
    """The blocks (by upper-case name) that another block extends: what an instance
    conforms to is its class's `kinds` (backend/compiler/generate.py)."""
    found: set[str] = set()
    for unit in units:
        form = forms.get(unit.class_name) if unit.kind == "FUNCTION_BLOCK" else None
        if isinstance(form, Class):
            found.update(kind for kind in form.kinds if kind != unit.name.upper())
    return found


def kind_of_type(type_name: str, classes: dict[str, str]) -> Kind | None:
    """The kind of a variable of a declared type; None for what the tier leaves to Python
    (enumerations, which `_member_kind` knows by their initial values)."""
    for prefix in ("REF_TO ", "REFERENCE TO "):
        if type_name.upper().startswith(prefix):
            return Ref(kind_of_type(type_name[len(prefix) :].strip(), classes))
    if type_name.upper().startswith(INTERFACE_PREFIX):  # a reference to an implementer
        return Ref(Implementer(type_name[len(INTERFACE_PREFIX) :].strip().upper()))
    name, _ = base_type(type_name)
    if name == "BOOL":
        return Bool()
    if name in ("REAL", "LREAL"):
        return Float()
    if name in ("STRING", "WSTRING"):
        return Text()
    limits = int_range(name)
    if limits is not None:
        # ULINT and LWORD (0..2**64-1) too: a padt_i128 in C (Int.ctype)
        return Int(*limits) if Int(*limits).fits128 else None
    if type_name.upper() in classes:
        return Instance(classes[type_name.upper()])
    if OPEN_ARRAY.fullmatch(type_name):  # ARRAY[*] OF T: its bounds come with the call
        return None
    shape = array_shape(type_name)
    if shape is not None:
        length = 1
        for low, high in shape.dims:
            length *= max(0, high - low + 1)
        return Array(kind_of_type(shape.element, classes), length)
    return None


@dataclass(frozen=True)
class FunctionInfo:
    """A FUNCTION as a caller sees it: the name it has in the namespace, and what its call
    gives: `result` None for no result, or one the tier leaves to Python; `outputs` when
    the call gives a tuple (the result with VAR_OUTPUT and VAR_IN_OUT values), the kinds
    of its items (None: the FUNCTION returns tuples of more than one shape)."""

    name: str
    result: Kind | None
    outputs: Outputs | None = None
    # a FUNCTION (or method) whose inputs, in-outs, result and outputs are all numbers or
    # BOOLs or texts, or (a FUNCTION's, on slots) structures and arrays (its body may be C,
    # function_body.py): its parameters in order, and the key its C body has in the table
    # of FUNCTIONs (`native_key`); () and "" for any other
    params: tuple[ParamInfo, ...] = ()
    native: str = ""
    owner: str = ""  # a method's: the class that defines it

    @property
    def in_image(self) -> bool:
        """Its parameters, result and outputs all numbers, BOOLs, texts or structures: its C
        may work in native memory too, where a text is the str a read of its bytes makes
        and a structure bytes (of the image, or of a FUNCTION's frame), but an array is
        bytes of the image, not yet taken or given there."""
        given = self.outputs.items if self.outputs is not None else (self.result,)
        return not any(isinstance(kind, Array) for kind in (*(p.kind for p in self.params), *given))


@dataclass(frozen=True)
class ParamInfo:
    """An input or in-out of a FUNCTION whose body may be C: its declared kind, and the
    constant it takes where a call does not give it (None for a structure or an array: the
    compiler's call gives it always, a fresh initial value where the ST leaves it out)."""

    name: str
    kind: Int | Bool | Float | Text | Instance | Array
    default: bool | int | float | str | None


SCALAR = (Int, Bool, Float)
# what a FUNCTION's C on slots takes and gives as a Python object: a text, a structure, an
# array of numbers, BOOLs or texts (a list)
OBJECTS = (Text, Instance, Array)


def _takes(kind: Kind | None) -> bool:
    """A number, BOOL or text, a structure, an array of elementary values: what a
    FUNCTION's C on slots takes and gives."""
    if isinstance(kind, Array):
        return isinstance(kind.element, (*SCALAR, Text))
    return isinstance(kind, (*SCALAR, *OBJECTS))


def c_code(kind: Kind) -> str:
    """A letter for the C type of a number or BOOL, as a FUNCTION's C signature has it (a
    result it does not have: `n`, no C value); a text `t`, in brackets a structure's class
    or an array's length and element."""
    if isinstance(kind, Nothing):
        return "n"
    if isinstance(kind, Text):
        return "t"
    if isinstance(kind, Instance):
        return f"[{kind.cls}]"
    if isinstance(kind, Array) and kind.element is not None:
        return f"[{kind.length}{c_code(kind.element)}]"
    if isinstance(kind, Int):
        return "q" if kind.fits64 else "Q"
    return "b" if isinstance(kind, Bool) else "d"


def native_key(name: str, params: tuple[ParamInfo, ...], returned: tuple[Kind, ...]) -> str:
    """The key of a FUNCTION's C body in an image's registry: its name and C signature, so
    that a call site compiled for another signature never finds it."""
    codes = "".join(c_code(param.kind) for param in params)
    return f"{name}({codes}){''.join(c_code(kind) for kind in returned)}"


def _native_params(function: Function, structures: dict[str, str]) -> tuple[ParamInfo, ...] | None:
    """The parameters of a FUNCTION whose every one is a number, BOOL or text with a
    constant default of its kind, or a structure (of `structures`: type -> class) or an
    array of elementary values; None otherwise."""
    found = []
    for param in function.params:
        default = param.default
        kind = kind_of_type(default.type, structures)
        if isinstance(kind, Instance | Array):
            if not _takes(kind):
                return None
            found.append(ParamInfo(param.name, kind, None))
            continue
        value = _constant_value(default)
        if not isinstance(kind, (*SCALAR, Text)) or value is None:
            return None
        python = {Int: int, Bool: bool, Float: float, Text: str}[type(kind)]
        if type(value) is not python or (isinstance(value, float) and not math.isfinite(value)):
            return None
        found.append(ParamInfo(param.name, kind, value))
    return tuple(found)


def _constant_value(node: Expr) -> bool | int | float | str | None:
    """The value of a parameter's default: a constant, or a REAL's (`_f32(2.5)`)."""
    match node:
        case Const(value=bool() | int() | float() | str() as value):
            return value
        case Call(callee=F32.name, args=(Const(value=float() | int() as value),)) if (
            type(value) is not bool
        ):
            return to_real32(float(value))
    return None


OPEN_ARRAY = re.compile(r"ARRAY\[\s*\*[\s,*]*\] OF .+", re.IGNORECASE)

# how the artifact names an interface variable's type (`INTERFACE IText`)
INTERFACE_PREFIX = "INTERFACE "

# The runtime's action control block of an SFC action (runtime.code.intrinsics): a chart's
# body reads its flags A and Q and calls its `update` (a Python method, no result); an
# instance's slot `_ac_X` holds one from its start (`_ActionControl()`).
ACTION_CONTROL = "_ActionControl"
ACTION_CONTROL_INFO = ClassInfo(
    ACTION_CONTROL,
    {"A": Bool(), "Q": Bool()},
    {"update": FunctionInfo("update", None)},
)


def function_table(units: list[PouCode], forms: Forms) -> dict[str, FunctionInfo]:
    """Every FUNCTION of `units` (an artifact's), by its name in the namespace. Whether a
    call gives a tuple, and of what, is read off the form's `return` statements (the
    artifact names the result type, not the outputs): the declared types of the variables
    returned."""
    # the structures by type name: a FUNCTION's C takes and gives them, as its result and
    # its outputs
    structures = {unit.name.upper(): unit.class_name for unit in units if unit.kind == "STRUCT"}
    table: dict[str, FunctionInfo] = {}
    for unit in units:
        if unit.kind != "FUNCTION" or not isinstance(unit.returns, str):
            continue
        form = forms[unit.class_name]
        if not isinstance(form, Function):
            continue
        returned = _returned(form, unit.class_name, structures)
        result = kind_of_type(unit.returns, structures) if unit.returns else None
        info = FunctionInfo(unit.class_name, result, returned.outputs)
        gives = bool(unit.returns)
        table[unit.class_name] = _with_native(info, form, unit.class_name, gives, structures)
    return table


def _with_native(
    info: FunctionInfo,
    function: Function,
    key: str,
    gives: bool,
    structures: dict[str, str] | None = None,
) -> FunctionInfo:
    """`info` with its parameters and C key where everything its call takes and gives is a
    number, a BOOL or a text, or (given `structures`, a FUNCTION's) a structure or an array
    (`gives`: it has a result)."""
    params = _native_params(function, structures or {})
    if info.outputs is not None:
        values: tuple[Kind | None, ...] | None = info.outputs.items or None
    else:
        values = (info.result,) if gives else ()
    if params is None or values is None:
        return info
    kinds = [*(p.kind for p in params), *(v for n, v in enumerate(values) if n or v != Nothing())]
    if not all(
        isinstance(kind, (*SCALAR, Text)) or (structures is not None and _takes(kind))
        for kind in kinds
    ):
        return info
    given = tuple(kind for kind in values if kind is not None)
    return replace(info, params=params, native=native_key(key, params, given))


def _method_info(function: Function, cls: str, by_type: dict[str, str]) -> FunctionInfo:
    """A method of class `cls` as a caller sees it; its C key names the class. Its body is
    C in native memory only, so of numbers, BOOLs and texts only."""
    info = replace(_returned(function, function.name, by_type), owner=cls)
    gives = any(
        isinstance(line.header, Return) and line.header.value is not None
        and not (isinstance(line.header.value, Const) and line.header.value.value is None)
        for line in printed_lines(function)
    )  # fmt: skip
    return _with_native(info, function, f"{cls}.{function.name}", gives)


def _item_kind(item: Expr, classes: dict[str, str]) -> Kind | None:
    """The kind of an item of the tuple a call gives: its declared type's, or None's."""
    if isinstance(item, Const) and item.value is None:
        return Nothing()
    return kind_of_type(item.type, classes) if item.type else None


def _returned(function: Function, name: str, classes: dict[str, str]) -> FunctionInfo:
    """What a call of `function` gives, read off its `return` statements: the declared
    types of the variables it returns (a tuple of them: the result with the outputs)."""
    values = [
        line.header.value
        for line in printed_lines(function)
        if isinstance(line.header, Return) and line.header.value is not None
    ]
    shapes = {
        tuple(_item_kind(item, classes) for item in value.items)
        for value in values
        if isinstance(value, Sequence) and value.as_tuple
    }
    if shapes:
        return FunctionInfo(name, None, Outputs(shapes.pop() if len(shapes) == 1 else ()))
    results = {kind_of_type(v.type, classes) if v.type else None for v in values}
    return FunctionInfo(name, results.pop() if len(results) == 1 else None)
