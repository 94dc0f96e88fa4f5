"""A unit of the typed form (units.py) as JSON: the form an artifact carries its code in.

Each node is an array, its class's name first and then its fields in the order the class
declares them (`["Binary","+",left,right,"INT"]`); a tuple is an array (a pair, such as a
keyword of a call, an array of two); a constant's infinite or NaN float, which JSON cannot
spell, is `["float","inf"]` (`"-inf"`, `"nan"`). `encode_unit` writes it canonically, so
that the same unit is always the same text (and the same CRC).

A form is data: the runtime decodes it and prints the Python itself (python_text.py);
nothing of an artifact is executed as it came. An artifact comes from outside, so
`decode_unit` takes only exactly what the compiler could have built: every node where its
position allows its kind, every field of its type (no Boolean for an integer nor the
reverse), and beyond the types, every string the printer writes into the program as it
is a plain identifier (no text can slip a line or a statement in), and every number and
size within limits a resource can run. Anything else is a `FormRefused` naming the form
and where in it. What the names are (which globals code may use, which attributes) is
checked on the decoded unit, with the rest of what code may contain (form_check.py).
"""

from __future__ import annotations

import functools
import json
import keyword
import math
import re
import types
from collections.abc import Callable, Mapping
from dataclasses import dataclass, fields, is_dataclass
from typing import Any, Literal, Union, get_args, get_origin, get_type_hints

from runtime.contract.code.units import Function, Unit
from runtime.contract.outside_json import MIB, JsonRefused, read_json

# as large as the artifact itself may be
MAX_FORM_BYTES = 64 * MIB
# The deepest nesting of JSON a form may have. A runtime keeps Python's recursion limit of
# 1,000 and decodes and prints in threads of its own. The decoder takes one Python frame per
# level of JSON (json.loads itself gives up near 990 levels); printing takes up to two (a
# Wrap, or an Index offset, in another: python_text -> _wrap_text / _bare -> python_text), and
# so does the check (a member's base, a call's arguments: form_check.py; 700 frames at 350).
# Measured in a fresh thread: a nest of Wraps or Indexes decodes and prints up to 499
# levels of JSON, a Chain's up to 664, anything else up to json.loads' limit. 350 leaves
# some 300 frames to whatever calls the decoder and the printer.
FORM_DEPTH = 350
# items of a tuple (an array's values, the arguments of a call) and a Repeated's count: an
# array has at most a million values (backend/compiler/limits.py), and a larger count
# would have the runtime allocate without bound
MAX_COUNT = 1_000_000
MAX_TYPE = 1_000  # characters of a type's text (data, never printed)
MAX_NAME = 1_000  # characters of a name: an identifier, a member's or a kind's (repr'd)
MAX_STRING = 65_535  # characters of a text constant (the compiler's MAX_STRING_LITERAL)
MAX_CONST_BITS = 128  # magnitude of an integer constant (LINT, ULINT and sums of them)
MAX_OFFSET_BITS = 64  # magnitude of a Wrap's offset
MAX_LINE = 10**9  # an ST line (0: none)
# what the printer writes into the program as it is: a plain ASCII identifier
IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
NON_FINITE = ("inf", "-inf", "nan")


class FormRefused(ValueError):
    """A typed form from outside that is not a unit the compiler could have built; or a
    unit too deeply nested to encode as one."""


def encode_unit(unit: Unit) -> str:
    """`unit` as its canonical JSON text; FormRefused if it would be nested deeper than
    FORM_DEPTH (no runtime would read it)."""
    try:
        data = _plain(unit, 1)
    except _Refusal as refusal:
        raise FormRefused(f"{unit.name}: the typed form {refusal.reason}") from None
    return json.dumps(
        data, separators=(",", ":"), sort_keys=True, ensure_ascii=True, allow_nan=False
    )


def _plain(value: Any, level: int) -> Any:
    """`value` as JSON data, an array of it at `level` of nesting. One frame a level, as in
    decoding: a form FORM_DEPTH deep must encode within the recursion limit."""
    if isinstance(value, float) and not math.isfinite(value):
        value = ("float", str(value))  # "inf", "-inf", "nan"
    if is_dataclass(value):
        items = [getattr(value, f.name) for f in fields(value)]
        plain: list[Any] = [type(value).__name__]
    elif isinstance(value, tuple):
        items, plain = list(value), []
    else:
        return value
    if level > FORM_DEPTH:
        raise _Refusal(f"is nested deeper than {FORM_DEPTH}")
    for item in items:
        plain.append(_plain(item, level + 1))
    return plain


