"""A watch set's reading plan is made off the cycle thread (runtime/online_values.py,
`planned`): the set waits until it is made, once, and a reload makes it anew; a plan that
fails there is made where the set is read, which meets the error."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from runtime.memory import ObjectMemory
from runtime.watch_sets import WatchSet
from tests.support.resource_harness import Harness, compiled, harness

PLANT = """PROGRAM Main
VAR n : INT; flags : ARRAY[1..3] OF BOOL; END_VAR
n := n + 1; flags[2] := n > 1;
END_PROGRAM
"""


class Elsewhere:
    """Another thread, run by hand: the work handed to it waits until `run`."""

    def __init__(self) -> None:
        self.waiting: list[Callable[[], None]] = []

    def __call__(self, work: Callable[[], None]) -> None:
        self.waiting.append(work)

    def run(self) -> None:
        work, self.waiting = self.waiting, []
        for item in work:
            item()


def watched(h: Harness) -> WatchSet:
    h.ok("watch", id="w", variables=["Main.n", "Main.flags"])
    watch_set = h.resource.online.watches.get("w")
    assert watch_set is not None
    return watch_set


def test_a_set_waits_for_its_plan_made_elsewhere_once() -> None:
    h = harness(PLANT, [{"name": "Main"}])
    h.cycle(2)
    watch_set, elsewhere = watched(h), Elsewhere()
    online = h.resource.online
    assert not online.planned(watch_set, elsewhere)
    assert not online.planned(watch_set, elsewhere)  # asked again: still the one piece of work
    assert len(elsewhere.waiting) == 1
    elsewhere.run()
    assert online.planned(watch_set, elsewhere) and not elsewhere.waiting
    snapshot = online.snapshot(watch_set, h.resource.cycle_count, True, h.resource.forcing.table)
    assert snapshot.values == [2, [False, True, False]]


def test_after_a_reload_the_plan_is_made_anew_for_the_new_configuration() -> None:
    h = harness(PLANT, [{"name": "Main"}])
    h.cycle()
    watch_set, elsewhere = watched(h), Elsewhere()
    online = h.resource.online
    online.planned(watch_set, elsewhere)
    elsewhere.run()
    h.send(compiled(PLANT.replace("n + 1", "n + 10"), [{"name": "Main"}]))
    assert h.cmd("reload")["ok"]
    assert not online.planned(watch_set, elsewhere)  # made for the configuration before
    elsewhere.run()
    h.cycle()
    assert online.planned(watch_set, elsewhere)
    snapshot = online.snapshot(watch_set, h.resource.cycle_count, True, h.resource.forcing.table)
    assert snapshot.values == [11, [False, True, False]]


def test_a_plan_that_fails_elsewhere_is_made_where_the_set_is_read(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    h = harness(PLANT, [{"name": "Main"}])
    watch_set, elsewhere = watched(h), Elsewhere()
    online = h.resource.online

    def broken(*args: object) -> object:
        raise RuntimeError("no reader")

    monkeypatch.setattr(ObjectMemory, "reader", broken)
    assert not online.planned(watch_set, elsewhere)
    elsewhere.run()  # fails there, quietly
    assert online.planned(watch_set, elsewhere)  # so the set is read here, and
    with pytest.raises(RuntimeError, match="no reader"):  # the error is met where it is read
        online.snapshot(watch_set, 1, True, h.resource.forcing.table)
