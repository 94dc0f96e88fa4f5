"""Typed-form nodes (runtime/contract/code/typed_form.py) that bring a value into a type:
an integer wrapped to its width, a value converted between types (X_TO_Y semantics)."""

from __future__ import annotations

from backend.compiler.types import ElementaryType, Type, artifact_type_text, integer_like
from runtime.contract.code.names import BUILTINS, CALLED_INTRINSICS
from runtime.contract.code.typed_form import Binary, Call, Choice, Const, Expr, Wrap

NS_PER_DAY = 86_400_000_000_000


def intrinsic(callee: str, result: Type | str, *args: Expr) -> Call:
    """A call of an intrinsic (an entry of runtime/contract/intrinsic_table.py) or of a
    conversion Python has, by position."""
    assert callee in CALLED_INTRINSICS or callee in BUILTINS, f"{callee} is no intrinsic"
    return Call(callee, args, result if isinstance(result, str) else artifact_type_text(result))


def wrapped(value: Expr, t: ElementaryType, offset: int = 0) -> Expr:
    """An integer expression, plus `offset`, brought into the range of its type (two's
    complement; a time of day wraps around midnight)."""
    name = artifact_type_text(t)
    if t.name in ("TOD", "LTOD"):
        if offset:
            value = Binary("+", value, Const(offset, name), name)
        return Binary("%", value, Const(NS_PER_DAY, name), name)
    if t.is_any_literal or not (t.is_integer or t.category in ("time", "date")):
        return Binary("+", value, Const(offset, name), name) if offset else value
    return Wrap(value, t.bits, t.signed, offset, name)


def wrap_constant(value: int, t: ElementaryType) -> int:
    """A literal's value as stored in `t` (16#FFFF in an INT is -1)."""
    if not (t.is_integer or t.category in ("time", "date")):
        return value
    value &= (1 << t.bits) - 1
    if t.signed and value >= 1 << (t.bits - 1):
        value -= 1 << t.bits
    return value


def literal_in(value: Expr, t: ElementaryType) -> Expr:
    """An integer expression of literals in type `t`: a constant as stored in `t`,
    anything else wrapped to it (`-79 MOD 100`; `LWORD_TO_DWORD(16#FFFF_FFFF_FFFF_FFFF)`
    is 16#FFFF_FFFF, as the literal taken as an LWORD and converted)."""
    if isinstance(value, Const) and type(value.value) is int:
        if t.min <= value.value <= t.max:
            return value
        return Const(wrap_constant(value.value, t), artifact_type_text(t))
    return wrapped(value, t)


def converted(value: Expr, source: Type, target: ElementaryType) -> Expr:
    """`value` of type `source` converted to `target` (X_TO_Y semantics)."""
    src = integer_like(source) or source
    if not isinstance(src, ElementaryType):
        return value
    cat, tcat, name = src.category, target.category, artifact_type_text(target)
    if tcat == "bool":
        if cat == "string":
            return intrinsic("_str_to_bool", name, value)
        return Binary("!=", value, Const(0, "DINT"), name) if cat != "bool" else value
    if tcat in ("int", "bits"):
        if cat == "real":
            return wrapped(intrinsic("_round", name, value), target)
        if cat == "string" and src.name in ("CHAR", "WCHAR"):
            return intrinsic("_ord", name, value)
        if cat == "string":
            number = intrinsic("_str_to_int", "LINT", value)
            if not target.signed:  # a negative text does not convert to an unsigned type
                number = intrinsic("max", "LINT", number, Const(0, "LINT"))
            return wrapped(number, target)
        if cat == "bool":
            return intrinsic("int", name, value)
        if src.is_any_literal:
            return literal_in(value, target)
        if src.is_integer and (src.bits < target.bits and (target.signed or not src.signed)):
            return value
        return wrapped(value, target)
    if tcat == "real":
        if cat == "string":
            return intrinsic("_str_to_real", name, value)
        if target.bits == 32 and not (cat == "real" and src.bits == 32):
            return intrinsic("_f32", name, value)
        return intrinsic("float", name, value)
    if tcat == "string":
        if cat == "real":
            return intrinsic("_real_to_str", name, value)
        if cat == "bool":
            return Choice(value, Const("TRUE", name), Const("FALSE", name), name)
        if cat == "time":
            prefix = "LTIME#" if src.name == "LTIME" else "T#"
            return intrinsic("_time_to_str", name, value, Const(prefix, "STRING"))
        if cat == "date":
            return intrinsic("_date_to_str", name, value, Const(src.name, "STRING"))
        if cat == "string":
            if src.name.startswith("W") and not target.name.startswith("W"):
                return intrinsic("_w2s", name, value)
            if target.name.startswith("W") and not src.name.startswith("W"):
                return intrinsic("_s2w", name, value)
            return value
        return intrinsic("str", name, value)
    if tcat in ("time", "date"):
        if cat == "string":  # a literal of any length: wrapped as every store is
            return wrapped(intrinsic("_str_to_time", name, value), target)
        million = Const(1_000_000, "LINT")
        if cat == "real":  # REAL ms -> ns
            return wrapped(intrinsic("_round", name, Binary("*", value, million, "LREAL")), target)
        if cat in ("int", "bits"):  # integers count milliseconds
            return wrapped(Binary("*", value, million, name), target)
        return value
    return value
