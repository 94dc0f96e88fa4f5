"""Snapshots of generated instances for the context of a warm start (docs/context.md): the
values of every variable below a program instance or the globals as a JSON tree
(`snapshot`), and written back into fresh instances of the same code (`restore`), with a
`ContextMismatch` that names the path where a tree does not fit.

`capture` takes the same tree for the periodic save, with the bulk left for later: an
array of structs that hold values only stays as `Records`, rows of their values, which
`Records.nodes` turns into the tree's nodes on the thread that encodes the file. The cycle
thread then copies values in C-level passes only.
"""

from __future__ import annotations

import struct
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from itertools import chain, compress, repeat
from math import isfinite
from operator import attrgetter
from typing import Any

from runtime.code.intrinsics import Reference

# Node tags. Slot names are identifiers, so no tag can be taken for a field; a dict node is
# told apart by its keys.
IEEE = "ieee"  # {"ieee": "7ff8000000000000"}: NaN or an infinity, by its bits
CLASS, FIELDS = "c", "v"  # {"c": class name, "v": {field: node}}: an instance
_ALIAS = "@"  # {"@": n}: the container met n-th (pre-order), met again

_PLAIN = frozenset({type(None), bool, int, str})
_VALUES = _PLAIN | {float}
_DOUBLE = struct.Struct("<d")
_BITS = struct.Struct("<Q")
_UNSET = object()
# Built-in types are values or containers we do not know how to write back; everything else
# (generated classes, runtime helpers) is a record of named fields.
_NOT_RECORDS = (int, float, str, bytes, bytearray, tuple, list, dict, set, frozenset, type)


class ContextMismatch(ValueError):
    """A tree that does not fit the instance it should be restored into."""

    def __init__(self, reason: str) -> None:
        super().__init__(reason)
        self.reason = reason
        self.path: list[str | int] = []  # filled in while the error unwinds, innermost last

    def __str__(self) -> str:
        where = _render_path(self.path)
        return f"{where}: {self.reason}" if where else self.reason


class UnsupportedValue(TypeError):
    """A value that snapshot cannot encode (nothing generated code stores)."""

    def __init__(self, reason: str) -> None:
        super().__init__(reason)
        self.reason = reason
        self.path: list[str | int] = []

    def __str__(self) -> str:
        where = _render_path(self.path)
        return f"{where}: {self.reason}" if where else self.reason


def _render_path(path: list[str | int]) -> str:
    text = ""
    for key in path:
        text += f"[{key}]" if isinstance(key, int) else (f".{key}" if text else key)
    return text


@dataclass(frozen=True)
class _Plan:
    """How to walk instances of one class: its name and its slots (sorted, so that snapshot
    and restore meet containers in the same order whatever the declaration order)."""

    name: str
    slots: tuple[str, ...]
    has_dict: bool
    # every slot's value at once; AttributeError when one is not set or there is a __dict__
    get_all: Callable[[Any], tuple[Any, ...]]
    slot_set: frozenset[str]

    def fields(self, instance: Any) -> list[tuple[str, Any]]:
        """(name, value) of every field that is set, sorted by name."""
        found = [(n, v) for n in self.slots if (v := getattr(instance, n, _UNSET)) is not _UNSET]
        if self.has_dict:
            found += vars(instance).items()
            found.sort(key=lambda field: field[0])
        return found


# Bounded because every download brings new classes; a plan is cheap to rebuild.
_PLANS: dict[type, _Plan] = {}
_PLANS_MAX = 1024


def _plan(kind: type) -> _Plan | None:
    plan = _PLANS.get(kind)
    if plan is None:
        plan = _new_plan(kind)
        if plan is not None:
            if len(_PLANS) >= _PLANS_MAX:
                _PLANS.clear()
            _PLANS[kind] = plan
    return plan