def decode_unit(text: str | bytes, what: str) -> Unit:
    """The unit `text` encodes (`encode_unit`); FormRefused naming `what` (a unit of an
    artifact) and where in the form otherwise."""
    if not isinstance(text, str | bytes):  # an artifact's field, as its JSON had it
        raise FormRefused(f"{what} is {_shown(text)}, not a text")
    try:  # the decoder counts the depth as it goes, cheaper than a walk of its own
        data = read_json(text, what, MAX_FORM_BYTES, max_depth=None)
    except JsonRefused as exc:
        raise FormRefused(str(exc)) from None
    try:
        unit: Unit = _value(data, _UNIT, 1)
    except _Refusal as refusal:
        # the path from the top node's name down, e.g. Class.functions[1].body[3].value
        root = data[0] if refusal.where else "the form"
        where = root + "".join(reversed(refusal.where))
        raise FormRefused(f"{what}: {where} {refusal.reason}") from None
    return unit


class _Refusal(Exception):
    """What is wrong, and where: the steps to it from the top, innermost first (each level
    adds its own as the refusal passes it, so that no path is built unless one is)."""

    def __init__(self, reason: str) -> None:
        super().__init__(reason)
        self.reason = reason
        self.where: list[str] = []


@dataclass(frozen=True, slots=True)
class _Spec:
    """What may stand at one position of a form: JSON scalars of `scalars` (`check` says
    what is wrong with one, or None), values of `literals`, nodes of `tags`, a tuple of
    `items` (at least `least` of them), a fixed tuple of `pair`; or what `special` takes."""

    what: str
    scalars: frozenset[type] = frozenset()
    check: Callable[[Any], str | None] | None = None
    literals: frozenset[str] | None = None
    tags: Mapping[str, type] | None = None
    items: _Spec | None = None
    least: int = 0
    pair: tuple[_Spec, ...] | None = None
    special: Callable[[Any], Any] | None = None


def _value(data: Any, spec: _Spec, level: int) -> Any:
    """`data`, at `level` of the form's JSON, decoded as `spec` says. One function for
    nodes and tuples alike, calling itself once per level of JSON: a form FORM_DEPTH deep
    must decode within the recursion limit."""
    kind = type(data)
    if kind in spec.scalars:  # most values are: checked first
        if spec.check is not None and (kind is str or kind is int):
            reason = spec.check(data)
            if reason is not None:
                raise _Refusal(reason)
        return data
    if kind is str and spec.literals is not None and data in spec.literals:
        return data
    if spec.special is not None:
        return spec.special(data)
    if kind is list and level > FORM_DEPTH:
        raise _Refusal(f"is nested deeper than {FORM_DEPTH}")
    if kind is list and spec.tags is not None:
        cls, field_specs = _node_class(data, spec)
        values = []
        for (name, field_spec), item in zip(field_specs, data[1:], strict=True):
            try:
                values.append(_value(item, field_spec, level + 1))
            except _Refusal as refusal:
                refusal.where.append(f".{name}")
                raise
        node = cls(*values)
        check = _NODE_CHECKS.get(cls)
        if check is not None:
            check(node)
        return node
    if kind is list and (spec.items is not None or spec.pair is not None):
        decoded = []
        for index, (item, item_spec) in enumerate(_parts(data, spec)):
            try:
                decoded.append(_value(item, item_spec, level + 1))
            except _Refusal as refusal:
                refusal.where.append(f"[{index}]")
                raise
        return tuple(decoded)
    raise _Refusal(f"is {_shown(data)}, not {spec.what}")


def _node_class(data: list[Any], spec: _Spec) -> tuple[type, tuple[tuple[str, _Spec], ...]]:
    """The class of the node `data` is, where `spec` allows it, with its fields' specs."""
    assert spec.tags is not None
    tag = data[0] if data else None
    cls = spec.tags.get(tag) if type(tag) is str else None
    if cls is None:
        raise _Refusal(f"is {_shown(data)}, not {spec.what}")
    field_specs = _fields(cls)
    if len(data) != len(field_specs) + 1:
        count = len(field_specs)
        raise _Refusal(f"is a {tag} of {len(data) - 1} fields; a {tag} has {count}")
    return cls, field_specs


