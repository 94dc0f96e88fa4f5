"""`ObjectMemory` (runtime/memory.py): what services read and write of a loaded
configuration, and what the context takes and restores, over the generated objects."""

from __future__ import annotations

import json

import pytest

from backend.compiler.pipeline import compile_sources
from backend.compiler.source import SourceFile
from runtime.clock import VirtualClock
from runtime.context_snapshot import ContextMismatch
from runtime.contract.artifact import ProgramConfig, ResourceConfig
from runtime.memory import ObjectMemory, ValueTrees
from runtime.resource import Resource

PLANT = """
TYPE Point : STRUCT x : REAL; n : DINT; END_STRUCT; END_TYPE
VAR_GLOBAL
  level : INT;
  points : ARRAY[1..2] OF Point;
END_VAR
PROGRAM A
VAR_EXTERNAL level : INT; points : ARRAY[1..2] OF Point; END_VAR
VAR t : TON; n : DINT; seen : INT; history : ARRAY[0..2] OF INT; END_VAR
n := n + 1;
seen := level;
history[n MOD 3] := level + DINT_TO_INT(n);
points[2].n := n;
t(IN := TRUE, PT := T#1s);
END_PROGRAM
PROGRAM B
VAR_EXTERNAL level : INT; END_VAR
VAR seen : INT; r : LREAL; END_VAR
seen := level;
r := r + 0.5;
END_PROGRAM
"""


def loaded() -> Resource:
    config = ResourceConfig(name="P", target_cycle_ms=10, safety_operation=False)
    programs = [ProgramConfig("A", "A", 1), ProgramConfig("B", "B", 2)]
    result = compile_sources([SourceFile("p.st", PLANT)], resource=config, programs=programs)
    assert result.artifact is not None, [str(d) for d in result.diagnostics]
    resource = Resource("P", VirtualClock())
    resource.load(result.artifact)
    return resource


def test_a_global_written_is_seen_by_every_program() -> None:
    resource = loaded()
    variables = resource.variables
    memory = variables.memory
    assert isinstance(memory, ObjectMemory)
    level = variables.lookup("level")
    # two programs: each has a view of the globals of its own
    assert all(program.view is not variables.globals for program in variables.programs)
    memory.store(level, 7)
    assert memory.read(level) == 7
    resource.start()
    resource.cycle()
    assert variables.value("A.seen") == variables.value("B.seen") == 7
    memory.writer(variables.lookup("points[1].x"))(2.5)
    assert memory.read(variables.lookup("points[1].x")) == 2.5
    paths = ["A.n", "level", "points[2].n", "B.r", "A.history"]
    read = memory.reader([variables.lookup(path) for path in paths])
    assert read() == [1, 7, 1, 0.5, [0, 8, 0]]
    history = read()[4]
    resource.cycle()
    assert read() == [2, 7, 2, 1.0, [0, 8, 9]]
    assert history == [0, 8, 0]  # an array read is a copy


def test_take_and_restore_round_trip() -> None:
    resource = loaded()
    resource.start()
    clock = resource.clock
    assert isinstance(clock, VirtualClock)
    for _ in range(3):
        resource.cycle()
        clock.advance(10_000_000)  # the timer runs: its elapsed time is saved too
    resource.variables.store(resource.variables.lookup("level"), 40)
    before = resource.variables.values()
    taken = resource.variables.memory.take()
    deferred = resource.variables.memory.take(deferred=True)
    trees = ValueTrees(**json.loads(json.dumps(vars(taken))))  # as a context file holds it

    fresh = loaded()
    fresh.variables.memory.restore(trees)
    assert fresh.variables.values() == before
    # the programs' views of the globals have them too
    fresh.start()
    fresh.cycle()
    assert fresh.variables.value("A.seen") == fresh.variables.value("B.seen") == 40

    other = loaded()
    other.variables.memory.restore(ValueTrees(deferred.globals, {"B": deferred.programs["B"]}))
    assert other.variables.value("B.r") == before["B.r"]
    assert other.variables.value("A.n") == 0  # a program the trees do not name is left alone
    with pytest.raises(ContextMismatch):
        other.variables.memory.restore(ValueTrees(taken.globals, {"A": taken.programs["B"]}))
