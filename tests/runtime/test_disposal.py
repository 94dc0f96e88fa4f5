"""What a reload replaces is freed between cycles a slice at a time (runtime/disposal.py):
by a cycle driver's steps when one runs, at once otherwise; what somebody else still holds
is never emptied."""

from __future__ import annotations

import weakref
from collections.abc import Iterator

import pytest

from runtime.disposal import DISPOSAL


class Variable:
    """Like a bound variable: a plain object with attributes."""

    def __init__(self, n: int) -> None:
        self.n = n
        self.path = f"Main.v{n}"


class Point:
    __slots__ = ("__weakref__", "tags", "x", "y")

    def __init__(self, n: int) -> None:
        self.x, self.y, self.tags = n, -n, [n] * 3


class Configuration:
    """Like the old instances a reload leaves: large lists and dicts below an object."""

    def __init__(self, size: int) -> None:
        self.bound = [Variable(n) for n in range(size)]
        self.by_name = {v.path: v for v in self.bound}
        self.points = (tuple(Point(n) for n in range(size)),)


@pytest.fixture
def stepping() -> Iterator[None]:
    """As while a cycle driver runs."""
    DISPOSAL.deferred = True
    try:
        yield
    finally:
        DISPOSAL.let_go_at_once()


def test_a_large_configuration_is_freed_over_several_steps(stepping: None) -> None:
    configuration = Configuration(5_000)
    deep, point = weakref.ref(configuration.bound[2_500]), weakref.ref(configuration.points[0][7])
    DISPOSAL.dispose([configuration])
    del configuration
    DISPOSAL.step(budget_ns=1)  # one piece at least, however small the budget
    assert DISPOSAL.pending and deep() is not None and point() is not None
    steps = 1
    while DISPOSAL.pending:
        DISPOSAL.step(budget_ns=1)
        steps += 1
    assert deep() is None and point() is None
    assert steps > 20  # slices, not one go


def test_what_somebody_else_holds_is_let_go_of_but_never_emptied(stepping: None) -> None:
    configuration = Configuration(1_000)
    kept_list, kept_dict = configuration.bound, configuration.by_name
    kept_point = configuration.points[0][3]
    DISPOSAL.dispose([configuration])
    del configuration
    while DISPOSAL.pending:
        DISPOSAL.step()
    assert len(kept_list) == 1_000 and kept_list[999].n == 999
    assert len(kept_dict) == 1_000 and kept_dict["Main.v5"].n == 5
    assert kept_point.tags == [3, 3, 3]


def test_without_a_driver_everything_is_freed_at_once() -> None:
    configuration = Configuration(100)
    deep = weakref.ref(configuration.bound[50])
    holder: list[object] = [configuration]
    del configuration
    DISPOSAL.dispose(holder)
    assert deep() is None and not holder and not DISPOSAL.pending


def test_when_the_driver_stops_what_is_pending_is_freed(stepping: None) -> None:
    configuration = Configuration(2_000)
    deep = weakref.ref(configuration.bound[1_000])
    DISPOSAL.dispose([configuration])
    del configuration
    DISPOSAL.step(budget_ns=1)
    DISPOSAL.let_go_at_once()
    assert deep() is None and not DISPOSAL.pending and not DISPOSAL.deferred