def _parts(data: list[Any], spec: _Spec) -> list[tuple[Any, _Spec]]:
    """The items of the tuple `data`, each with its spec."""
    if spec.pair is not None:
        if len(data) != len(spec.pair):
            raise _Refusal(f"has {len(data)} items, not {len(spec.pair)}")
        return list(zip(data, spec.pair, strict=True))
    assert spec.items is not None
    if not spec.least <= len(data) <= MAX_COUNT:
        raise _Refusal(f"has {len(data):,} items, not {spec.least} to {MAX_COUNT:,}")
    return [(item, spec.items) for item in data]


def _shown(data: Any) -> str:
    """`data` as a message shows it: a node by its tag, anything else by its type and (when
    short) its value."""
    if type(data) is list:
        tag = data[0] if data and type(data[0]) is str else None
        return f"a {tag[:40]!r} node" if tag is not None else "an array"
    if type(data) is dict:
        return "an object"
    shown = repr(data)
    return f"{type(data).__name__} {shown if len(shown) <= 40 else shown[:37] + '...'}"


# --- checks beyond the types, each saying what is wrong or None ---


def _identifier(value: str) -> str | None:
    if len(value) <= MAX_NAME and IDENTIFIER.fullmatch(value) and not keyword.iskeyword(value):
        return None
    return f"is {_shown(value)}, not an identifier (ASCII, no keyword)"


def _dotted(value: str) -> str | None:
    """A name of the generated code, or of an attribute of one (`_math.sin`)."""
    if len(value) <= MAX_NAME and all(_identifier(part) is None for part in value.split(".")):
        return None
    return f"is {_shown(value)}, not a dotted name of identifiers"


def _shown_name(value: str) -> str | None:
    """A name the printer writes with repr: any text, of a bounded length."""
    return None if len(value) <= MAX_NAME else f"is longer than {MAX_NAME:,} characters"


def _type_text(value: str) -> str | None:
    return None if len(value) <= MAX_TYPE else f"is longer than {MAX_TYPE:,} characters"


def _within(low: int, high: int) -> Callable[[int], str | None]:
    def check(value: int) -> str | None:
        return None if low <= value <= high else f"is {value}, not {low:,} to {high:,}"

    return check


def _bits_at_most(bits: int) -> Callable[[int], str | None]:
    def check(value: int) -> str | None:
        return None if abs(value).bit_length() <= bits else f"has more than {bits} bits"

    return check


def _const_value(data: Any) -> bool | int | float | str | None:
    """A constant: a JSON scalar within limits, or a non-finite float spelled as an array."""
    if type(data) is list and len(data) == 2 and data[0] == "float" and data[1] in NON_FINITE:
        return float(data[1])
    reason = None
    if type(data) is int:
        reason = _bits_at_most(MAX_CONST_BITS)(data)
    elif type(data) is str and len(data) > MAX_STRING:
        reason = f"is longer than {MAX_STRING:,} characters"
    elif type(data) is float and not math.isfinite(data):  # NaN, Infinity, 1e999 in JSON
        reason = 'is a non-finite float not written as ["float", "inf"]'
    elif type(data) not in (bool, int, float, str, type(None)):
        reason = f"is {_shown(data)}, not a constant"
    if reason is not None:
        raise _Refusal(reason)
    return data  # type: ignore[no-any-return]