def _new_plan(kind: type) -> _Plan | None:
    if kind.__module__ == "builtins" or issubclass(kind, _NOT_RECORDS):
        return None
    slots: set[str] = set()
    has_dict = False
    for cls in kind.__mro__[:-1]:  # object itself declares nothing
        declared = cls.__dict__.get("__slots__")
        if declared is None:
            has_dict = True  # a class without __slots__ gives its instances a __dict__
            continue
        for name in (declared,) if isinstance(declared, str) else declared:
            if name in ("__dict__", "__weakref__"):
                has_dict = has_dict or name == "__dict__"
                continue
            if name.startswith("__") and not name.endswith("__"):
                name = f"_{cls.__name__.lstrip('_')}{name}"  # stored under its mangled name
            slots.add(name)
    ordered = tuple(sorted(slots))
    get_all = _no_fast_path if has_dict else _getter(ordered)
    return _Plan(kind.__name__, ordered, has_dict, get_all, frozenset(ordered))


def _getter(slots: tuple[str, ...]) -> Callable[[Any], tuple[Any, ...]]:
    if len(slots) > 1:
        get_all: Callable[[Any], tuple[Any, ...]] = attrgetter(*slots)
        return get_all
    get_one = attrgetter(*slots) if slots else None
    return lambda instance: () if get_one is None else (get_one(instance),)


def _no_fast_path(instance: Any) -> tuple[Any, ...]:
    raise AttributeError("fields in a __dict__ are walked one by one")


# ---- snapshot


@dataclass(frozen=True)
class Deferred:
    """A tree the cycle thread left for the thread that encodes the context: `build` makes
    it from what was copied between two cycles (a memory image's bytes: image_memory.py),
    so the periodic save's share of the cycle thread is that copy."""

    build: Callable[[], Any]


@dataclass(frozen=True)
class Records:
    """An array of records of one class that hold values only, as `capture` took it: the
    rows of their slots' values (tuples: later changes of the instances do not reach them).
    It stands for the list of record nodes `nodes` makes."""

    name: str
    slots: tuple[str, ...]
    rows: list[tuple[Any, ...]]

    def nodes(self, start: int = 0, stop: int | None = None) -> list[dict[str, Any]]:
        """The record nodes of rows[start:stop], as `snapshot` writes them."""
        rows = self.rows[start:stop]
        if not _only_values(chain.from_iterable(rows)):
            rows = [tuple(map(_value_node, row)) for row in rows]
        name, slots = self.name, self.slots
        return [{CLASS: name, FIELDS: dict(zip(slots, row, strict=True))} for row in rows]


def _value_node(value: Any) -> Any:
    kind = type(value)
    if kind is float:
        return value if isfinite(value) else nonfinite_node(value)
    if kind in _PLAIN:
        return value
    raise UnsupportedValue(f"cannot save a value of type {kind.__qualname__}")


def capture(root: Any) -> Any:
    """`snapshot(root)`, except that arrays of value-only records stay `Records`: what the
    cycle thread takes for the periodic save (`context.encode_context` expands them)."""
    return _node(root, {}, True)


def expand(tree: Any) -> Any:
    """The tree `capture` took, as `snapshot` would have written it."""
    if type(tree) is Records:
        return tree.nodes()
    if type(tree) is list:
        return [expand(item) for item in tree]
    if type(tree) is dict:
        return {key: expand(item) for key, item in tree.items()}
    return tree


def snapshot(root: Any) -> Any:
    """A JSON-able tree of every value below `root` (an instance, a list or a value).

    A finite float stays a JSON number: its shortest repr reads back to the same bits
    (-0.0 included) and JSON keeps `1.0` apart from `1`. NaN and the infinities, which JSON
    cannot hold, become `{"ieee": bits}`, so a NaN's sign and payload survive too. A
    container met twice (a VAR_IN_OUT array bound to the caller's array, or a cycle) becomes
    an alias to its first occurrence.
    """
    return _node(root, {}, False)


def nonfinite_node(value: float) -> dict[str, str]:
    return {IEEE: f"{_BITS.unpack(_DOUBLE.pack(value))[0]:016x}"}


