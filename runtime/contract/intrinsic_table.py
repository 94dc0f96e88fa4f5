"""Every name generated code finds in its namespace, declared once: what it takes, what it
gives, the program faults it raises and what it means (docs/artifact.md, "Generated code").

The compiler writes calls of these, the check of generated code allows exactly these names
(`code/names.py`), the Python tier binds each to its implementation
(`runtime/code/intrinsics.py`, checked against this table as it builds a namespace) and
the native tier translates the ones it knows to C by these entries
(`runtime/code/native/translate.py`). A test holds the implementations, their arities and
docs/artifact.md to this table.

Parameter and result kinds are the run-time representation (docs/artifact.md): `INT` an
integer of any integer, bit-string, TIME or date type; `REAL` a float; `BOOL`; `STRING` a
str (STRING or WSTRING); `ANY` a value of any type; `OBJECT` a structure or block
instance; `REFERENCE` a reference or None; `*` before the last kind: any number of
those (none too); `-` no value. docs/native-code.md says where this is going: a typed
form of the program whose calls name these entries."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Intrinsic:
    """A function generated code calls (`called`), or an object it reads."""

    name: str
    params: tuple[str, ...]
    result: str
    faults: tuple[str, ...]  # the program faults it raises (runtime/code/intrinsics.py)
    meaning: str
    called: bool = True

    @property
    def variadic(self) -> bool:
        return bool(self.params) and self.params[-1].startswith("*")


def _called(
    name: str, params: str, result: str, meaning: str, faults: tuple[str, ...] = ()
) -> Intrinsic:
    return Intrinsic(name, tuple(params.split()), result, faults, meaning)


def _object(name: str, meaning: str) -> Intrinsic:
    return Intrinsic(name, (), "OBJECT", (), meaning, called=False)


ZERO = "DivisionByZero"
BOUNDS = "IndexOutOfRange"
NULL = "NullDereference"
FAULT = "ProgramFault"

# arithmetic, what the native tier translates to C
IDIV = _called("_idiv", "INT INT", "INT", "integer division, truncating toward zero", (ZERO,))
IMOD = _called("_imod", "INT INT", "INT", "the remainder of `_idiv`", (ZERO,))
FDIV = _called("_fdiv", "REAL REAL", "REAL", "REAL division, IEEE results")
TDIV = _called("_tdiv", "INT REAL", "INT", "TIME divided by a number", (ZERO,))
POW = _called(
    "_pow", "REAL REAL", "REAL", "`**`: +inf past the range, NaN of a negative base's fraction"
)
REF = _called("_ref", "OBJECT ANY STRING *BOOL", "REFERENCE", "REF(x)", (FAULT,))
DEREF = _called("_deref", "REFERENCE", "ANY", "what a reference refers to", (NULL,))
DEREF_SET = _called(
    "_deref_set", "REFERENCE ANY", "-", "writing what a reference refers to", (NULL,)
)
MUX = _called("_mux", "INT *ANY", "ANY", "MUX", (BOUNDS,))
COPY = _called("_copy", "ANY", "ANY", "a deep copy: value semantics of arrays and structures")
FILL = _called(
    "_fill",
    "ANY ANY",
    "-",
    "an array or structure written whole into a variable, in place",
)
ROL = _called("_rol", "INT INT INT", "INT", "ROL over a width")
ROR = _called("_ror", "INT INT INT", "INT", "ROR over a width")
F32 = _called("_f32", "REAL", "REAL", "rounding to IEEE single precision (REAL)")
ROUND = _called("_round", "REAL", "INT", "to the nearest integer, halves away from zero")
SAFE_MATH = _called(
    "_safe_math", "ANY REAL", "REAL", "a function of `_math`, NaN out of its domain"
)
IX = _called("_ix", "INT INT INT", "INT", "the offset of an index within its bounds", (BOUNDS,))
TICK = _object("_tick", "None, or the slice meter's tick, called at each loop pass")

INTRINSICS: tuple[Intrinsic, ...] = (
    IDIV,
    IMOD,
    FDIV,
    TDIV,
    POW,
    F32,
    ROUND,
    IX,
    _called("_setbits", "INT INT INT INT", "INT", "a bit or part of a bit string written"),
    COPY,
    FILL,
    _called("_init", "OBJECT ANY", "OBJECT", "a structure initializer applied"),
    ROL,
    ROR,
    MUX,
    _called("_bcd_to_int", "INT", "INT", "BCD_TO_INT", (FAULT,)),
    _called("_int_to_bcd", "INT", "INT", "INT_TO_BCD", (FAULT,)),
    _called("_str_to_int", "STRING", "INT", "a string's integer (0 when none)"),
    _called("_str_to_real", "STRING", "REAL", "a string's REAL (0.0 when none)"),
    _called("_str_to_bool", "STRING", "BOOL", "a string's BOOL"),
    _called("_real_to_str", "REAL", "STRING", "a REAL as text"),
    _called("_time_to_str", "INT STRING", "STRING", "a TIME as its literal, with its prefix"),
    _called("_date_to_str", "INT STRING", "STRING", "a date or time of day as its literal"),
    _called("_str_to_time", "STRING", "INT", "a TIME literal's nanoseconds"),
    _called("_ord", "STRING", "INT", "the code of a string's first character"),
    _called("_w2s", "STRING", "STRING", "WSTRING to STRING"),
    _called("_s2w", "STRING", "STRING", "STRING to WSTRING"),
    _called("_left", "STRING INT", "STRING", "LEFT"),
    _called("_right", "STRING INT", "STRING", "RIGHT"),
    _called("_mid", "STRING INT INT", "STRING", "MID (positions from 1)"),
    _called("_insert", "STRING STRING INT", "STRING", "INSERT"),
    _called("_delete", "STRING INT INT", "STRING", "DELETE"),
    _called("_replace", "STRING STRING INT INT", "STRING", "REPLACE"),
    _called("_find", "STRING STRING", "INT", "FIND (0 when not found)"),
    SAFE_MATH,
    REF,
    DEREF,
    DEREF_SET,
    _called("_printf", "STRING *ANY", "INT", "the test helper of `padt exec`"),
    _called("_ActionControl", "", "OBJECT", "a new IEC action control block"),
    _called("_step_time", "OBJECT INT", "INT", "an SFC step's time"),
    _called("_step_enter", "OBJECT", "-", "an SFC step becoming active"),
    _called("_test", "STRING *ANY", "ANY", "a test function (docs/testing.md)"),
    _object("_SYS", "the system variables and the running program's time"),
    _object("_G", "the globals as the running program sees them"),
    _object("_P", "the program instances by class name"),
    TICK,
    _object("_math", "the math module (only as `_safe_math(_math.f, x)`)"),
    _object("_SfcStep", "the class of SFC steps"),
    _object("_reference_roots", "the paths of instances that references read"),
)
