"""Reading many variables at once, fast, for the cycle thread: watch sets and recordings
read thousands of values between two cycles, where a lookup by path per value would cost
more than the cycle."""

from __future__ import annotations

import operator
from collections.abc import Callable
from copy import deepcopy
from typing import Any, cast

from runtime.code.instances import BoundVariable

Accessor = str | int
_Group = tuple[Any, tuple[Accessor, ...], list[int], list[str]]


def value_reader(
    variables: list[BoundVariable], globals_of: Callable[[], Any]
) -> Callable[[], list[Any]]:
    """A function that reads the variables' values now, fast. Variables are grouped by
    their owner (a program instance, or the globals) and by the path down to their last
    list index (`points[3]` of `points[3].x`); below that, one `attrgetter` (in C) reads all
    the members of a group at once. Arrays are copied: the programs go on changing them."""
    groups: dict[tuple[int, tuple[Accessor, ...]], _Group] = {}
    for index, bound in enumerate(variables):
        attrs = bound.path.attrs
        cut = len(attrs)  # after the last list index (a plain loop: most paths have none)
        while cut and type(attrs[cut - 1]) is not int:
            cut -= 1
        head = attrs[:cut]
        key = (id(bound.program) if bound.program is not None else 0, head)
        group = groups.setdefault(key, (bound.program, head, [], []))
        group[2].append(index)
        group[3].append(".".join(cast(tuple[str, ...], attrs[cut:])))  # names only
    readers = [
        (owner, head, operator.attrgetter(*names) if names != [""] else None, len(indices) == 1)
        for owner, head, indices, names in groups.values()
    ]
    # where each variable's value is in what the readers give one after the other: one
    # `itemgetter` puts them in order (a loop in Python would cost as much as the reading)
    read_order = [i for _, _, indices, _ in groups.values() for i in indices]
    position = {index: n for n, index in enumerate(read_order)}
    reorder = (
        None
        if read_order == list(range(len(variables))) or len(variables) < 2
        else operator.itemgetter(*(position[i] for i in range(len(variables))))
    )
    arrays = [i for i, b in enumerate(variables) if b.path.type.upper().startswith("ARRAY")]

    def read() -> list[Any]:
        got: list[Any] = []
        the_globals = globals_of()
        for owner, head, getter, single in readers:
            value = owner.instance if owner is not None else the_globals
            for accessor in head:
                value = value[accessor] if isinstance(accessor, int) else getattr(value, accessor)
            if getter is None:  # the element itself: `values[3]`
                got.append(value)
            elif single:
                got.append(getter(value))
            else:
                got.extend(getter(value))
        out = got if reorder is None else list(reorder(got))
        for index in arrays:
            out[index] = deepcopy(out[index])
        return out

    return read