def _only_values(values: Iterable[Any]) -> bool:
    """True when `values` are elementary and every float is finite: such a sequence is its
    own tree. Built of C-level passes only, as it runs over whole arrays."""
    values = values if isinstance(values, list | tuple) else list(values)
    kinds = set(map(type, values))
    if kinds <= _PLAIN:
        return True
    if not kinds <= _VALUES:
        return False
    floats = compress(values, map(isinstance, values, repeat(float)))
    return all(map(isfinite, floats))


def _node(value: Any, seen: dict[int, int], defer: bool) -> Any:
    kind = type(value)
    if kind in _PLAIN:
        return value
    if kind is Reference:
        return None  # a warm start begins with every reference NULL (docs/context.md)
    if kind is float:
        return value if isfinite(value) else nonfinite_node(value)
    if id(value) in seen:
        return {_ALIAS: seen[id(value)]}
    plan = None if kind is list else _plan(kind)
    if kind is not list and plan is None:
        raise UnsupportedValue(f"cannot save a value of type {kind.__qualname__}")
    # numbered before the children, so that a cycle refers back to an ancestor
    seen[id(value)] = len(seen)
    if plan is None:
        return _list_node(value, seen, defer)
    return {CLASS: plan.name, FIELDS: _fields_node(value, plan, seen, defer)}


def _fields_node(instance: Any, plan: _Plan, seen: dict[int, int], defer: bool) -> dict[str, Any]:
    pairs: Iterable[tuple[str, Any]]
    try:
        # one C call fetches every slot; most records (timers, structs of numbers) hold
        # values only and are then copied without a Python step per field
        values: tuple[Any, ...] = plan.get_all(instance)
    except AttributeError:  # a slot never set: the general path leaves it out
        pairs = plan.fields(instance)
    else:
        if _only_values(values):
            return dict(zip(plan.slots, values, strict=True))
        pairs = zip(plan.slots, values, strict=True)
    fields: dict[str, Any] = {}
    for name, item in pairs:
        item_kind = type(item)
        if item_kind in _PLAIN:
            fields[name] = item
        elif item_kind is float:
            fields[name] = item if isfinite(item) else nonfinite_node(item)
        else:
            try:
                fields[name] = _node(item, seen, defer)
            except UnsupportedValue as exc:
                exc.path.insert(0, name)
                raise
    return fields


def _list_node(items: list[Any], seen: dict[int, int], defer: bool) -> list[Any] | Records:
    if _only_values(items):
        return items.copy()  # an array of elementary values, the common case
    records = _records_node(items, seen, defer)
    if records is not None:
        return records
    out: list[Any] = []
    append = out.append
    for index, item in enumerate(items):
        item_kind = type(item)
        if item_kind in _PLAIN:
            append(item)
        elif item_kind is float:
            append(item if isfinite(item) else nonfinite_node(item))
        else:
            try:
                append(_node(item, seen, defer))
            except UnsupportedValue as exc:
                exc.path.insert(0, index)
                raise
    return out


def _records_node(
    items: list[Any], seen: dict[int, int], defer: bool
) -> list[Any] | Records | None:
    """An array of structs of one class that hold values only (the bulk of a large
    program's data) in a few C-level passes: its record nodes, or `Records` when `defer`;
    None when the general path must do it."""
    kinds = set(map(type, items))
    plan = _plan(next(iter(kinds))) if len(kinds) == 1 else None
    if plan is None or plan.has_dict:
        return None
    ids = list(map(id, items))
    if not seen.keys().isdisjoint(ids) or len(set(ids)) != len(ids):
        return None  # an element met before: the general path writes the alias
    try:
        rows = list(map(plan.get_all, items))
    except AttributeError:
        return None
    # ST is typed: a slot holds the same kind of value in every element, so the first row
    # tells them all; only a reference slot varies (NULL or not), and None sends the array
    # down the checking path. `Records.nodes` checks every value later.
    if defer and not set(map(type, rows[0])) <= _VALUES - {type(None)}:
        defer = False
    if not defer and not _only_values(chain.from_iterable(rows)):
        return None
    first = len(seen)  # no element holds a container, so pre-order numbers them one by one
    seen.update(zip(ids, range(first, first + len(ids)), strict=True))
    name, slots = plan.name, plan.slots
    if defer:
        return Records(name, slots, rows)
    return [{CLASS: name, FIELDS: dict(zip(slots, row, strict=True))} for row in rows]


