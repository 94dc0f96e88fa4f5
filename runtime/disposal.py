"""Letting go of a replaced configuration a slice at a time, between cycles.

The last reference to what a reload replaced (the old instances not adopted, their bound
paths and lookup by name, the switch-over lists) goes away on the cycle thread, between
two cycles. Freed there by reference counts in one go, 10,000 variables' worth took 2-3
ms: one C call. A thread freeing it in the background was worse: it shares the
interpreter lock with the cycle thread, which then waited for it in every cycle, for up
to the switch interval each time.

So the cycle driver takes it apart itself, with a small budget after every cycle
(`step`): a list or dict only the disposal holds loses its items a slice at a time.
Anything somebody else still holds is only let go of; it is freed where its last holder
drops it. Without a driver (tests, tools) everything is let go of at once."""

from __future__ import annotations

import sys
import time

STEP_NS = 150_000  # the budget after one cycle (a slice may overrun it by its own time)
SLICE = 128  # items freed in one go: 20-150 us
SMALL = 64  # the items of a container up to this size are taken apart, and the slots of
# an object with up to this many (a program with thousands of them is freed whole: looking
# at every slot in Python takes longer than freeing them)
_CONTAINERS = (list, dict, tuple)
_SCALARS = frozenset({int, float, bool, str, bytes, type(None)})
_OWNED = 2  # references to an object held only here: a local and getrefcount's argument


class Disposal:
    """The cycle thread's: `dispose` when a switch-over is done, `step` between cycles."""

    def __init__(self) -> None:
        self.deferred = False  # set by a cycle driver, which steps
        self._stack: list[object] = []

    def dispose(self, holder: list[object]) -> None:
        """Takes the objects out of `holder` (the caller's only references, emptied)."""
        if self.deferred:
            self._stack.extend(holder)
        holder.clear()

    def let_go_at_once(self) -> None:
        """No more stepping: what is pending is freed now, and from now on at once."""
        self.deferred = False
        self._stack.clear()

    @property
    def pending(self) -> int:
        return len(self._stack)

    def step(self, budget_ns: int = STEP_NS) -> None:
        """Takes apart what is pending until the budget is spent (the rest waits); one
        piece at least."""
        stack = self._stack
        deadline = time.perf_counter_ns() + budget_ns
        while stack:
            item = stack.pop()
            if sys.getrefcount(item) <= _OWNED:  # else somebody else holds it: theirs
                if isinstance(item, list | dict):
                    _slice_off(item, stack)
                else:
                    stack.extend(_parts(item))
            del item
            if time.perf_counter_ns() >= deadline:
                return


def _slice_off(items: list[object] | dict[object, object], stack: list[object]) -> None:
    """Frees a slice of the container's items; the container goes back on the stack while
    items remain (it is still only ours). Of a large container's items only the large
    containers are kept to be taken apart in turn; of a small one's, all that hold others."""
    large = len(items) > SMALL
    if isinstance(items, dict):
        chunk = [items.popitem()[1] for _ in range(min(SLICE, len(items)))]
    else:
        chunk = items[-SLICE:]
        del items[-SLICE:]
    if items:
        stack.append(items)
    if large:
        stack.extend([o for o in chunk if type(o) in _CONTAINERS and len(o) > SMALL])  # type: ignore[arg-type]
    else:
        stack.extend(o for o in chunk if _composite(o))
    # the rest of the chunk is freed when it goes, here


def _parts(item: object) -> list[object]:
    """What an object (or a tuple) holds that is worth taking apart; the object itself is
    then freed cheaply, its parts still held."""
    if isinstance(item, tuple):  # a large one as a list, which is freed in slices
        return [list(item)] if len(item) > SMALL else [o for o in item if _composite(o)]
    if isinstance(item, type):
        return []  # a class's reference cycles are the collector's
    if hasattr(item, "__dict__") and vars(item):
        return [o for o in vars(item).values() if _composite(o)]
    names = _slot_names(type(item))
    if len(names) > SMALL:
        return []
    return [o for o in (getattr(item, n, None) for n in names) if _composite(o)]


def _slot_names(kind: type) -> list[str]:
    names: list[str] = []
    for base in kind.__mro__:
        slots = base.__dict__.get("__slots__", ())
        names += [slots] if isinstance(slots, str) else slots
    return names


def _composite(value: object) -> bool:
    """Anything that holds other objects."""
    if type(value) in _SCALARS:  # most of what a program holds: answered at once
        return False
    if isinstance(value, _CONTAINERS):
        return True
    return hasattr(value, "__dict__") or hasattr(type(value), "__slots__")


DISPOSAL = Disposal()
