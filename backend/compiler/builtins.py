"""The standard functions of IEC 61131-3 that the compiler knows by name.

Each builtin gives the type of a call from its argument types (or an error message) and
the call in the typed form (runtime/contract/code/typed_form.py) from its arguments'.
Standard *function blocks* (TON, CTU, ...) are not here: they are written in ST in
`stdlib/`.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal

from backend.compiler.conversions import converted, intrinsic, wrapped
from backend.compiler.types import (
    ANY_INT,
    ANY_REAL,
    BOOL,
    DINT,
    INT,
    LINT,
    LREAL,
    LWORD,
    REAL,
    STRING,
    TIME,
    ULINT,
    WSTRING,
    ArrayType,
    ElementaryType,
    EnumType,
    OpenArrayType,
    Type,
    artifact_type_text,
    common_numeric,
    elementary,
    integer_like,
)
from runtime.contract.code.typed_form import (
    Binary,
    BinaryOp,
    Chain,
    Choice,
    Const,
    Expr,
    Index,
    Named,
    Sequence,
    Unary,
    Var,
)

# (argument types) -> result type, or an error message
Typing = Callable[[list[Type]], Type | str]
# (arguments, argument types, result type) -> the call's value
Emitting = Callable[[list[Expr], list[Type], Type], Expr]


@dataclass(frozen=True)
class Builtin:
    name: str
    params: tuple[str, ...] | None  # names for named arguments; None: IN1, IN2, ... (variadic)
    typing: Typing
    emit: Emitting
    min_args: int = 1


def _numeric(t: Type) -> ElementaryType | None:
    if isinstance(t, EnumType):
        return t.base
    return t if isinstance(t, ElementaryType) and t.is_numeric else None


def _concrete(t: ElementaryType) -> ElementaryType:
    """The type a literal takes when nothing else decides: DINT, LREAL."""
    return {ANY_INT.name: DINT, ANY_REAL.name: LREAL}.get(t.name, t)


def _same_kind(a: Type, b: ElementaryType) -> bool:
    if not isinstance(a, ElementaryType):
        return False
    return a.category == b.category or (a.is_integer and b.is_integer)


def _conversion(target: ElementaryType, source_name: str | None) -> Builtin:
    def typing(args: list[Type]) -> Type | str:
        if len(args) != 1:
            return "takes exactly one argument"
        if integer_like(args[0]) is None and not isinstance(args[0], ElementaryType):
            return f"cannot convert {args[0].name}"
        if source_name is not None:
            wanted = elementary(source_name)
            arg = integer_like(args[0]) or args[0]
            concrete = isinstance(arg, ElementaryType) and not arg.is_any_literal
            if wanted is not None and concrete and not _same_kind(arg, wanted):
                return f"expects {wanted.name}, not {arg.name}"
        return target

    def emit(values: list[Expr], args: list[Type], result: Type) -> Expr:
        source = args[0]
        if isinstance(target, ElementaryType) and target.is_integer:
            src = integer_like(source) or source
            if isinstance(src, ElementaryType) and src.category in ("time", "date"):
                milliseconds = intrinsic("_idiv", target, values[0], Const(1_000_000, "LINT"))
                return wrapped(milliseconds, target)  # ns -> ms
        return converted(values[0], source, target)

    return Builtin(f"TO_{target.name}", ("IN",), typing, emit)


def _truncation(target: ElementaryType) -> Builtin:
    def typing(args: list[Type]) -> Type | str:
        if len(args) != 1 or _numeric(args[0]) is None:
            return "expects one number"
        return target

    def emit(values: list[Expr], args: list[Type], result: Type) -> Expr:
        return wrapped(intrinsic("int", target, values[0]), target)

    return Builtin("TRUNC", ("IN",), typing, emit)


def _bcd(to_bcd: bool, target: ElementaryType) -> Builtin:
    """BCD_TO_INT / INT_TO_BCD (and typed forms such as WORD_BCD_TO_INT): packed decimal."""

    def typing(args: list[Type]) -> Type | str:
        if len(args) != 1 or integer_like(args[0]) is None:
            return "expects one integer or bit string"
        return target

    def emit(values: list[Expr], args: list[Type], result: Type) -> Expr:
        helper = "_int_to_bcd" if to_bcd else "_bcd_to_int"
        return wrapped(intrinsic(helper, target, values[0]), target)

    return Builtin("BCD", ("IN",), typing, emit)


_BCD_FROM = re.compile(r"^(?:([A-Z]+)_)?BCD_TO_([A-Z]+)$")
_BCD_TO = re.compile(r"^([A-Z]+)_TO_BCD(?:_([A-Z]+))?$")
_CONVERSION = re.compile(r"^(?:([A-Z_]+?)_)?TO_([A-Z_]+)$")
_TRUNC = re.compile(r"^(?:([A-Z_]+?)_)?TRUNC(?:_([A-Z_]+))?$")


# ---- generic helpers -----------------------------------------------------------------------


def _same_numeric(args: list[Type]) -> ElementaryType | str:
    result: ElementaryType | None = None
    for arg in args:
        number = _numeric(arg)
        if number is None:
            return f"expects numbers, not {arg.name}"
        result = number if result is None else common_numeric(result, number)
        if result is None:
            return "arguments of different types"
    assert result is not None
    return result


def _comparable(args: list[Type]) -> Type | str:
    if all(isinstance(a, ElementaryType) and a.category in ("string",) for a in args):
        return BOOL
    if all(isinstance(a, ElementaryType) and a.category in ("time", "date", "bool") for a in args):
        return BOOL
    numeric = _same_numeric(args)
    return numeric if isinstance(numeric, str) else BOOL


def _real_result(args: list[Type]) -> Type | str:
    if len(args) != 1:
        return "takes exactly one argument"
    number = _numeric(args[0])
    if number is None:
        return f"expects a number, not {args[0].name}"
    return number if number.category == "real" and not number.is_any_literal else LREAL


def _fn(callee: str) -> Emitting:
    """A call of an intrinsic (or of what Python has) with the arguments as they are."""
    return lambda values, _args, result: intrinsic(callee, result, *values)


def _extreme(callee: str) -> Emitting:
    """MAX and MIN: Python's `max` or `min` of two values or more; of one, the value
    itself (`max(x)` would iterate over x, and a FUNCTION faulted with a TypeError)."""
    return lambda values, _args, result: (
        values[0] if len(values) == 1 else intrinsic(callee, result, *values)
    )


def _chained(op: BinaryOp, values: list[Expr], result: Type) -> Expr:
    """`a op b op c ...`, left to right."""
    name = artifact_type_text(result)
    chain = values[0]
    for value in values[1:]:
        chain = Binary(op, chain, value, name)
    return chain


def _compare_chain(op: BinaryOp) -> Emitting:
    """GT(a, b, c): a > b > c, as Python chains comparisons (each value evaluated once)."""

    def emit(values: list[Expr], args: list[Type], result: Type) -> Expr:
        return Chain(op, tuple(values))

    return emit


SHIFTS = frozenset({"SHL", "SHR", "ROL", "ROR"})


def shifted_literal_type(value: int | None, based: bool) -> ElementaryType:
    """The type an integer literal without one is shifted or rotated as: DINT, as every
    such literal (a based one a bit pattern of 32 bits: `16#FFFF_FFFF` is -1), unless its
    value needs more bits: LWORD for a based literal (a bit pattern of 64 bits), LINT for
    another, ULINT beyond LINT (`ROR(16#8000_0000_0000_0001, 1)` once lost its high bits)."""
    if value is None or -(1 << 31) <= value < (1 << 32 if based else 1 << 31):
        return ANY_INT
    if based and 0 <= value < 1 << 64:
        return LWORD
    return LINT if -(1 << 63) <= value < 1 << 63 else ULINT


def _shift(kind: str) -> Builtin:
    def typing(args: list[Type]) -> Type | str:
        if len(args) != 2:
            return "takes IN and N"
        value = integer_like(args[0])
        if value is None or integer_like(args[1]) is None:
            return "expects integers"
        return _concrete(value)

    def emit(values: list[Expr], args: list[Type], result: Type) -> Expr:
        assert isinstance(result, ElementaryType)
        value, n = values
        name = artifact_type_text(result)
        if kind == "SHL":
            return wrapped(Binary("<<", value, _shift_count(n, result.bits), name), result)
        if kind == "SHR" and result.signed:  # arithmetic for signed types
            return Binary(">>", value, n, name)
        bits = Binary("&", value, Const((1 << result.bits) - 1, name), name)
        if kind == "SHR":  # logical for unsigned types and bit strings
            return wrapped(Binary(">>", bits, n, name), result)
        width = Const(result.bits, "INT")
        return wrapped(
            intrinsic("_rol" if kind == "ROL" else "_ror", result, bits, n, width), result
        )

    return Builtin(kind, ("IN", "N"), typing, emit, min_args=2)


def _shift_count(n: Expr, bits: int) -> Expr:
    """SHL's count, at most the width of the type: every bit is shifted out at `bits`
    already, and Python makes the whole number before the wrap masks it (a count of two
    thousand million made a 250 MB number, one of 10**15 a MemoryError; the form check
    refuses a shift left by a count that is not so bounded). A negative count stays a
    run-time error of the program."""
    if isinstance(n, Const) and isinstance(n.value, int) and not isinstance(n.value, bool):
        return n if n.value <= bits else Const(bits, n.type)
    return intrinsic("min", n.type, n, Const(bits, n.type))


def _bitwise(op: BinaryOp, name: str) -> Builtin:
    def typing(args: list[Type]) -> Type | str:
        if all(a == BOOL for a in args):
            return BOOL
        result = _same_numeric(args)
        if isinstance(result, str) or result.category == "real":
            return "expects BOOL or bit strings"
        return _concrete(result)

    def emit(values: list[Expr], args: list[Type], result: Type) -> Expr:
        return _chained(op, values, result)

    return Builtin(name, None, typing, emit, min_args=2)


def _not_typing(args: list[Type]) -> Type | str:
    if len(args) != 1:
        return "takes one argument"
    if args[0] == BOOL:
        return BOOL
    value = integer_like(args[0])
    return _concrete(value) if value is not None else "expects BOOL or a bit string"


def _not_emit(values: list[Expr], args: list[Type], result: Type) -> Expr:
    if result == BOOL:
        return Unary("not", values[0], "BOOL")
    assert isinstance(result, ElementaryType)
    return wrapped(Unary("~", values[0], artifact_type_text(result)), result)


def _sel_typing(args: list[Type]) -> Type | str:
    if len(args) != 3:
        return "takes G, IN0 and IN1"
    if args[0] != BOOL:
        return "G must be BOOL"
    return _common(args[1:])


def _common(args: list[Type]) -> Type | str:
    if all(a == args[0] for a in args):
        first = args[0]
        return _concrete(first) if isinstance(first, ElementaryType) else first
    numeric = _same_numeric(args)
    if isinstance(numeric, str):
        if all(isinstance(a, ElementaryType) and a.category == "string" for a in args):
            return STRING
        if all(isinstance(a, ElementaryType) and a.category in ("time",) for a in args):
            return args[0]
        return numeric
    return _concrete(numeric)


def _select(values: list[Expr], args: list[Type], result: Type) -> Expr:
    """SEL(G, IN0, IN1): only the input chosen is evaluated."""
    return Choice(values[0], values[2], values[1], artifact_type_text(result))


def _limit(values: list[Expr], args: list[Type], result: Type) -> Expr:
    """LIMIT(MN, IN, MX) = MIN(MAX(IN, MN), MX)."""
    low, value, high = values
    return intrinsic("min", result, intrinsic("max", result, value, low), high)


def _mux_typing(args: list[Type]) -> Type | str:
    if len(args) < 2:
        return "takes K and at least one input"
    if integer_like(args[0]) is None:
        return "K must be an integer"
    return _common(args[1:])


def _limit_typing(args: list[Type]) -> Type | str:
    if len(args) != 3:
        return "takes MN, IN and MX"
    return _common(args)


def _bound(kind: str) -> Builtin:
    def typing(args: list[Type]) -> Type | str:
        if len(args) != 2 or not isinstance(args[0], ArrayType | OpenArrayType):
            return "takes an array and a dimension"
        return DINT

    def emit(values: list[Expr], args: list[Type], result: Type) -> Expr:
        array = args[0]
        dim = Binary("-", values[1], Const(1, "DINT"), "DINT")
        if isinstance(array, OpenArrayType):  # [items, bounds] of the array passed
            bounds = Index(Index(values[0], Const(1, "DINT"), ""), dim, "")
            return Index(bounds, Const(0 if kind == "LOWER" else 1, "DINT"), "DINT")
        assert isinstance(array, ArrayType)
        ends = tuple(Const(lo if kind == "LOWER" else hi, "DINT") for lo, hi in array.dims)
        return Index(Sequence(ends, "", as_tuple=True), dim, "DINT")

    return Builtin(f"{kind}_BOUND", ("ARR", "DIM"), typing, emit, min_args=2)


def _abs_typing(args: list[Type]) -> Type | str:
    if len(args) != 1:
        return "takes one argument"
    number = _numeric(args[0])
    return _concrete(number) if number is not None else "expects a number"


def _abs_emit(values: list[Expr], args: list[Type], result: Type) -> Expr:
    assert isinstance(result, ElementaryType)
    return wrapped(intrinsic("abs", result, values[0]), result)


def _arith(name: str, op: BinaryOp | Literal["/", "MOD"], variadic: bool) -> Builtin:
    def typing(args: list[Type]) -> Type | str:
        if not variadic and len(args) != 2:
            return "takes two arguments"
        if all(isinstance(a, ElementaryType) and a.category in ("time",) for a in args):
            return args[0]
        result = _same_numeric(args)
        return result if isinstance(result, str) else _concrete(result)

    def emit(values: list[Expr], args: list[Type], result: Type) -> Expr:
        assert isinstance(result, ElementaryType)
        if op == "/":
            helper = "_fdiv" if result.category == "real" else "_idiv"
            return wrapped(intrinsic(helper, result, *values), result)
        if op == "MOD":
            return intrinsic("_imod", result, *values)
        return wrapped(_chained(op, values, result), result)

    return Builtin(name, None if variadic else ("IN1", "IN2"), typing, emit, min_args=2)


_MATH = {
    name: f"_math.{name.lower()}"
    for name in ("SQRT", "LN", "EXP", "SIN", "COS", "TAN", "ASIN", "ACOS", "ATAN")
}
_MATH["LN"] = "_math.log"  # the natural logarithm: math has no `ln`
_MATH["LOG"] = "_math.log10"


def _math_fn(name: str) -> Builtin:
    helper = _MATH[name]

    def emit(values: list[Expr], args: list[Type], result: Type) -> Expr:
        value = intrinsic("_safe_math", result, Named(helper), values[0])
        return intrinsic("_f32", result, value) if result == REAL else value

    return Builtin(name, ("IN",), _real_result, emit)


def _expt_typing(args: list[Type]) -> Type | str:
    if len(args) != 2:
        return "takes IN1 and IN2"
    base = _numeric(args[0])
    if base is None or _numeric(args[1]) is None:
        return "expects numbers"
    return base if base.category == "real" and not base.is_any_literal else LREAL


def _strings(args: list[Type]) -> Type | str:
    if not all(isinstance(a, ElementaryType) and a.category == "string" for a in args):
        return "expects strings"
    if all(a == args[0] for a in args):
        return args[0]
    return WSTRING if all(a.name == WSTRING.name for a in args) else STRING


def _string_of(args: list[Type]) -> Type:
    """LEFT, MID, INSERT, ...: a WSTRING of a WSTRING, else a STRING."""
    return WSTRING if args and args[0].name == WSTRING.name else STRING


def _time_arith(name: str, op: BinaryOp, result_name: str | None) -> Builtin:
    """ADD_TIME, SUB_DT_TIME, ...: the typed forms of + and - on times and dates."""

    def typing(args: list[Type]) -> Type | str:
        if len(args) != 2:
            return "takes IN1 and IN2"
        if result_name is not None:
            found = elementary(result_name)
            assert found is not None
            return found
        return args[0]

    def emit(values: list[Expr], args: list[Type], result: Type) -> Expr:
        assert isinstance(result, ElementaryType)
        return wrapped(Binary(op, values[0], values[1], artifact_type_text(result)), result)

    return Builtin(name, ("IN1", "IN2"), typing, emit, min_args=2)


def _time_scale(name: str, op: str) -> Builtin:
    """MUL_TIME / DIV_TIME (MULTIME / DIVTIME in the first edition): TIME times a number."""

    def typing(args: list[Type]) -> Type | str:
        if len(args) != 2 or not (
            isinstance(args[0], ElementaryType) and args[0].category == "time"
        ):
            return "takes a TIME and a number"
        if _numeric(args[1]) is None:
            return "takes a TIME and a number"
        return args[0]

    def emit(values: list[Expr], args: list[Type], result: Type) -> Expr:
        assert isinstance(result, ElementaryType)
        if op == "*":
            scaled: Expr = Binary("*", values[0], values[1], "LREAL")
        else:
            scaled = intrinsic("_fdiv", "LREAL", *values)
        return wrapped(intrinsic("_round", result, scaled), result)

    return Builtin(name, ("IN1", "IN2"), typing, emit, min_args=2)


def _printf_typing(args: list[Type]) -> Type | str:
    if not args or not (isinstance(args[0], ElementaryType) and args[0].category == "string"):
        return "needs a format string first"
    return DINT


_COMPARISONS: tuple[tuple[str, BinaryOp], ...] = (
    ("GT", ">"),
    ("GE", ">="),
    ("EQ", "=="),
    ("LE", "<="),
    ("LT", "<"),
    ("NE", "!="),
)
# the typed forms of + and - on times and dates: (name, operation, result type)
_TIME_ARITHMETIC: tuple[tuple[str, BinaryOp, str], ...] = (
    ("ADD_TIME", "+", "TIME"),
    ("ADD_LTIME", "+", "LTIME"),
    ("SUB_TIME", "-", "TIME"),
    ("SUB_LTIME", "-", "LTIME"),
    ("ADD_TOD_TIME", "+", "TOD"),
    ("ADD_LTOD_LTIME", "+", "TOD"),
    ("ADD_DT_TIME", "+", "DT"),
    ("ADD_LDT_LTIME", "+", "DT"),
    ("SUB_TOD_TIME", "-", "TOD"),
    ("SUB_LTOD_LTIME", "-", "TOD"),
    ("SUB_DT_TIME", "-", "DT"),
    ("SUB_LDT_LTIME", "-", "DT"),
    ("SUB_DATE_DATE", "-", "TIME"),
    ("SUB_LDATE_LDATE", "-", "LTIME"),
    ("SUB_TOD_TOD", "-", "TIME"),
    ("SUB_LTOD_LTOD", "-", "LTIME"),
    ("SUB_DT_DT", "-", "TIME"),
    ("SUB_LDT_LDT", "-", "LTIME"),
    ("CONCAT_DATE_TOD", "+", "DT"),
    ("CONCAT_LDATE_LTOD", "+", "DT"),
)

_FIXED: dict[str, Builtin] = {
    b.name: b
    for b in [
        Builtin("ABS", ("IN",), _abs_typing, _abs_emit),
        *(_math_fn(name) for name in _MATH),
        Builtin("EXPT", ("IN1", "IN2"), _expt_typing, _fn("_pow"), min_args=2),
        _arith("ADD", "+", True),
        _arith("MUL", "*", True),
        _arith("SUB", "-", False),
        _arith("DIV", "/", False),
        _arith("MOD", "MOD", False),
        Builtin(
            "MOVE",
            ("IN",),
            lambda a: a[0] if len(a) == 1 else "takes one argument",
            lambda values, _args, _result: values[0],
        ),
        _shift("SHL"),
        _shift("SHR"),
        _shift("ROL"),
        _shift("ROR"),
        _bitwise("&", "AND"),
        _bitwise("|", "OR"),
        _bitwise("^", "XOR"),
        Builtin("NOT", ("IN",), _not_typing, _not_emit),
        Builtin("SEL", ("G", "IN0", "IN1"), _sel_typing, _select, min_args=3),
        Builtin("MUX", None, _mux_typing, _fn("_mux"), min_args=2),
        Builtin("MAX", None, _common, _extreme("max"), min_args=1),
        Builtin("MIN", None, _common, _extreme("min"), min_args=1),
        Builtin("LIMIT", ("MN", "IN", "MX"), _limit_typing, _limit, min_args=3),
        *(
            Builtin(name, None, _comparable, _compare_chain(op), min_args=2)
            for name, op in _COMPARISONS
        ),
        Builtin("LEN", ("IN",), lambda a: INT, _fn("len")),
        Builtin("LEFT", ("IN", "L"), _string_of, _fn("_left"), min_args=2),
        Builtin("RIGHT", ("IN", "L"), _string_of, _fn("_right"), min_args=2),
        Builtin("MID", ("IN", "L", "P"), _string_of, _fn("_mid"), min_args=3),
        Builtin("CONCAT", None, _strings, lambda v, a, r: _chained("+", v, r), min_args=1),
        Builtin(
            "INSERT",
            ("IN1", "IN2", "P"),
            _string_of,
            _fn("_insert"),
            min_args=3,
        ),
        Builtin("DELETE", ("IN", "L", "P"), _string_of, _fn("_delete"), min_args=3),
        Builtin(
            "REPLACE",
            ("IN1", "IN2", "L", "P"),
            _string_of,
            _fn("_replace"),
            min_args=4,
        ),
        Builtin("FIND", ("IN1", "IN2"), lambda a: INT, _fn("_find"), min_args=2),
        *(_time_arith(name, op, result) for name, op, result in _TIME_ARITHMETIC),
        *(
            _time_scale(name, op)
            for name, op in (
                ("MUL_TIME", "*"),
                ("MULTIME", "*"),
                ("MUL_LTIME", "*"),
                ("DIV_TIME", "/"),
                ("DIVTIME", "/"),
                ("DIV_LTIME", "/"),
            )
        ),
        _bound("LOWER"),
        _bound("UPPER"),
        Builtin("PRINTF", None, _printf_typing, _fn("_printf")),
        Builtin(
            "__CURRENT_TIME",
            (),
            lambda a: TIME,
            lambda _values, _args, _result: Var("now_ns", "system", "TIME"),
            min_args=0,
        ),
    ]
}


def names() -> list[str]:
    """The standard functions of a fixed name, sorted (the conversions `<T>_TO_<T>` and
    their kin follow patterns `lookup` knows)."""
    return sorted(name for name in _FIXED if not name.startswith("_"))


def lookup(name: str) -> Builtin | None:
    upper = name.upper()
    found = _FIXED.get(upper)
    if found is not None:
        return found
    bcd = _BCD_FROM.match(upper)
    if bcd:
        target = elementary(bcd.group(2))
        if target is not None and target.is_integer:
            return _bcd(False, target)
    bcd = _BCD_TO.match(upper)
    if bcd:
        target = elementary(bcd.group(2) or "WORD")
        if target is not None and target.is_integer:
            return _bcd(True, target)
    trunc = _TRUNC.match(upper)
    if trunc:
        target = elementary(trunc.group(2) or "DINT")
        if target is not None and target.is_integer:
            return _truncation(target)
    conversion = _CONVERSION.match(upper)
    if conversion:
        source, target_name = conversion.groups()
        target = elementary(target_name)
        if target is not None and (source is None or elementary(source) is not None):
            return _conversion(target, source)
    return None
