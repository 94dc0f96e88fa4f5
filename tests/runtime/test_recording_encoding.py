"""The two halves of recording a cycle's values: reading them on the cycle thread
(`ObjectMemory.reader`) and encoding them as JSON on the writer thread (`ValuesEncoder`). Both
are tuned for thousands of variables every 10 ms; these tests hold them to the plain
definitions: the values `Variables.read` gives, the text `json.dumps` of the nested
message gives. And the writer keeps out of the cycle's way (`CycleGate`)."""

from __future__ import annotations

import gc
import math
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import pytest
from hypothesis import given
from hypothesis import strategies as st

from backend.compiler.pipeline import compile_sources
from backend.compiler.source import SourceFile
from runtime.clock import VirtualClock
from runtime.contract.artifact import ProgramConfig, ResourceConfig
from runtime.contract.recording import RecordingHeader, nest, read_recording
from runtime.resource import Resource
from runtime.trace_writer import CycleGate, TraceWriter, Values, ValuesEncoder, _json

PLANT = """
TYPE Point : STRUCT x : REAL; n : DINT; name : STRING[8]; END_STRUCT; END_TYPE
VAR_GLOBAL
  level AT %IW0 : INT;
  points : ARRAY[1..3] OF Point;
  mode : STRING[16] := 'auto';
END_VAR
PROGRAM A
VAR_EXTERNAL level : INT; points : ARRAY[1..3] OF Point; END_VAR
VAR t : TON; n : DINT; history : ARRAY[0..2] OF INT; on : BOOL; END_VAR
n := n + 1;
history[n MOD 3] := level + n;
points[2].x := DINT_TO_REAL(n) / 3.0;
points[3].n := n * 7;
on := NOT on;
t(IN := on, PT := T#20ms);
END_PROGRAM
PROGRAM B
VAR k : DINT := 5; r : LREAL; END_VAR
k := k * 3 MOD 1000;
r := DINT_TO_LREAL(k) / 7.0;
END_PROGRAM
"""


def running() -> Resource:
    config = ResourceConfig(name="P", target_cycle_ms=10, safety_operation=False)
    programs = [ProgramConfig("A", "A", 1), ProgramConfig("B", "B", 2)]
    result = compile_sources([SourceFile("p.st", PLANT)], resource=config, programs=programs)
    assert result.artifact is not None, [str(d) for d in result.diagnostics]
    resource = Resource("P", VirtualClock())
    resource.load(result.artifact)
    resource.start()
    return resource


def test_the_values_read_are_those_of_the_variables_in_any_order() -> None:
    resource = running()
    variables = resource.variables
    everything = list(variables.bound)
    # globals, both programs, members of FBs, struct members in arrays (indexed paths)
    paths = [b.path.path for b in everything]
    assert {"level", "mode", "A.t.Q", "B.k", "A.history"} <= set(paths)
    assert any(path.startswith("points[") for path in paths)
    orders = [everything, everything[::-1], everything[1::2] + everything[::2], everything[:1]]
    readers = [(order, variables.memory.reader(order)) for order in orders]
    clock = resource.clock
    assert isinstance(clock, VirtualClock)
    for _ in range(5):
        resource.io.set_inputs({"level": 40})
        resource.cycle()
        clock.advance(10_000_000)
        for order, read in readers:
            assert read() == [variables.read(b) for b in order]
    # an array is copied: what was read does not change with the program
    [history] = [b for b in everything if b.path.path == "A.history"]
    read = variables.memory.reader([history])
    kept = read()
    resource.cycle()
    assert kept != read()


LEAVES = st.one_of(
    st.integers(-(1 << 63), (1 << 64) - 1),
    st.floats(allow_nan=True, allow_infinity=True),
    st.booleans(),
    st.text(max_size=8),
    st.lists(st.one_of(st.integers(-100, 100), st.floats(width=32)), max_size=4),
)
NAMES = st.sampled_from(["A", "B", "x", "t", "Q", "level", "Ünits", 'q"uote'])


@st.composite
def recorded(draw: st.DrawFn) -> tuple[list[str], list[Any]]:
    """Distinct paths of one to three parts (none the parent of another) and values."""
    paths: list[str] = []
    for parts in draw(st.lists(st.lists(NAMES, min_size=1, max_size=3), min_size=1, max_size=12)):
        path = ".".join(parts)
        clashes = any(
            p == path or p.startswith(path + ".") or path.startswith(p + ".") for p in paths
        )
        if not clashes:
            paths.append(path)
    return paths, draw(st.lists(LEAVES, min_size=len(paths), max_size=len(paths)))


@given(recorded(), st.integers(0, 1 << 40))
def test_a_values_message_is_the_json_of_the_nested_values(
    chosen: tuple[list[str], list[Any]], cycle: int
) -> None:
    paths, values = chosen
    expected = _json({"cycle": cycle, "values": nest(paths, values)})
    assert ValuesEncoder(paths).encode(cycle, values) == expected


@contextmanager
def collections_counted() -> Iterator[list[int]]:
    counted = [0]

    def count(phase: str, _info: dict[str, Any]) -> None:
        counted[0] += phase == "start"

    gc.callbacks.append(count)
    try:
        yield counted
    finally:
        gc.callbacks.remove(count)


def test_encoding_ten_thousand_values_sets_off_no_garbage_collection() -> None:
    """Every collection stops the cycle thread too; `json.dumps` of the nested message
    made one every 700 or so entries (a tuple each): 164 for these 20 messages."""
    paths = [f"Plant.v{n}" if n % 5 else f"G{n % 3}.s.v{n}" for n in range(10_000)]
    values = [[n, n / 7, n % 2 == 0, math.pi * n][n % 4] for n in range(10_000)]
    encoder = ValuesEncoder(paths)
    assert encoder.encode(1, values) == _json({"cycle": 1, "values": nest(paths, values)})
    with collections_counted() as counted:
        for cycle in range(20):
            encoder.encode(cycle, values)
    # allow a few that another thread of the test process may set off meanwhile
    assert counted[0] < 10, counted[0]


def header(paths: list[str]) -> RecordingHeader:
    return RecordingHeader(
        resource="P",
        project="p",
        crc="0",
        variables=[(path, "DINT") for path in paths],
        all_inputs=False,
        started_ns=1_700_000_000 * 10**9,
        recording="g",
        part=1,
    )


def test_a_writer_waits_while_a_cycle_runs_but_not_for_a_cycle_that_never_ends(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    gate = CycleGate()
    writer = TraceWriter(tmp_path, header(["P.n"]), {}, 1 << 30, None, gate)
    monkeypatch.setattr("runtime.trace_writer.MAX_PAUSE_S", 60.0)
    gate.begins()
    assert writer.offer(Values(1, 1_700_000_000 * 10**9, [1]))
    time.sleep(0.3)
    assert writer.written == 0  # the cycle has the interpreter
    gate.ends()
    # the resource stopped inside a cycle: the writer goes on after MAX_PAUSE_S
    monkeypatch.setattr("runtime.trace_writer.MAX_PAUSE_S", 0.01)
    gate.begins()
    for cycle in range(2, 41):
        assert writer.offer(Values(cycle, 1_700_000_000 * 10**9 + cycle, [cycle]))
    writer.close()
    writer.join(30)
    assert writer.finished and writer.error is None
    assert read_recording(tmp_path / "g-1.mcap").column("P.n") == list(range(1, 41))
