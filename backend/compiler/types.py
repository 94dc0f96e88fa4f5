"""The type system: elementary IEC types, arrays, structs, enums, function blocks.

Run-time representation (the artifact documents it for the runtime): integers and bit
strings as Python int kept inside their width, REAL/LREAL as float, BOOL as bool,
TIME/LTIME and the date types as int nanoseconds, STRING as str, enums as int, arrays as
flat Python lists, structs and FB instances as objects of generated classes.
"""

from __future__ import annotations

from dataclasses import dataclass

DEFAULT_STRING_LENGTH = 80


@dataclass(frozen=True)
class ElementaryType:
    name: str
    category: str  # "bool" | "int" | "bits" | "real" | "time" | "date" | "string"
    bits: int = 0
    signed: bool = False
    length: int = 0  # STRING[n]; 0 = the default length

    @property
    def is_integer(self) -> bool:
        return self.category in ("int", "bits")

    @property
    def is_numeric(self) -> bool:
        return self.category in ("int", "bits", "real")

    @property
    def is_any_literal(self) -> bool:
        return self.name.startswith("ANY_")

    @property
    def max_length(self) -> int:
        """How many characters a string variable holds (IEC's default is 80)."""
        if self.category != "string":
            return 0
        return self.length or DEFAULT_STRING_LENGTH

    @property
    def min(self) -> int:
        return -(1 << (self.bits - 1)) if self.signed else 0

    @property
    def max(self) -> int:
        return (1 << (self.bits - 1)) - 1 if self.signed else (1 << self.bits) - 1


@dataclass(frozen=True)
class ArrayType:
    element: Type
    dims: tuple[tuple[int, int], ...]

    @property
    def name(self) -> str:
        ranges = ", ".join(f"{lo}..{hi}" for lo, hi in self.dims)
        return f"ARRAY[{ranges}] OF {self.element.name}"

    @property
    def size(self) -> int:
        size = 1
        for lo, hi in self.dims:
            size *= hi - lo + 1
        return size


@dataclass(frozen=True)
class OpenArrayType:
    """`ARRAY[*] OF T` (`ARRAY[*, *]`, ...): a parameter bound to an array of any bounds
    at each call; LOWER_BOUND and UPPER_BOUND read the bounds of the array passed."""

    element: Type
    rank: int

    @property
    def name(self) -> str:
        return f"ARRAY[{', '.join('*' * self.rank)}] OF {self.element.name}"

    def binds(self, source: Type) -> bool:
        """Can an argument of `source` be passed for this parameter?"""
        if isinstance(source, OpenArrayType):
            return source == self
        return (
            isinstance(source, ArrayType)
            and len(source.dims) == self.rank
            and source.element == self.element
        )


@dataclass(frozen=True)
class StructType:
    name: str


@dataclass(frozen=True)
class EnumType:
    name: str
    base: ElementaryType


@dataclass(frozen=True)
class FbType:
    """An instance of a FUNCTION_BLOCK (or of a PROGRAM, for program instances)."""

    name: str


@dataclass(frozen=True)
class InterfaceType:
    """A variable of an INTERFACE type: a reference to an instance of a block that
    implements it, NULL until one is assigned."""

    name: str


@dataclass(frozen=True)
class VariadicType:
    name: str = "..."


@dataclass(frozen=True)
class RefType:
    """A reference (IEC 61131-3 ed. 3 `REF_TO T`); `target` None is the type of NULL,
    which fits every reference type."""

    target: Type | None
    pointer: bool = False  # CODESYS `POINTER TO T`: the same, made by ADR
    implicit: bool = False  # CODESYS `REFERENCE TO T`: read and written as the T

    @property
    def name(self) -> str:
        if self.target is None:
            return "NULL"
        kind = "REFERENCE TO " if self.implicit else "POINTER TO " if self.pointer else "REF_TO "
        return kind + self.target.name


def value_type(declared: Type) -> Type:
    """The type a variable of `declared` type is used as: a REFERENCE TO T as a T."""
    if isinstance(declared, RefType) and declared.implicit and declared.target is not None:
        return declared.target
    return declared


def is_implicit_reference(declared: Type) -> bool:
    return isinstance(declared, RefType) and declared.implicit


NULL_TYPE = RefType(None)

Type = (
    ElementaryType
    | ArrayType
    | OpenArrayType
    | StructType
    | EnumType
    | FbType
    | VariadicType
    | RefType
    | InterfaceType
)