# ---- restore


def restore(root: Any, tree: Any) -> None:
    """Write the values of `tree` (from `snapshot`) into `root`, a fresh instance of the same
    code. The whole tree is checked against the instance before the first value is written:
    on ContextMismatch the instance is unchanged. Containers are filled in place, so
    references to them (`_G`, a program registered for `prog();`) stay valid; where the
    tree has an alias, the slot is pointed at the restored container it names."""
    if root is None and tree is None:
        return  # no globals, nothing saved for them
    restorer = _Restorer()
    restorer.check(root, tree)
    for target, name, value in restorer.writes:
        if name is None:
            target[:] = value  # in place: the list object may be aliased
        else:
            setattr(target, name, value)


def _clip(node: Any) -> str:
    text = repr(node)
    return text if len(text) <= 60 else text[:57] + "..."


def _kind_name(node: Any) -> str:
    if isinstance(node, list):
        return f"an array of {len(node)}"
    if isinstance(node, dict) and CLASS in node:
        return f"an instance of {node[CLASS]}"
    if isinstance(node, dict) and _ALIAS in node:
        return "an alias"
    return "a value"


class _Restorer:
    def __init__(self) -> None:
        self.seen: list[Any] = []  # target containers in the order snapshot numbered them
        # (instance, attribute, value), or (list, None, new items): applied after the check
        self.writes: list[tuple[Any, str | None, Any]] = []

    def check(self, target: Any, node: Any) -> None:
        """Check `node` against the container `target`; queue the writes it needs."""
        self.seen.append(target)
        if type(target) is list:
            self._check_list(target, node)
            return
        plan = _plan(type(target))
        if plan is None:
            raise ContextMismatch(f"cannot restore into a {type(target).__qualname__}")
        if not (type(node) is dict and node.keys() == {CLASS, FIELDS}):
            raise ContextMismatch(f"expected an instance of {plan.name}, found {_kind_name(node)}")
        if node[CLASS] != plan.name:
            raise ContextMismatch(f"expected an instance of {plan.name}, found {node[CLASS]}")
        fields = node[FIELDS]
        if type(fields) is not dict:
            raise ContextMismatch(f"the fields of {plan.name} are not an object")
        if self._values_only(target, plan, fields):
            return
        present = plan.fields(target)
        if len(fields) != len(present) or any(name not in fields for name, _ in present):
            missing = sorted({name for name, _ in present} - fields.keys())
            extra = sorted(fields.keys() - {name for name, _ in present})
            raise ContextMismatch(
                f"{plan.name} fields differ: missing {missing or 'none'}, unknown {extra or 'none'}"
            )
        for name, current in present:
            try:
                value = self._child(current, fields[name])
            except ContextMismatch as exc:
                exc.path.insert(0, name)
                raise
            if value is not current:
                self.writes.append((target, name, value))

    def _values_only(self, target: Any, plan: _Plan, fields: dict[str, Any]) -> bool:
        """Queue the writes of a record that holds values only, there and in the tree, in
        C-level passes (the elements of an array of structs); False: check field by field."""
        try:
            values = plan.get_all(target)
        except AttributeError:
            return False
        if fields.keys() != plan.slot_set or not set(map(type, values)) <= _VALUES:
            return False
        saved = list(map(fields.__getitem__, plan.slots))
        if list(map(type, saved)) != list(map(type, values)):
            return False  # NaN or infinity tags, containers, a REAL saved as 1, or a mismatch
        self.writes.extend(zip(repeat(target), plan.slots, saved, strict=False))
        return True

    def _check_list(self, target: list[Any], node: Any) -> None:
        if type(node) is Records:
            node = node.nodes()
        if type(node) is not list or len(node) != len(target):
            raise ContextMismatch(f"expected an array of {len(target)}, found {_kind_name(node)}")
        kinds = list(map(type, target))
        if set(kinds) <= _VALUES and list(map(type, node)) == kinds:
            self.writes.append((target, None, node.copy()))  # an array of elementary values
            return
        items: list[Any] = []
        for index, (current, sub) in enumerate(zip(target, node, strict=True)):
            try:
                items.append(self._child(current, sub))
            except ContextMismatch as exc:
                exc.path.insert(0, index)
                raise
        self.writes.append((target, None, items))

    def _child(self, current: Any, node: Any) -> Any:
        """The value that goes where `current` is: a decoded value, `current` itself once
        checked (a container, filled in place), or the container an alias names."""
        kind = type(node)
        is_ieee = kind is dict and len(node) == 1 and IEEE in node
        if kind in _VALUES or is_ieee:
            if not self._is_value(current):
                raise ContextMismatch(f"expected {self._describe(current)}, found a value")
            return _as_kind_of(current, nonfinite_value(node[IEEE]) if is_ieee else node)
        if kind is dict and len(node) == 1 and _ALIAS in node:
            return self._alias(current, node[_ALIAS])
        if (
            kind is not list
            and kind is not Records
            and not (kind is dict and node.keys() == {CLASS, FIELDS})
        ):
            raise ContextMismatch(f"malformed node {_clip(node)}")
        if self._is_value(current):
            raise ContextMismatch(f"expected a value, found {_kind_name(node)}")
        self.check(current, node)
        return current

    def _alias(self, current: Any, index: Any) -> Any:
        if type(index) is not int or not 0 <= index < len(self.seen):
            raise ContextMismatch(f"alias to an unknown container {index!r}")
        referred = self.seen[index]
        same = type(referred) is type(current) and (
            type(current) is not list or len(current) == len(referred)
        )
        if not same:
            raise ContextMismatch(
                f"alias to {self._describe(referred)} where {self._describe(current)} is"
            )
        return referred

    @staticmethod
    def _is_value(current: Any) -> bool:
        kind = type(current)
        return kind in _PLAIN or kind is float or kind is Reference

    @staticmethod
    def _describe(current: Any) -> str:
        if type(current) is list:
            return f"an array of {len(current)}"
        if _Restorer._is_value(current):
            return "a value"
        return f"an instance of {type(current).__name__}"


