"""Where the values of a loaded configuration live, and the one way services reach them
(docs/native-code.md, "Who reaches a value, and how"). `Memory` reads and writes variables
by their `BoundVariable` and takes and restores them all for the context; values are the
contract's representations (bool, int, float, str, lists for arrays). `ObjectMemory` keeps
them in the generated slot objects, as both tiers run today."""

from __future__ import annotations

import copy
import functools
import operator
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Protocol, cast

from runtime.code.code_image import Accessor
from runtime.code.instances import BoundVariable
from runtime.code.user_program import UserProgram, share_globals
from runtime.context_snapshot import capture, restore, snapshot


@dataclass(frozen=True)
class ValueTrees:
    """Every value of a configuration as `context_snapshot` trees: what a context holds."""

    globals: Any  # the globals' tree; None: the configuration has no globals
    programs: dict[str, Any]  # each user program's tree, by program name


class Memory(Protocol):
    """The values of one loaded configuration, reached by `BoundVariable`: whatever holds
    them (objects, or a native image later), services read and write them only this way.
    Values are read and written between two cycles, on the cycle thread; a reader may be
    made on any thread (it reads no value while it is made)."""

    def reader(self, bounds: list[BoundVariable]) -> Callable[[], list[Any]]:
        """A function that reads the variables' values now, in their order (between two
        cycles); made once, then called as often as needed."""
        ...

    def read(self, bound: BoundVariable) -> Any:
        """One variable's value now."""
        ...

    def writer(self, bound: BoundVariable) -> Callable[[Any], None]:
        """A function that stores a value (already checked, `Variables.checked`) into the
        variable wherever the programs read it."""
        ...

    def store(self, bound: BoundVariable, value: Any) -> None:
        """`writer(bound)(value)`, once."""
        ...

    def take(self, *, deferred: bool = False) -> ValueTrees:
        """Every value, as the context saves it. With `deferred` the bulk may be left for
        the thread that encodes the context (`context_snapshot.capture`)."""
        ...

    def restore(self, trees: ValueTrees) -> None:
        """The values of `trees` (the programs it names, and the globals) back into this
        memory of the same configuration; ContextMismatch where a tree does not fit, which
        may leave values restored before it (the caller then starts afresh)."""
        ...


_Group = tuple[UserProgram | None, tuple[Accessor, ...], list[int], list[str]]


class ObjectMemory(Memory):
    """The values in the generated objects: the globals, every user program's instance,
    and the programs' private views of the globals (`UserProgram.view`)."""

    def __init__(self, globals_: Any, programs: list[UserProgram]) -> None:
        self._globals = globals_
        # a copy: a program restarted from fresh instances comes with a memory of its own
        self._programs = list(programs)

    def reader(self, bounds: list[BoundVariable]) -> Callable[[], list[Any]]:
        """Fast enough for watch sets and recordings of thousands of values between two
        cycles, where a walk by path per value would cost more than the cycle. Variables
        are grouped by their owner (a program instance, or the globals) and by the path
        down to their last list index (`points[3]` of `points[3].x`); below that, one
        `attrgetter` (in C) reads all the members of a group at once. Arrays are copied:
        the programs go on changing them."""
        groups: dict[tuple[int, tuple[Accessor, ...]], _Group] = {}
        for index, bound in enumerate(bounds):
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
            if read_order == list(range(len(bounds))) or len(bounds) < 2
            else operator.itemgetter(*(position[i] for i in range(len(bounds))))
        )
        arrays = [i for i, b in enumerate(bounds) if b.path.type.upper().startswith("ARRAY")]
        the_globals = self._globals

        def read() -> list[Any]:
            got: list[Any] = []
            for owner, head, getter, single in readers:
                value = owner.instance if owner is not None else the_globals
                for step in head:  # `_down` inline: a call per group would cost
                    value = value[step] if isinstance(step, int) else getattr(value, step)
                if getter is None:  # the element itself: `values[3]`
                    got.append(value)
                elif single:
                    got.append(getter(value))
                else:
                    got.extend(getter(value))
            out = got if reorder is None else list(reorder(got))
            for index in arrays:
                out[index] = copy.deepcopy(out[index])
            return out

        return read

    def read(self, bound: BoundVariable) -> Any:
        owner = bound.program.instance if bound.program is not None else self._globals
        value = _down(owner, bound.path.attrs)
        # a copy: whoever reads values must not hold (and change) the program's own lists
        return copy.deepcopy(value) if isinstance(value, list) else value

    def writer(self, bound: BoundVariable) -> Callable[[Any], None]:
        return functools.partial(self.store, bound)

    def store(self, bound: BoundVariable, value: Any) -> None:
        """A global goes into the globals and into every program's private view of them."""
        if bound.program is not None:
            _write(bound.program.instance, bound.path.attrs, value)
            return
        _write(self._globals, bound.path.attrs, value)
        for program in self._programs:
            if program.view is not self._globals:
                _write(program.view, bound.path.attrs, value)

    def take(self, *, deferred: bool = False) -> ValueTrees:
        take = capture if deferred else snapshot
        programs = {program.name: take(program.instance) for program in self._programs}
        return ValueTrees(None if self._globals is None else take(self._globals), programs)

    def restore(self, trees: ValueTrees) -> None:
        restore(self._globals, trees.globals)
        for program in self._programs:
            if program.name in trees.programs:
                restore(program.instance, trees.programs[program.name])
        share_globals(self._globals, self._programs)  # the private views see them too


def _down(owner: Any, attrs: tuple[Accessor, ...]) -> Any:
    """What `attrs` leads to below `owner`."""
    for accessor in attrs:
        owner = owner[accessor] if isinstance(accessor, int) else getattr(owner, accessor)
    return owner


def _write(owner: Any, attrs: tuple[Accessor, ...], value: Any) -> None:
    target = _down(owner, attrs[:-1])
    last = attrs[-1]
    if isinstance(last, int):
        target[last] = value
    else:
        setattr(target, last, value)