# The checks of every str and int field, by class and field (a field's check applies to
# each str or int in it: the names in Call.keywords, the kinds of a Class). Every str and
# int field must have one (`_spec` asserts it), so that a new field is decided on; a field
# named `type` is a type's text, one named `line` an ST line (`_field_spec`).
_CHECKS: dict[tuple[str, str], Callable[[Any], str | None]] = {
    ("Var", "name"): _identifier,
    ("Member", "name"): _identifier,
    ("Assigned", "name"): _identifier,
    ("ForEach", "name"): _identifier,
    ("Call", "callee"): _identifier,
    ("Call", "keywords"): _identifier,
    ("Param", "name"): _identifier,
    ("Function", "name"): _identifier,
    ("Slot", "name"): _identifier,
    ("Class", "name"): _identifier,
    ("Inherited", "name"): _identifier,
    ("Inherited", "owner"): _identifier,
    ("Alias", "name"): _identifier,
    ("Alias", "target"): _identifier,
    ("Named", "name"): _dotted,
    ("Members", "items"): _shown_name,
    ("Class", "kinds"): _shown_name,
    ("Slice", "start"): _within(0, MAX_COUNT),
    ("Slice", "stop"): _within(0, MAX_COUNT),
    ("Repeated", "count"): _within(0, MAX_COUNT),
    ("Wrap", "bits"): _within(1, 64),
    ("Wrap", "offset"): _bits_at_most(MAX_OFFSET_BITS),
}
_LINE = _within(0, MAX_LINE - 1)
# Fields whose value the class's hint does not describe as JSON: decoded by a function
_SPECIAL: dict[tuple[str, str], Callable[[Any], Any]] = {("Const", "value"): _const_value}
# Blocks Python needs a statement in (the printer prints none for an empty one)
_NOT_EMPTY = {
    ("Function", "body"),
    ("If", "body"),
    ("Elif", "body"),
    ("While", "body"),
    ("ForEach", "body"),
}


def _method_params(function: Function) -> None:
    """A method's instance is `s`, so none of its parameters may be."""
    if function.method and any(param.name == "s" for param in function.params):
        raise _Refusal("is a method with a parameter named 's', the name of its instance")


# What a node must be beyond its fields, by class
_NODE_CHECKS: dict[type, Callable[[Any], None]] = {Function: _method_params}


@functools.cache
def _fields(cls: type) -> tuple[tuple[str, _Spec], ...]:
    """The fields of a node class, each with what may stand in it (built once a class)."""
    hints = get_type_hints(cls)
    return tuple((f.name, _field_spec(cls.__name__, f.name, hints[f.name])) for f in fields(cls))


def _field_spec(owner: str, name: str, hint: Any) -> _Spec:
    special = _SPECIAL.get((owner, name))
    if special is not None:
        return _Spec("a constant", special=special)
    check = _CHECKS.get((owner, name))
    if name in ("type", "line"):  # the fields every node (statement) has
        check = _type_text if name == "type" else _LINE
    spec = _spec(hint, check, f"{owner}.{name}")
    if (owner, name) in _NOT_EMPTY:
        return _Spec(spec.what, items=spec.items, least=1)
    return spec


def _spec(hint: Any, check: Callable[[Any], str | None] | None, field: str) -> _Spec:
    """What the type `hint` allows, `check` applying to its str and int values."""
    origin = get_origin(hint)
    members = get_args(hint) if origin in (Union, types.UnionType) else (hint,)
    scalars: set[type] = set()
    literals: set[str] = set()
    tags: dict[str, type] = {}
    items = None
    pair = None
    for member in members:
        if member in (bool, int, float, str, type(None)):
            assert member in (bool, type(None)) or check is not None, f"{field} is unchecked"
            scalars.add(member)
        elif get_origin(member) is Literal:
            literals.update(get_args(member))
        elif is_dataclass(member) and isinstance(member, type):
            tags[member.__name__] = member
        elif get_origin(member) is tuple and get_args(member)[1:] == (Ellipsis,):
            items = _spec(get_args(member)[0], check, field)
        elif get_origin(member) is tuple:
            pair = tuple(_spec(part, check, field) for part in get_args(member))
        else:
            raise AssertionError(f"{field}: no JSON for {member!r}")
    allowed = sorted(_JSON_NAMES[t] for t in scalars) + [repr(v) for v in sorted(literals)]
    allowed += sorted(tags) + (["an array"] if items or pair else [])
    return _Spec(
        what=allowed[0] if len(allowed) == 1 else f"one of {', '.join(allowed)}",
        scalars=frozenset(scalars),
        check=check,
        literals=frozenset(literals) if literals else None,
        tags=tags or None,
        items=items,
        pair=pair,
    )


_JSON_NAMES = {bool: "a bool", int: "an int", float: "a float", str: "a str", type(None): "null"}
# what the top of a form may be: a Class, a Function or an Alias
_UNIT = _spec(Unit, None, "unit")