def _int(name: str, bits: int, signed: bool, category: str = "int") -> ElementaryType:
    return ElementaryType(name, category, bits, signed)


BOOL = ElementaryType("BOOL", "bool", 1)
TIME = ElementaryType("TIME", "time", 64, True)
LTIME = ElementaryType("LTIME", "time", 64, True)
REAL = ElementaryType("REAL", "real", 32, True)
LREAL = ElementaryType("LREAL", "real", 64, True)
STRING = ElementaryType("STRING", "string")
WSTRING = ElementaryType("WSTRING", "string")
SINT, INT, DINT, LINT = (
    _int(n, b, True) for n, b in (("SINT", 8), ("INT", 16), ("DINT", 32), ("LINT", 64))
)
USINT, UINT, UDINT, ULINT = (
    _int(n, b, False) for n, b in (("USINT", 8), ("UINT", 16), ("UDINT", 32), ("ULINT", 64))
)
BYTE, WORD, DWORD, LWORD = (
    _int(n, b, False, "bits") for n, b in (("BYTE", 8), ("WORD", 16), ("DWORD", 32), ("LWORD", 64))
)
DATE = ElementaryType("DATE", "date", 64, True)
TOD = ElementaryType("TOD", "date", 64, True)
DT = ElementaryType("DT", "date", 64, True)
# The types of literals before the context gives them one.
ANY_INT = ElementaryType("ANY_INT", "int", 64, True)
ANY_REAL = ElementaryType("ANY_REAL", "real", 64, True)

ELEMENTARY: dict[str, ElementaryType] = {
    t.name: t
    for t in (
        BOOL, SINT, INT, DINT, LINT, USINT, UINT, UDINT, ULINT, BYTE, WORD, DWORD, LWORD,
        REAL, LREAL, TIME, LTIME, STRING, WSTRING, DATE, TOD, DT,
    )
}  # fmt: skip
LDATE = ElementaryType("LDATE", "date", 64, True)
LTOD = ElementaryType("LTOD", "date", 64, True)
LDT = ElementaryType("LDT", "date", 64, True)
# Spelled-out names of the date types are the same types.
ELEMENTARY.update(
    {
        "LDATE": LDATE,
        "LTOD": LTOD,
        "LDT": LDT,
        "TIME_OF_DAY": TOD,
        "LTIME_OF_DAY": LTOD,
        "DATE_AND_TIME": DT,
        "LDATE_AND_TIME": LDT,
        "CHAR": ElementaryType("CHAR", "string", length=1),
        "WCHAR": ElementaryType("WCHAR", "string", length=1),
    }
)


def elementary(name: str) -> ElementaryType | None:
    return ELEMENTARY.get(name.upper())


def integer_like(t: Type) -> ElementaryType | None:
    """The integer representation of `t` (enums count as their base type)."""
    if isinstance(t, EnumType):
        return t.base
    if isinstance(t, ElementaryType) and t.is_integer:
        return t
    return None


def common_numeric(a: ElementaryType, b: ElementaryType) -> ElementaryType | None:
    """The type of `a op b` for arithmetic, or None if the operands do not mix."""
    if a == b:
        return a
    if not (a.is_numeric and b.is_numeric):
        return None
    if a.category == "real" or b.category == "real":
        concrete = [t for t in (a, b) if t.category == "real" and not t.is_any_literal]
        if not concrete:
            return LREAL
        return LREAL if LREAL in concrete else REAL
    if ANY_INT in (a, b):
        # An integer literal counts as DINT, so narrow integers are promoted (USINT - 1 is
        # -1, as in CODESYS); bit strings keep their type (b AND 16#0F is a BYTE).
        other = b if a == ANY_INT else a
        if other.category == "int" and other.bits < 32:
            return DINT
        return other
    if a.category == "bits" or b.category == "bits":
        return a if a.bits >= b.bits else b
    if a.signed == b.signed:
        return a if a.bits >= b.bits else b
    signed, unsigned = (a, b) if a.signed else (b, a)
    if signed.bits > unsigned.bits:
        return signed
    # a signed type that holds every value of the unsigned one
    return {8: INT, 16: DINT, 32: LINT}.get(unsigned.bits, LINT)


