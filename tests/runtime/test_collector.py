"""The running configuration is kept out of the cycle collector's full collections
(runtime/collector.py), and a configuration replaced by a load or reload is still freed,
its reference cycles (classes and their namespace) included."""

from __future__ import annotations

import gc
import weakref

from backend.compiler.pipeline import compile_sources
from backend.compiler.source import SourceFile
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


def in_a_generation(target: object) -> bool:
    return any(target is o for g in range(3) for o in gc.get_objects(generation=g))


def test_the_configuration_is_frozen_after_a_full_collection_and_the_old_one_freed() -> None:
    resource = Resource("R", VirtualClock())
    resource.load(compiled("n := n + 1;"))
    gc.collect()  # the first full collection after the load
    COLLECTOR.between_cycles()
    program = resource.programs[0].instance
    assert COLLECTOR.frozen and not in_a_generation(program)

    old_class = weakref.ref(type(program))
    del program
    resource.load(compiled("n := n + 2;"))  # another configuration in STOP
    assert not COLLECTOR.frozen  # waits for a full collection to free the old one first
    COLLECTOR.between_cycles()
    assert not COLLECTOR.frozen
    gc.collect()
    COLLECTOR.between_cycles()
    assert old_class() is None  # the replaced configuration's classes are gone
    assert COLLECTOR.frozen and not in_a_generation(resource.programs[0].instance)
    resource.start()
    resource.cycle()
    assert resource.variables.value("Main.n") == 2


def test_in_stop_the_collection_is_made_at_once_and_frees_the_old_configuration() -> None:
    resource = Resource("R", VirtualClock())
    resource.load(compiled("n := n + 1;"))
    old_class = weakref.ref(type(resource.programs[0].instance))
    resource.load(compiled("n := n + 3;"))
    COLLECTOR.between_cycles(running=False)  # what the cycle driver does in STOP
    assert old_class() is None
    assert COLLECTOR.frozen and not in_a_generation(resource.programs[0].instance)
    resource.start()
    resource.cycle()
    assert resource.variables.value("Main.n") == 3