_KIND_NAMES = {int: "whole number", float: "number", str: "string"}


def _as_kind_of(current: Any, value: Any) -> Any:
    """`value` as the kind of value its slot holds: generated code relies on it, and the
    native tier checks it on every read (a REAL that held the integer 0 stopped a program).
    A whole number saved for a REAL comes back as a float; any other change of kind is a
    mismatch. (A slot holding None, a NULL reference, takes what was saved; a reference is
    saved as NULL and keeps the initial value it was declared with, `:= REF(x)`.)"""
    have, got = type(current), type(value)
    if have is got or current is None:
        return value
    if have is Reference and value is None:
        return current
    if have is float and got is int:
        try:
            return float(value)
        except OverflowError:
            pass
    kind = "TRUE or FALSE" if have is bool else f"a {_KIND_NAMES.get(have, have.__name__)}"
    raise ContextMismatch(f"expected {kind}, found {_clip(value)}")


def nonfinite_value(bits: Any) -> float:
    try:
        if isinstance(bits, str) and len(bits) == 16:
            value: float = _DOUBLE.unpack(_BITS.pack(int(bits, 16)))[0]
            if not isfinite(value):  # finite values are plain numbers: one encoding each
                return value
    except (ValueError, struct.error):
        pass
    raise ContextMismatch(f"malformed NaN or infinity {_clip(bits)}")
