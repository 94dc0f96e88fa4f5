"""The collector in the runtime process (runtime/collector.py): a configuration is out of
the collector's sight as soon as it arrives, loaded or prepared for a reload; what a
replaced one leaves (its classes' reference cycles) is freed at once in STOP, and in RUN
once enough arrivals wait; no collection at all while a reload prepares."""

from __future__ import annotations

import gc
import weakref
from collections.abc import Iterator

import pytest

from backend.compiler.pipeline import compile_sources
from backend.compiler.source import SourceFile
from runtime import collector, reload_switch
from runtime.clock import VirtualClock
from runtime.collector import COLLECTOR
from runtime.contract.artifact import Artifact, ProgramConfig, ResourceConfig
from runtime.resource import Resource


def compiled(body: str) -> Artifact:
    source = f"PROGRAM Main\nVAR n : DINT; t : TON; END_VAR\n{body}\nEND_PROGRAM\n"
    config = ResourceConfig(name="R", target_cycle_ms=10, safety_operation=False)
    result = compile_sources(
        [SourceFile("main.st", source)],
        resource=config,
        programs=[ProgramConfig("Main", "Main", 1)],
    )
    assert result.artifact is not None, result.diagnostics
    return result.artifact


@pytest.fixture
def managed() -> Iterator[None]:
    """This test process as the runtime process runs: everything frozen, then as it was."""
    COLLECTOR.manage()
    try:
        yield
    finally:
        COLLECTOR.release()


def in_sight(target: object) -> bool:
    return any(target is o for g in range(3) for o in gc.get_objects(generation=g))


def test_a_loaded_configuration_is_out_of_sight_and_in_stop_the_old_one_is_freed_at_once(
    managed: None,
) -> None:
    resource = Resource("R", VirtualClock())
    resource.load(compiled("n := n + 1;"))
    assert not in_sight(resource.programs[0].instance)
    old_class = weakref.ref(type(resource.programs[0].instance))
    resource.load(compiled("n := n + 3;"))  # another configuration, in STOP
    COLLECTOR.between_cycles(running=False)  # what the cycle driver does in STOP
    assert old_class() is None  # its classes' reference cycles freed
    assert COLLECTOR.arrivals == 0 and not in_sight(resource.programs[0].instance)
    resource.start()
    resource.cycle()
    assert resource.variables.value("Main.n") == 3


def test_running_a_reload_s_instances_are_frozen_before_the_switch_over_and_the_old_ones_wait(
    managed: None, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(collector, "RECLAIM_AFTER", 4)
    resource = Resource("R", VirtualClock())
    resource.load(compiled("n := n + 1;"))
    resource.start()
    resource.cycle()
    COLLECTOR.between_cycles(running=False)  # the load's arrival reclaimed, as in STOP
    old_class = weakref.ref(type(resource.programs[0].instance))

    job = reload_switch.begin(resource, compiled("n := n + 2; t(IN := TRUE);"), {})
    job.prepare()
    assert job.instances is not None and not in_sight(job.instances.programs[0].instance)
    reload_switch.finish(resource, job)
    del job
    assert COLLECTOR.arrivals == 2  # prepared, then taken
    COLLECTOR.between_cycles(running=True)
    gc.collect()  # a full collection of the collector's own does not see them either
    assert old_class() is not None  # the replaced classes wait, frozen, while running

    reload_switch.reload(resource, compiled("n := n + 5;"), {})  # two arrivals more
    COLLECTOR.between_cycles(running=True)  # RECLAIM_AFTER reached: all freed
    assert old_class() is None and COLLECTOR.arrivals == 0
    resource.cycle()
    assert resource.variables.value("Main.n") == 1 + 5  # carried over both reloads


class Node:
    def __init__(self) -> None:
        self.me = self  # a reference cycle: only a collection frees it


def test_no_collection_while_a_reload_prepares_and_what_it_made_is_frozen_at_the_end(
    managed: None,
) -> None:
    before = gc.get_threshold()
    collections = gc.get_stats()[0]["collections"]
    with COLLECTOR.held_back():
        with COLLECTOR.held_back():  # two reloads' workers at once: the last one ends it
            # the plan's maps of every variable: young when made, walked by every young
            # collection until they are promoted
            made = {n: [Node()] for n in range(20_000)}
            assert gc.get_threshold()[0] == 0
        assert gc.get_threshold()[0] == 0 and in_sight(made)
    assert gc.get_stats()[0]["collections"] == collections  # not one, young ones included
    assert gc.get_threshold() == before
    assert not in_sight(made) and gc.get_count()[0] < 10
    assert COLLECTOR.arrivals == 1  # the new configuration arrived with the preparation


def test_outside_the_runtime_process_the_collector_is_left_alone() -> None:
    frozen = gc.get_freeze_count()
    resource = Resource("R", VirtualClock())
    resource.load(compiled("n := n + 1;"))
    assert gc.get_freeze_count() == frozen and COLLECTOR.arrivals == 0
    assert in_sight(resource.programs[0].instance)
    before = gc.get_threshold()
    with COLLECTOR.held_back():
        assert gc.get_threshold() == before
