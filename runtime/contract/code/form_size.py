"""How much memory the typed forms of an artifact make a runtime allocate, checked before
anything is allocated.

Each count of a form is bounded on its own (form_json.MAX_COUNT), but counts multiply: an
array of a million arrays of a million values is two counts within bounds, and a runtime
that set it up would allocate 10**12 list cells and be killed for memory. The compiler
never makes such a form (backend/compiler/checks/data.py bounds the data of a resource);
an artifact from outside may. So the runtime counts, from the forms alone, the cells every
expression allocates (an item of a list, a slot of an instance) and every instance a
resource sets up, and refuses the artifact beyond MAX_CELLS.

A count is linear in the sizes of the classes an expression instantiates (`POU_TON()` is
as many cells as a TON's slots make), so each unit is summed up as it is decoded
(`unit_cells`), and the classes are resolved together once every unit is known
(`check_cells`), without keeping the units' nodes.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, fields

from runtime.contract.code.form_json import FormRefused
from runtime.contract.code.statements import Elif, Stmt
from runtime.contract.code.typed_form import (
    Binary,
    Call,
    Const,
    Expr,
    Named,
    Repeated,
    Sequence,
    Slice,
    This,
    Var,
)
from runtime.contract.code.units import Alias, Class, Function, Inherited, Unit

# The cells one expression, or one resource's instances, may allocate. The compiler's own
# limit is a million values of data a resource (backend/compiler/limits.py
# MAX_DATA_VALUES); a value is a cell or a few (a block's internal slots, the lists around
# an array's values), and a resource instantiates each PROGRAM and the globals up to twice
# (a user program and the POU's own instance; the globals and each program's view of
# them). Eight times the compiler's limit takes all of that, and stays a few hundred MiB.
MAX_CELLS = 8_000_000
# the names the compiler gives the classes whose instances a call makes (`POU_TON()`)
_CLASS_CALL = re.compile(r"(?:POU|STRUCT)_[A-Za-z0-9_]+\Z|GLOBALS\Z")
_OWN = ""  # the key of a Cells for the cells an expression allocates itself

# cells an expression allocates (key ""), and instances it makes of each class (by name)
Cells = dict[str, int]


@dataclass(frozen=True)
class UnitCells:
    """What a unit allocates: an instance of a class (None for a FUNCTION), and each
    expression of its code (parameters' defaults, bodies) that allocates anything."""

    name: str
    instance: Cells | None
    # each expression of its code that allocates anything, each distinct one once
    expressions: tuple[tuple[tuple[str, int], ...], ...]


def unit_cells(unit: Unit) -> UnitCells:
    """The cells of one decoded unit; FormRefused where a part alone is beyond MAX_CELLS."""
    path = f"{type(unit).__name__} {unit.name}"
    match unit:
        case Class(slots=slots, functions=functions):
            initials = [_expression(slot.initial, path) for slot in slots]
            instance = _within(_total([{_OWN: len(slots) + 1}, *initials]), path)
            code = [f for f in functions if not isinstance(f, Inherited)]
            expressions = _distinct(_function_cells(f, path) for f in code)
            return UnitCells(unit.name, instance, expressions)
        case Function():
            return UnitCells(unit.name, None, _distinct([_function_cells(unit, path)]))
        case Alias():
            return UnitCells(unit.name, {_OWN: 1}, ())
    raise AssertionError(f"no unit {unit!r}")


def check_cells(units: Iterable[UnitCells], instantiated: Mapping[str, int]) -> None:
    """FormRefused unless every instance, every expression and the whole resource (the
    classes `instantiated`, by name, that many times each) are within MAX_CELLS."""
    by_name = {unit.name: unit for unit in units}
    sizes = _class_sizes(by_name)
    for unit in by_name.values():
        for expression in unit.expressions:
            cells = _resolved(dict(expression), sizes)
            if cells > MAX_CELLS:
                raise FormRefused(f"{unit.name}: an expression makes {cells:,} cells; {_AT_MOST}")
    total = sum(sizes.get(name, 0) * times for name, times in instantiated.items())
    if total > MAX_CELLS:
        raise FormRefused(f"the resource's instances make {total:,} cells; {_AT_MOST}")


_AT_MOST = f"at most {MAX_CELLS:,}"


def _class_sizes(units: Mapping[str, UnitCells]) -> dict[str, int]:
    """The cells of an instance of each class, from the sizes of the classes its slots
    instantiate (anything else a call names makes no instance: 0). A class that holds an
    instance of itself would instantiate without end. Depth first without recursion: an
    artifact may chain as many classes as it has units."""
    sizes: dict[str, int] = {}
    for root in sorted(units):
        stack, entered = [root], set()  # entered and not sized: the classes holding this one
        while stack:
            name = stack[-1]
            unit = units.get(name)
            if name in sizes or unit is None or unit.instance is None:
                sizes.setdefault(name, 0)
                stack.pop()
                continue
            inner = [n for n in unit.instance if n != _OWN and n not in sizes]
            if name not in entered:
                entered.add(name)
                if held := entered.intersection(inner):
                    raise FormRefused(
                        f"{min(held)}: an instance holds an instance of its own class"
                    )
                stack.extend(inner)
                continue
            size = _resolved(unit.instance, sizes)
            if size > MAX_CELLS:
                raise FormRefused(f"{name}: an instance makes {size:,} cells; {_AT_MOST}")
            sizes[name] = size
            entered.discard(name)
            stack.pop()
    return sizes


def _resolved(cells: Cells, sizes: Mapping[str, int]) -> int:
    return sum(times * (1 if name == _OWN else sizes.get(name, 0)) for name, times in cells.items())


def _function_cells(function: Function, path: str) -> Iterable[Cells]:
    for param in function.params:
        yield _expression(param.default, path)
    yield from _statements_cells(function.body, path)


def _statements_cells(statements: Iterable[Stmt | Elif], path: str) -> Iterable[Cells]:
    """The cells of each expression in the statements: each is made anew each time it is
    evaluated, and what it made is let go (or kept in a slot it replaces), so the largest
    one is what the code needs at once."""
    for statement in statements:
        for name in _FIELDS[type(statement)]:
            value = getattr(statement, name)
            if isinstance(value, tuple):
                yield from _statements_cells(value, path)
            elif value is not None and not isinstance(value, int | str):
                yield _expression(value, path)


def _expression(node: Expr, path: str) -> Cells:
    """The cells `node` allocates, refused at once beyond MAX_CELLS (every class makes at
    least one cell, so instances count at least that) before counts multiply further.
    Most nodes allocate nothing: they share one empty count, which nothing changes."""
    kind = type(node)
    if kind in _LEAVES:
        return _NOTHING
    if kind is Repeated:
        assert isinstance(node, Repeated)
        cells = _times(_expression(node.item, path), node.count if node.each_new else 1)
        cells[_OWN] = cells.get(_OWN, 0) + node.count
    elif kind is Sequence:
        assert isinstance(node, Sequence)
        cells = _total([{_OWN: len(node.items)}, *(_expression(i, path) for i in node.items)])
    elif kind is Binary:
        assert isinstance(node, Binary)
        if node.op == "*" and (_is_container(node.left) or _is_container(node.right)):
            # the compiler repeats a list as a Repeated, never by `*`, which would repeat
            # it (or a text) by a number the form's counts do not bound
            raise FormRefused(f"{path}: a list or text repeated by `*`")
        # `initials + [0] * n` (the rest of an array): the operands, and the new list made
        # of their cells (the instances in them are not made again)
        cells = _copied(_total([_expression(node.left, path), _expression(node.right, path)]))
    elif kind is Slice:  # `whole[n:]`: the whole, and the new list of its tail
        assert isinstance(node, Slice)
        cells = _copied(_expression(node.value, path))
    else:
        cells = _total([_expression(child, path) for child in _children(node)])
        if kind is Call:
            assert isinstance(node, Call)
            if isinstance(node.callee, str) and _CLASS_CALL.match(node.callee):
                cells = {**cells, node.callee: cells.get(node.callee, 0) + 1}
    return _within(cells, path) if cells else _NOTHING


# the nodes that allocate nothing and hold no node that does
_LEAVES = frozenset({Const, Var, This, Named})
_NOTHING: Cells = {}


def _within(cells: Cells, path: str) -> Cells:
    if (made := sum(cells.values())) > MAX_CELLS:
        raise FormRefused(f"{path}: an expression makes {made:,} cells or more; {_AT_MOST}")
    return cells


def _is_container(node: Expr) -> bool:
    return isinstance(node, Sequence | Repeated | Slice) or (
        isinstance(node, Const) and isinstance(node.value, str)
    )


def _children(node: Expr) -> Iterable[Expr]:
    for name in _FIELDS[type(node)]:
        value = getattr(node, name)
        if isinstance(value, tuple):
            for item in value:
                # a keyword or a member is a (name, value) pair
                yield item[1] if isinstance(item, tuple) else item
        elif not isinstance(value, str | int | float | bool) and value is not None:
            yield value


def _total(parts: list[Cells]) -> Cells:
    """The sum of counts, a new one (or the shared empty one where all are empty)."""
    total: Cells = {}
    for part in parts:
        for name, times in part.items():
            total[name] = total.get(name, 0) + times
    return total if total else _NOTHING


def _copied(cells: Cells) -> Cells:
    return {**cells, _OWN: 2 * cells[_OWN]} if cells.get(_OWN) else cells


def _times(cells: Cells, factor: int) -> Cells:
    return {name: times * factor for name, times in cells.items()}


def _distinct(
    functions: Iterable[Iterable[Cells]],
) -> tuple[tuple[tuple[str, int], ...], ...]:
    """The expressions that allocate anything, each distinct count once: which is the
    largest depends on the sizes of the classes, known only once every unit is."""
    found = {tuple(sorted(c.items())) for cells in functions for c in cells if c}
    return tuple(sorted(found))


class _Fields(dict[type, tuple[str, ...]]):
    """The field names of each kind of node, looked up once."""

    def __missing__(self, cls: type) -> tuple[str, ...]:
        names = self[cls] = tuple(f.name for f in fields(cls))
        return names


_FIELDS = _Fields()
