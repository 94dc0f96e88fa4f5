"""The standard functions of IEC 61131-3 that the compiler knows by name.

Each builtin gives the type of a call from its argument types (or an error message) and
the Python code of the call from the arguments' code. Standard *function blocks* (TON,
CTU, ...) are not here: they are written in ST in `stdlib/`.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass

from backend.compiler.types import (
    ANY_INT,
    ANY_REAL,
    BOOL,
    DINT,
    INT,
    LREAL,
    REAL,
    STRING,
    TIME,
    WSTRING,
    ArrayType,
    ElementaryType,
    EnumType,
    OpenArrayType,
    Type,
    common_numeric,
    elementary,
    integer_like,
)

# (argument types) -> result type, or an error message
Typing = Callable[[list[Type]], Type | str]
# (argument code, argument types, result type) -> code
Emitting = Callable[[list[str], list[Type], Type], str]


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


NS_PER_DAY = 86_400_000_000_000


def wrap_code(code: str, t: ElementaryType, offset: int = 0) -> str:
    """Bring an integer expression, plus `offset`, into the range of its type (two's
    complement; a time of day wraps around midnight). A signed wrap to 8 or 16 bits adds
    a constant anyway: an offset costs nothing there (`x + 1` wraps as
    `(x + 32769 & 65535) - 32768`); elsewhere it is added to the expression."""
    masked = t.signed and t.is_integer and not t.is_any_literal and t.bits < 32
    if offset and not masked:
        code, offset = f"(({code}) + {offset})", 0
    if t.name in ("TOD", "LTOD"):
        return f"(({code}) % {NS_PER_DAY})"
    if t.is_any_literal or not (t.is_integer or t.category in ("time", "date")):
        return code
    mask = (1 << t.bits) - 1
    half = 1 << (t.bits - 1)
    if t.bits >= 32:
        # the wrap's constants are numbers of several digits for CPython (30 bits a digit),
        # slower to add and mask than testing a value that is in range almost always: a
        # DINT store 67 -> 34 ns, a LINT or TIME one 53 -> 35. Nested wraps may share the
        # name: an inner one is read before an outer one binds it
        low, high = (-half, half - 1) if t.signed else (0, mask)
        wrap = f"(__w + {half} & {mask}) - {half}" if t.signed else f"__w & {mask}"
        return f"(__w if {low} <= (__w := {code}) <= {high} else {wrap})"
    if t.signed:
        return f"((({code}) + {half + offset} & {mask}) - {half})"
    return f"(({code}) & {mask})"


# ---- conversions ------------------------------------------------------------------------


def convert_code(code: str, source: Type, target: ElementaryType) -> str:
    """Code converting a value of `source` to `target` (X_TO_Y semantics)."""
    src = integer_like(source) or source
    if not isinstance(src, ElementaryType):
        return code
    cat, tcat = src.category, target.category
    if tcat == "bool":
        if cat == "string":
            return f"_str_to_bool({code})"
        return f"({code} != 0)" if cat != "bool" else code
    if tcat in ("int", "bits"):
        if cat == "real":
            return wrap_code(f"_round({code})", target)
        if cat == "string" and src.name in ("CHAR", "WCHAR"):
            return f"_ord({code})"
        if cat == "string":
            if not target.signed:  # a negative text does not convert to an unsigned type
                return wrap_code(f"max(_str_to_int({code}), 0)", target)
            return wrap_code(f"_str_to_int({code})", target)
        if cat == "bool":
            return f"int({code})"
        if src.is_any_literal or (
            src.is_integer and (src.bits < target.bits and (target.signed or not src.signed))
        ):
            return code
        return wrap_code(code, target)
    if tcat == "real":
        if cat == "string":
            return f"_str_to_real({code})"
        if target.bits == 32 and not (cat == "real" and src.bits == 32):
            return f"_f32({code})"
        return f"float({code})"
    if tcat == "string":
        if cat == "real":
            return f"_real_to_str({code})"
        if cat == "bool":
            return f"('TRUE' if {code} else 'FALSE')"
        if cat == "time":
            prefix = "LTIME#" if src.name == "LTIME" else "T#"
            return f"_time_to_str({code}, {prefix!r})"
        if cat == "date":
            return f"_date_to_str({code}, {src.name!r})"
        if cat == "string":
            if src.name.startswith("W") and not target.name.startswith("W"):
                return f"_w2s({code})"
            if target.name.startswith("W") and not src.name.startswith("W"):
                return f"_s2w({code})"
            return code
        return f"str({code})"
    if tcat in ("time", "date"):
        if cat == "string":
            return f"_str_to_time({code})"
        if cat == "real":
            return wrap_code(f"_round({code} * 1000000)", target)  # REAL ms -> ns
        if cat in ("int", "bits"):
            return wrap_code(f"({code}) * 1000000", target)  # integers count milliseconds
        return code
    return code


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

    def emit(codes: list[str], args: list[Type], result: Type) -> str:
        source = args[0]
        if isinstance(target, ElementaryType) and target.is_integer:
            src = integer_like(source) or source
            if isinstance(src, ElementaryType) and src.category in ("time", "date"):
                return wrap_code(f"_idiv({codes[0]}, 1000000)", target)  # ns -> ms
        return convert_code(codes[0], source, target)

    return Builtin(f"TO_{target.name}", ("IN",), typing, emit)


def _truncation(target: ElementaryType) -> Builtin:
    def typing(args: list[Type]) -> Type | str:
        if len(args) != 1 or _numeric(args[0]) is None:
            return "expects one number"
        return target

    def emit(codes: list[str], args: list[Type], result: Type) -> str:
        return wrap_code(f"int({codes[0]})", target)

    return Builtin("TRUNC", ("IN",), typing, emit)


def _bcd(to_bcd: bool, target: ElementaryType) -> Builtin:
    """BCD_TO_INT / INT_TO_BCD (and typed forms such as WORD_BCD_TO_INT): packed decimal."""

    def typing(args: list[Type]) -> Type | str:
        if len(args) != 1 or integer_like(args[0]) is None:
            return "expects one integer or bit string"
        return target

    def emit(codes: list[str], args: list[Type], result: Type) -> str:
        helper = "_int_to_bcd" if to_bcd else "_bcd_to_int"
        return wrap_code(f"{helper}({codes[0]})", target)

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


def _fn(template: str) -> Emitting:
    """Code from a template with {0}, {1}... for the arguments."""
    return lambda codes, _args, _result: template.format(*codes)


def _numeric_result(name: str, wrap_result: bool) -> Emitting:
    def emit(codes: list[str], args: list[Type], result: Type) -> str:
        code = f"{name}({', '.join(codes)})"
        if wrap_result and isinstance(result, ElementaryType):
            return wrap_code(code, result)
        return code

    return emit


def _compare_chain(op: str) -> Emitting:
    def emit(codes: list[str], args: list[Type], result: Type) -> str:
        return "(" + f" {op} ".join(codes) + ")"

    return emit


def _shift(kind: str) -> Builtin:
    def typing(args: list[Type]) -> Type | str:
        if len(args) != 2:
            return "takes IN and N"
        value = integer_like(args[0])
        if value is None or integer_like(args[1]) is None:
            return "expects integers"
        return _concrete(value)

    def emit(codes: list[str], args: list[Type], result: Type) -> str:
        assert isinstance(result, ElementaryType)
        value, n = codes
        mask = (1 << result.bits) - 1
        bits = result.bits
        if kind == "SHL":
            return wrap_code(f"({value} << {n})", result)
        if kind == "SHR":  # arithmetic for signed types, logical for unsigned and bit strings
            if result.signed:
                return f"({value} >> {n})"
            return wrap_code(f"(({value} & {mask}) >> {n})", result)
        if kind == "ROL":
            return wrap_code(f"_rol({value} & {mask}, {n}, {bits})", result)
        return wrap_code(f"_ror({value} & {mask}, {n}, {bits})", result)

    return Builtin(kind, ("IN", "N"), typing, emit, min_args=2)


def _bitwise(op: str, name: str) -> Builtin:
    def typing(args: list[Type]) -> Type | str:
        if all(a == BOOL for a in args):
            return BOOL
        result = _same_numeric(args)
        if isinstance(result, str) or result.category == "real":
            return "expects BOOL or bit strings"
        return _concrete(result)

    def emit(codes: list[str], args: list[Type], result: Type) -> str:
        return "(" + f" {op} ".join(codes) + ")"

    return Builtin(name, None, typing, emit, min_args=2)


def _not_typing(args: list[Type]) -> Type | str:
    if len(args) != 1:
        return "takes one argument"
    if args[0] == BOOL:
        return BOOL
    value = integer_like(args[0])
    return _concrete(value) if value is not None else "expects BOOL or a bit string"


def _not_emit(codes: list[str], args: list[Type], result: Type) -> str:
    if result == BOOL:
        return f"(not {codes[0]})"
    assert isinstance(result, ElementaryType)
    return wrap_code(f"(~{codes[0]})", result)


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

    def emit(codes: list[str], args: list[Type], result: Type) -> str:
        array = args[0]
        if isinstance(array, OpenArrayType):  # [items, bounds] of the array passed
            return f"{codes[0]}[1][{codes[1]} - 1][{0 if kind == 'LOWER' else 1}]"
        assert isinstance(array, ArrayType)
        values = [lo if kind == "LOWER" else hi for lo, hi in array.dims]
        return f"{tuple(values)!r}[{codes[1]} - 1]"

    return Builtin(f"{kind}_BOUND", ("ARR", "DIM"), typing, emit, min_args=2)


def _abs_typing(args: list[Type]) -> Type | str:
    if len(args) != 1:
        return "takes one argument"
    number = _numeric(args[0])
    return _concrete(number) if number is not None else "expects a number"


def _abs_emit(codes: list[str], args: list[Type], result: Type) -> str:
    assert isinstance(result, ElementaryType)
    return wrap_code(f"abs({codes[0]})", result)


def _arith(name: str, op: str, variadic: bool) -> Builtin:
    def typing(args: list[Type]) -> Type | str:
        if not variadic and len(args) != 2:
            return "takes two arguments"
        if all(isinstance(a, ElementaryType) and a.category in ("time",) for a in args):
            return args[0]
        result = _same_numeric(args)
        return result if isinstance(result, str) else _concrete(result)

    def emit(codes: list[str], args: list[Type], result: Type) -> str:
        assert isinstance(result, ElementaryType)
        if op == "/":
            helper = "_fdiv" if result.category == "real" else "_idiv"
            return wrap_code(f"{helper}({codes[0]}, {codes[1]})", result)
        if op == "MOD":
            return f"_imod({codes[0]}, {codes[1]})"
        return wrap_code("(" + f" {op} ".join(codes) + ")", result)

    return Builtin(name, None if variadic else ("IN1", "IN2"), typing, emit, min_args=2)


_MATH = {
    name: f"_math.{name.lower()}"
    for name in ("SQRT", "LN", "EXP", "SIN", "COS", "TAN", "ASIN", "ACOS", "ATAN")
}
_MATH["LN"] = "_math.log"  # the natural logarithm: math has no `ln`
_MATH["LOG"] = "_math.log10"


def _math_fn(name: str) -> Builtin:
    helper = _MATH[name]

    def emit(codes: list[str], args: list[Type], result: Type) -> str:
        code = f"_safe_math({helper}, {codes[0]})"
        return f"_f32({code})" if result == REAL else code

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


def _time_arith(name: str, op: str, result_name: str | None) -> Builtin:
    """ADD_TIME, SUB_DT_TIME, ...: the typed forms of + and - on times and dates."""

    def typing(args: list[Type]) -> Type | str:
        if len(args) != 2:
            return "takes IN1 and IN2"
        if result_name is not None:
            found = elementary(result_name)
            assert found is not None
            return found
        return args[0]

    def emit(codes: list[str], args: list[Type], result: Type) -> str:
        assert isinstance(result, ElementaryType)
        return wrap_code(f"({codes[0]} {op} {codes[1]})", result)

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

    def emit(codes: list[str], args: list[Type], result: Type) -> str:
        assert isinstance(result, ElementaryType)
        if op == "*":
            return wrap_code(f"_round({codes[0]} * {codes[1]})", result)
        return wrap_code(f"_round(_fdiv({codes[0]}, {codes[1]}))", result)

    return Builtin(name, ("IN1", "IN2"), typing, emit, min_args=2)


def _printf_typing(args: list[Type]) -> Type | str:
    if not args or not (isinstance(args[0], ElementaryType) and args[0].category == "string"):
        return "needs a format string first"
    return DINT


_FIXED: dict[str, Builtin] = {
    b.name: b
    for b in [
        Builtin("ABS", ("IN",), _abs_typing, _abs_emit),
        *(_math_fn(name) for name in _MATH),
        Builtin("EXPT", ("IN1", "IN2"), _expt_typing, _fn("_pow({0}, {1})"), min_args=2),
        _arith("ADD", "+", True),
        _arith("MUL", "*", True),
        _arith("SUB", "-", False),
        _arith("DIV", "/", False),
        _arith("MOD", "MOD", False),
        Builtin(
            "MOVE", ("IN",), lambda a: a[0] if len(a) == 1 else "takes one argument", _fn("{0}")
        ),
        _shift("SHL"),
        _shift("SHR"),
        _shift("ROL"),
        _shift("ROR"),
        _bitwise("&", "AND"),
        _bitwise("|", "OR"),
        _bitwise("^", "XOR"),
        Builtin("NOT", ("IN",), _not_typing, _not_emit),
        Builtin("SEL", ("G", "IN0", "IN1"), _sel_typing, _fn("({2} if {0} else {1})"), min_args=3),
        Builtin("MUX", None, _mux_typing, lambda c, a, r: f"_mux({', '.join(c)})", min_args=2),
        Builtin("MAX", None, _common, _numeric_result("max", False), min_args=1),
        Builtin("MIN", None, _common, _numeric_result("min", False), min_args=1),
        Builtin(
            "LIMIT", ("MN", "IN", "MX"), _limit_typing, _fn("min(max({1}, {0}), {2})"), min_args=3
        ),
        *(
            Builtin(name, None, _comparable, _compare_chain(op), min_args=2)
            for name, op in (
                ("GT", ">"),
                ("GE", ">="),
                ("EQ", "=="),
                ("LE", "<="),
                ("LT", "<"),
                ("NE", "!="),
            )
        ),
        Builtin("LEN", ("IN",), lambda a: INT, _fn("len({0})")),
        Builtin("LEFT", ("IN", "L"), _string_of, _fn("_left({0}, {1})"), min_args=2),
        Builtin("RIGHT", ("IN", "L"), _string_of, _fn("_right({0}, {1})"), min_args=2),
        Builtin("MID", ("IN", "L", "P"), _string_of, _fn("_mid({0}, {1}, {2})"), min_args=3),
        Builtin("CONCAT", None, _strings, lambda c, a, r: "(" + " + ".join(c) + ")", min_args=1),
        Builtin(
            "INSERT",
            ("IN1", "IN2", "P"),
            _string_of,
            _fn("_insert({0}, {1}, {2})"),
            min_args=3,
        ),
        Builtin("DELETE", ("IN", "L", "P"), _string_of, _fn("_delete({0}, {1}, {2})"), min_args=3),
        Builtin(
            "REPLACE",
            ("IN1", "IN2", "L", "P"),
            _string_of,
            _fn("_replace({0}, {1}, {2}, {3})"),
            min_args=4,
        ),
        Builtin("FIND", ("IN1", "IN2"), lambda a: INT, _fn("_find({0}, {1})"), min_args=2),
        *(
            _time_arith(name, op, result)
            for name, op, result in (
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
        ),
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
        Builtin("PRINTF", None, _printf_typing, lambda c, a, r: f"_printf({', '.join(c)})"),
        Builtin("__CURRENT_TIME", (), lambda a: TIME, _fn("_SYS.now_ns"), min_args=0),
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
