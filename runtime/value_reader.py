"""Reading many variables at once, fast, for the cycle thread: watch sets and recordings
read thousands of values between two cycles, where a lookup by path per value would cost
more than the cycle."""

from __future__ import annotations

import operator
from collections.abc import Callable
from copy import deepcopy
from typing import Any

from runtime.instances import BoundVariable

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
        cut = max((n + 1 for n, a in enumerate(attrs) if isinstance(a, int)), default=0)
        head, tail = attrs[:cut], attrs[cut:]
        key = (id(bound.program) if bound.program is not None else 0, head)
        group = groups.setdefault(key, (bound.program, head, [], []))
        group[2].append(index)
        group[3].append(".".join(str(a) for a in tail))
    count = len(variables)
    readers = [
        (owner, head, indices, operator.attrgetter(*names) if names != [""] else None)
        for owner, head, indices, names in groups.values()
    ]
    arrays = [i for i, b in enumerate(variables) if b.path.type.upper().startswith("ARRAY")]

    def read() -> list[Any]:
        out: list[Any] = [None] * count
        the_globals = globals_of()
        for owner, head, indices, getter in readers:
            value = owner.instance if owner is not None else the_globals
            for accessor in head:
                value = value[accessor] if isinstance(accessor, int) else getattr(value, accessor)
            if getter is None:  # the element itself: `values[3]`
                out[indices[0]] = value
            elif len(indices) == 1:
                out[indices[0]] = getter(value)
            else:
                for index, got in zip(indices, getter(value), strict=True):
                    out[index] = got
        for index in arrays:
            out[index] = deepcopy(out[index])
        return out

    return read
