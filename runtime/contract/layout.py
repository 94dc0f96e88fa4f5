"""The layout of every class of an artifact in native memory, and of the memory image of a
configuration (issue 34, step 5: docs/native-code.md, "Layout").

A layout is computed here, in Python, from the units of the artifact: each class's slots
in their order, each of the type its variable is declared with (the artifact's
`VarInfo`), or, for a slot no variable declares (an open array's in-out, an SFC action's
control block), of the type its initial value has in the typed form. No C compiler is
needed, and every machine gets the same layout. The rules are the C ABI's of x86-64 and
AArch64, natural alignment with members in declaration order, so a C struct declared
member by member has exactly these offsets; the C that uses a layout asserts every one of
them (`runtime/code/native/layout_c.py`), and a compiler that disagreed would fail the
build rather than corrupt memory.

- BOOL is one byte, 0 or 1 (a read takes any other value as TRUE); the integers, TIME and
  the dates are C's integers of their width and sign (TIME and the dates 64 bits of
  nanoseconds); REAL a `float`, LREAL a `double`; an enumeration a 64-bit integer.
- `STRING[n]` is a length (`uint16_t`) and n + 1 characters of one byte, `WSTRING[n]` of two
  (IEC 61131-3's single-byte and double-byte strings); CHAR and WCHAR are strings of one.
- A structure or function block instance is its class's struct, inline; an array is its
  elements, inline, row-major, however many dimensions it has.
- A reference (REF_TO, REFERENCE TO, POINTER TO) is a `uint32_t` offset into the image, 0
  for NULL (the header is at 0, so no variable is).
- A block's in-out of an array, a structure or a block no other block extends (which the
  code passes as the very variable) is the `uint32_t` offset of the variable a call bound
  it to, then storage of its own of the variable's type: what the offset points at until
  a call binds it (a block never called, a context restored), as the Python tier gives
  such an in-out an object of its own. An interface variable, and an in-out of a block
  another extends (a derived block's instance may come), is an offset and a `uint32_t`
  class number. An in-out of an open array (`ARRAY[*] OF T`) is an offset and the bounds
  of each dimension (`int64_t`).
- A class without slots takes one byte, so each instance has an address of its own.

The image of a configuration is, in order: the header (what `SYS` reads, the watchdog's
flag, the slice budget), the globals, the user programs' instances by priority and Program
ID, each PROGRAM that is no user program's POU, and each user program's own copy of the
globals where programs get one (`runtime/code/instances.py`). A layout that cannot be made
(a type it does not know, a structure that holds itself, an image beyond what a 32-bit
offset reaches) is a `LayoutRefused`.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Iterable
from dataclasses import dataclass

from runtime.contract.artifact import Artifact, PouCode, VarInfo
from runtime.contract.code.typed_form import Call, Const, Expr, Repeated, Sequence
from runtime.contract.code.units import Alias, Class
from runtime.contract.system_variables import SYSTEM_VARIABLES
from runtime.contract.values import ArrayShape, array_shape, base_type, int_range

# struct's format characters (native sizes, as C's types on x86-64 and AArch64)
SCALAR_SIZES = {"?": 1, "b": 1, "B": 1, "h": 2, "H": 2, "i": 4, "I": 4, "q": 8, "Q": 8}
SCALAR_SIZES |= {"f": 4, "d": 8}
# not struct's: an int64_t that is None at INT64_MIN, a time of the runtime's own classes
# that has not started (an SFC step's, an action control block's)
NULLABLE_TIME = "o"
SCALAR_SIZES[NULLABLE_TIME] = 8
_INTEGER_CODES = {(8, True): "b", (16, True): "h", (32, True): "i", (64, True): "q"}
_INTEGER_CODES |= {(8, False): "B", (16, False): "H", (32, False): "I", (64, False): "Q"}

DEFAULT_STRING_LENGTH = 80  # a STRING or WSTRING declared without one
OFFSET_LIMIT = 1 << 32  # what a reference's uint32_t offset reaches
REFERENCE_TYPES = ("REF_TO ", "REFERENCE TO ", "POINTER TO ")
INTERFACE_TYPE = "INTERFACE "
SFC_STEP = "_SfcStep"  # the runtime's class of a step (runtime/code/intrinsics.py)
ACTION_CONTROL = "_ActionControl"  # the runtime's action control block of an SFC action
HEADER = "_SYS"  # the image's header


class LayoutRefused(ValueError):
    """No layout can be made: the message names the class, the slot and why."""


@dataclass(frozen=True, slots=True)
class Scalar:
    """An elementary value: `code` is its `struct` format character."""

    code: str


@dataclass(frozen=True, slots=True)
class Chars:
    """A STRING (`wide` False, one byte a character) or WSTRING of at most `length`."""

    length: int
    wide: bool


@dataclass(frozen=True, slots=True)
class Nested:
    """An instance of the class `cls`, inline."""

    cls: str


@dataclass(frozen=True, slots=True)
class Elements:
    """An array: `count` elements, inline (a multi-dimensional array row-major)."""

    element: Shape
    count: int


@dataclass(frozen=True, slots=True)
class Offset:
    """A reference: an offset into the image, 0 for NULL."""


@dataclass(frozen=True, slots=True)
class Bound:
    """A block's in-out of an array or structure: the offset of the `target` it is bound to,
    then a `target` of its own, `own` bytes from the start (the offset's own first)."""

    target: Shape

    def own(self, layout_of: Callable[[str], Layout]) -> int:
        return _round_up(4, size_and_align(self.target, layout_of)[1])


@dataclass(frozen=True, slots=True)
class Handle:
    """An interface value or a function block's in-out: an offset and a class number."""


@dataclass(frozen=True, slots=True)
class Slice:
    """An open array's in-out: an offset and the bounds of each of its `dims`."""

    element: Shape
    dims: int


Shape = Scalar | Chars | Nested | Elements | Offset | Bound | Handle | Slice


@dataclass(frozen=True, slots=True)
class Member:
    name: str
    shape: Shape
    offset: int
    size: int


@dataclass(frozen=True, slots=True)
class Layout:
    """A class in native memory: its size, its alignment and its members in order."""

    name: str
    size: int
    align: int
    members: tuple[Member, ...]

    def member(self, name: str) -> Member:
        return next(m for m in self.members if m.name == name)


@dataclass(frozen=True, slots=True)
class Placement:
    """An instance of the image: `name` is what it is (`_G`, a program's name,
    `_P.<POU>`, `<program>._G`), `cls` its class."""

    name: str
    cls: str
    offset: int


@dataclass(frozen=True, slots=True)
class ImageLayout:
    size: int
    placements: tuple[Placement, ...]


Layouts = dict[str, Layout]


def _scalar_code(type_name: str) -> str:
    name, _ = base_type(type_name)
    if name == "BOOL":
        return "?"
    if name == "REAL":
        return "f"
    if name == "LREAL":
        return "d"
    limits = int_range(name)
    if limits is None:
        return ""
    low, high = limits
    bits = (high - low).bit_length()
    return _INTEGER_CODES.get((bits, low < 0), "")


RUNTIME_CLASSES: dict[str, tuple[tuple[str, Shape], ...]] = {
    # `since` is None until the step's first active cycle
    SFC_STEP: (("X", Scalar("?")), ("T", Scalar("q")), ("since", Scalar(NULLABLE_TIME))),
    ACTION_CONTROL: (
        *((flag, Scalar("?")) for flag in ("A", "Q", "held", "stored", "sd_set", "ds_stored")),
        *((flag, Scalar("?")) for flag in ("sl_set", "p_prev", "p1_prev", "p0_prev")),
        *((t, Scalar(NULLABLE_TIME)) for t in ("l_since", "d_since", "sd_since", "ds_since")),
        ("sl_since", Scalar(NULLABLE_TIME)),
    ),
    HEADER: (
        ("now_ns", Scalar("q")),
        ("stop", Scalar("?")),  # set by the watchdog: a C body returns with its fault
        ("slice_budget", Scalar("q")),
        *((v.name, Scalar(_scalar_code(v.type))) for v in SYSTEM_VARIABLES),
    ),
}


def class_layouts(units: Iterable[PouCode]) -> Layouts:
    """The layout of every class of an artifact's units (PROGRAMs, function blocks,
    structures, the globals) and of the runtime's classes they hold, by class name."""
    try:
        return _Layouter(units).all()
    except RecursionError:  # a type nested deeper than any compiler writes
        raise LayoutRefused("a type nested too deep") from None


class _Layouter:
    """The layouts of one artifact, each made once, the classes a class holds first."""

    def __init__(self, units: Iterable[PouCode]) -> None:
        self._units = {u.class_name: u for u in units if u.kind != "FUNCTION"}
        self._by_type = {u.name.upper(): u for u in self._units.values()}
        self._done: Layouts = {}
        self._making: list[str] = []
        self._enumerations = self._enumeration_names()
        self._extended = self._extended_blocks()

    def all(self) -> Layouts:
        for name in sorted(self._units):
            self.layout(name)
        return dict(sorted(self._done.items()))

    def layout(self, cls: str) -> Layout:
        done = self._done.get(cls)
        if done is not None:
            return done
        if cls in self._making:
            raise LayoutRefused(f"class {cls} holds itself ({' > '.join(self._making)})")
        self._making.append(cls)
        made = place(cls, self._fields(cls), self.layout)
        self._making.pop()
        self._done[cls] = made
        return made

    def _fields(self, cls: str) -> tuple[tuple[str, Shape], ...]:
        if cls in RUNTIME_CLASSES:
            return RUNTIME_CLASSES[cls]
        unit = self._units.get(cls)
        if unit is None:
            raise LayoutRefused(f"no class {cls} in the artifact")
        form = unit.unit
        if isinstance(form, Alias):
            if form.target != SFC_STEP:
                raise LayoutRefused(f"class {cls} is an alias of {form.target}")
            return RUNTIME_CLASSES[SFC_STEP]
        if not isinstance(form, Class):
            raise LayoutRefused(f"unit {unit.name} is no class")
        declared = {v.attr: v for v in unit.variables}
        fields = {
            slot.name: self._slot_shape(cls, slot.name, declared.get(slot.name), slot.initial)
            for slot in form.slots
        }
        base = self._base(unit, form)
        if base is None:
            return tuple(fields.items())
        # the base's members first, where the base's own body would find them: its C body
        # then runs on a derived instance too (`SUPER^()`)
        first = [(m.name, m.shape) for m in self.layout(base).members]
        if any(fields.get(name) != shape for name, shape in first):
            return tuple(fields.items())
        taken = {name for name, _ in first}
        return (*first, *((n, s) for n, s in fields.items() if n not in taken))

    def _base(self, unit: PouCode, form: Class) -> str | None:
        """The class of the block `unit` extends: of the blocks it conforms to (its
        `kinds`), the one with the most slots, as each generation adds its own."""
        ancestors = [
            self._by_type[kind]
            for kind in form.kinds
            if kind != unit.name.upper()
            and kind in self._by_type
            and self._by_type[kind].kind == "FUNCTION_BLOCK"
        ]
        if not ancestors:
            return None
        return max(ancestors, key=lambda a: (len(a.variables), a.name)).class_name

    def _slot_shape(self, cls: str, slot: str, declared: VarInfo | None, initial: Expr) -> Shape:
        if declared is None and initial == Call(ACTION_CONTROL, (), ""):
            return Nested(ACTION_CONTROL)
        type_name = declared.type if declared is not None else _initial_type(initial)
        try:
            if declared is not None and declared.kind == "VAR_IN_OUT":
                return self._in_out(type_name)
            return self.shape(type_name)
        except LayoutRefused as refused:
            raise LayoutRefused(f"{cls}.{slot}: {refused}") from None

    def _in_out(self, type_name: str) -> Shape:
        """An in-out of an array, structure or block is the caller's object, referred to;
        of an elementary value, a copy in and out (the code's `t.x = v ... v = t.x`)."""
        if _open_array(type_name) is not None:
            return self.shape(type_name)
        shape = self.shape(type_name)
        if isinstance(shape, Elements):
            return Bound(shape)
        if isinstance(shape, Nested):
            # of a block another extends, an instance of the derived block may come: its
            # class must be known (a Handle); of any other, its class is the declared one
            unit = self._units.get(shape.cls)
            if unit is not None and unit.kind == "FUNCTION_BLOCK":
                return Handle() if unit.name.upper() in self._extended else Bound(shape)
            return Bound(shape)
        return shape

    def shape(self, type_name: str) -> Shape:
        """What a value of a declared type is in native memory."""
        upper = type_name.upper()
        if upper.startswith(REFERENCE_TYPES):
            return Offset()
        if upper.startswith(INTERFACE_TYPE):
            return Handle()
        name, length = base_type(type_name)
        if name in ("STRING", "WSTRING"):
            return Chars(length or DEFAULT_STRING_LENGTH, name == "WSTRING")
        if name in ("CHAR", "WCHAR"):
            return Chars(1, name == "WCHAR")
        code = _scalar_code(type_name)
        if code:
            return Scalar(code)
        if upper in self._by_type:
            cls = self._by_type[upper].class_name
            self.layout(cls)
            return Nested(cls)
        opened = _open_array(type_name)
        if opened is not None:
            dims, element = opened
            return Slice(self.shape(element), dims)
        shape = _array_shape(type_name)
        if shape is not None:
            count = 1
            for low, high in shape.dims:
                count *= max(0, high - low + 1)
            return Elements(self.shape(shape.element), count)
        if upper in self._enumerations:
            return Scalar("q")
        raise LayoutRefused(f"no layout for the type {type_name}")

    def _extended_blocks(self) -> set[str]:
        """The blocks (by upper-case name) another block extends: what an instance conforms
        to is its class's `kinds` (its block, its bases, its interfaces)."""
        found: set[str] = set()
        for unit in self._units.values():
            if unit.kind == "FUNCTION_BLOCK" and isinstance(unit.unit, Class):
                found.update(kind for kind in unit.unit.kinds if kind != unit.name.upper())
        return found

    def _enumeration_names(self) -> set[str]:
        """The named types that are enumerations: those of a slot that starts as an integer
        (or as integers) and that no class or elementary type has as its name."""
        names: set[str] = set()
        for unit in self._units.values():
            form = unit.unit
            if not isinstance(form, Class):
                continue
            starts = {s.name for s in form.slots if starts_as_integers(s.initial)}
            for variable in unit.variables:
                if variable.attr not in starts:
                    continue
                shape = _array_shape(variable.type) if "*" not in variable.type else None
                element = shape.element if shape is not None else variable.type
                if re.fullmatch(r"[A-Za-z_]\w*", element) and not _scalar_code(element):
                    names.add(element.upper())
        return names - set(self._by_type)


def _array_shape(type_name: str) -> ArrayShape | None:
    try:
        return array_shape(type_name)
    except ValueError:
        refused = f"the array type {type_name} has bounds that are no integers"
        raise LayoutRefused(refused) from None


def _initial_type(initial: Expr) -> str:
    """The type the typed form gives a slot's initial value (`Const` and `Call` say it)."""
    if isinstance(initial, Const | Call) and initial.type:
        return initial.type
    raise LayoutRefused("a slot no variable declares, of a type its initial value does not say")


_OPEN = re.compile(r"ARRAY\[\s*\*(?:\s*,\s*\*)*\s*\] OF (.+)", re.IGNORECASE)


def _open_array(type_name: str) -> tuple[int, str] | None:
    """`ARRAY[*, *] OF T` -> (2, T); None for any other type."""
    match = _OPEN.fullmatch(type_name)
    if match is None:
        return None
    return type_name[: match.start(1)].count("*"), match.group(1)


def starts_as_integers(node: Expr) -> bool:
    """Whether a slot's initial value is an integer constant, or a list of them: how an
    enumeration's variable (or an array of them) starts, its values integers of the
    compiler's choosing."""
    match node:
        case Const(value=value):
            return type(value) is int
        case Repeated(item=item):
            return starts_as_integers(item)
        case Sequence(items=items):
            return all(starts_as_integers(item) for item in items)
    return False


def size_and_align(shape: Shape, layout_of: Callable[[str], Layout]) -> tuple[int, int]:
    """The bytes a value of `shape` takes, and the alignment it needs."""
    match shape:
        case Scalar(code=code):
            size = SCALAR_SIZES[code]
            return size, size
        case Chars(length=length, wide=wide):
            unit = 2 if wide else 1  # the struct of a length and the characters
            return _round_up(2 + unit * (length + 1), 2), 2
        case Nested(cls=cls):
            nested = layout_of(cls)
            return nested.size, nested.align
        case Elements(element=element, count=count):
            size, align = size_and_align(element, layout_of)
            return size * count, align
        case Offset():
            return 4, 4
        case Bound(target=target):  # as C lays out `struct { uint32_t at; T own; }`
            size, align = size_and_align(target, layout_of)
            align = max(4, align)
            return _round_up(shape.own(layout_of) + size, align), align
        case Handle():
            return 8, 4
        case Slice(dims=dims):
            return 8 + 16 * dims, 8


def place(
    name: str, fields: Iterable[tuple[str, Shape]], layout_of: Callable[[str], Layout]
) -> Layout:
    """The layout of a class of `fields` in order: each at the next offset its alignment
    allows, the whole rounded up to the largest alignment."""
    members = []
    offset, align = 0, 1
    for member, shape in fields:
        size, member_align = size_and_align(shape, layout_of)
        offset = _round_up(offset, member_align)
        members.append(Member(member, shape, offset, size))
        offset += size
        align = max(align, member_align)
        if offset >= OFFSET_LIMIT:
            raise LayoutRefused(f"class {name} passes 4 GiB at {member}")
    return Layout(name, _round_up(max(offset, 1), align), align, tuple(members))


def _round_up(offset: int, align: int) -> int:
    return -(-offset // align) * align


def runtime_layouts() -> Layouts:
    """The layouts of the runtime's own classes (the header, an SFC step, an action
    control block)."""
    made: Layouts = {}
    for name, fields in RUNTIME_CLASSES.items():  # none holds another
        made[name] = place(name, fields, made.__getitem__)
    return made


def image_layout(artifact: Artifact, layouts: Layouts) -> ImageLayout:
    """Where each instance of a configuration lies in its image (`layouts` from
    `class_layouts` of the artifact's units)."""
    classes = {**runtime_layouts(), **layouts}
    pous = {pou.name.upper(): pou.class_name for pou in artifact.pous}
    configs = sorted(artifact.programs, key=lambda p: (p.priority, p.program_id))
    instances = [(HEADER, HEADER)]
    the_globals = artifact.globals.class_name if artifact.globals is not None else None
    if the_globals is not None:
        instances.append(("_G", the_globals))
    instances += [(config.name, pous[config.pou.upper()]) for config in configs]
    run = {config.pou.upper() for config in configs}
    instances += [
        (f"_P.{pou.name}", pou.class_name)
        for pou in artifact.pous
        if pou.kind == "PROGRAM" and pou.name.upper() not in run
    ]
    # as `instances_of` decides: a program gets its own copy of the globals when another
    # could change them during its program cycle, or when its cycle spans CPU cycles
    private = len(configs) > 1 or any(c.max_duration_us for c in configs)
    if private and the_globals is not None:
        instances += [(f"{config.name}._G", the_globals) for config in configs]
    placements = []
    offset = 0
    for name, cls in instances:
        layout = classes[cls]
        offset = _round_up(offset, layout.align)
        placements.append(Placement(name, cls, offset))
        offset += layout.size
        if offset >= OFFSET_LIMIT:
            raise LayoutRefused(f"the image passes 4 GiB at {name}")
    return ImageLayout(_round_up(offset, 8), tuple(placements))