# IEC 61131-3 ed. 3, its table of implicit conversions: what a value undergoes without a
# conversion function, because no value is lost; closed under chaining (SINT -> INT -> DINT
# -> LREAL). Everything else needs X_TO_Y or TO_Y.
_WIDENS_TO: dict[str, tuple[str, ...]] = {
    "SINT": ("INT", "REAL"),
    "INT": ("DINT", "REAL"),
    "DINT": ("LINT", "LREAL"),
    "USINT": ("UINT", "INT", "REAL"),
    "UINT": ("UDINT", "DINT", "REAL"),
    "UDINT": ("ULINT", "LINT", "LREAL"),
    "REAL": ("LREAL",),
    "BOOL": ("BYTE",),
    "BYTE": ("WORD",),
    "WORD": ("DWORD",),
    "DWORD": ("LWORD",),
    "TIME": ("LTIME",),
    "DATE": ("LDATE",),
    "TOD": ("LTOD",),
    "DT": ("LDT",),
    "CHAR": ("STRING",),
    "WCHAR": ("WSTRING",),
}


def _widenings(name: str) -> frozenset[str]:
    reached: set[str] = set()
    todo = list(_WIDENS_TO.get(name, ()))
    while todo:
        wider = todo.pop()
        if wider not in reached:
            reached.add(wider)
            todo.extend(_WIDENS_TO.get(wider, ()))
    return frozenset(reached)


IMPLICIT_CONVERSIONS: dict[str, frozenset[str]] = {name: _widenings(name) for name in _WIDENS_TO}


def implicit_conversion(target: ElementaryType, source: ElementaryType) -> bool:
    """Does IEC 61131-3 convert a `source` value to `target` without a conversion function?
    The same type always; an untyped integer literal into any number (its range is checked
    apart), an untyped REAL literal into REAL or LREAL; otherwise table 11. Strings of
    different lengths are the same type (an assignment cuts a string to its length)."""
    if target.name == source.name:
        return True
    if source == ANY_INT:
        return target.is_numeric
    if source == ANY_REAL:
        return target.category == "real"
    return target.name in IMPLICIT_CONVERSIONS.get(source.name, frozenset())


def assignable(target: Type, source: Type) -> bool:
    """Can a value of `source` be stored in `target` without an explicit conversion?

    Generous where real PLC compilers are (implicit numeric conversions between integer
    widths and to REAL); the check stage (`checks.conversions`) tells which of these IEC
    61131-3 makes only with a conversion function (`implicit_conversion`).
    A variable-length array is no value: it is only passed on (`OpenArrayType.binds`).
    """
    if isinstance(target, OpenArrayType) or isinstance(source, OpenArrayType):
        return False
    if target == source:
        return True
    if isinstance(target, RefType | InterfaceType) or isinstance(source, RefType):
        # an instance into an interface, a derived block's reference into its base's:
        # `Scope.conforms`, which knows the blocks
        return isinstance(target, RefType | InterfaceType) and source == NULL_TYPE
    if isinstance(target, EnumType):
        return (isinstance(source, EnumType) and source.name == target.name) or source == ANY_INT
    if isinstance(source, EnumType):
        return isinstance(target, ElementaryType) and target.is_integer
    if isinstance(target, ArrayType) and isinstance(source, ArrayType):
        return target.size == source.size and assignable(target.element, source.element)
    if not isinstance(target, ElementaryType) or not isinstance(source, ElementaryType):
        return False
    if target.category == source.category:
        return True
    if target.is_numeric and source.is_numeric:
        return True
    # BOOL widens to a bit string (IEC 61131-3 ed. 3, table 11), but BOOL and the numbers
    # do not mix: `i := TRUE` and `b := 42` are mistakes (the literals 0 and 1 as BOOL are
    # a question of the value, answered by the check stage: `bool_literal`)
    return target.category == "bits" and source.category == "bool"


def artifact_type_text(t: Type) -> str:
    """A type as the artifact names it; strings keep their length (`STRING[4]`) so that the
    runtime can check what it writes."""
    if isinstance(t, ElementaryType) and t.category == "string" and t.name in ("STRING", "WSTRING"):
        return f"{t.name}[{t.max_length}]"
    if isinstance(t, InterfaceType):  # a reference to the instance it is assigned
        return f"INTERFACE {t.name}"
    if isinstance(t, ArrayType) and isinstance(t.element, InterfaceType):  # elements too
        ranges = ", ".join(f"{low}..{high}" for low, high in t.dims)
        return f"ARRAY[{ranges}] OF {artifact_type_text(t.element)}"
    return t.name
