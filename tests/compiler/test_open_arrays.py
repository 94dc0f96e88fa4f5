"""Variable-length arrays (`ARRAY[*] OF T`, `ARRAY[*, *] OF T`) as inputs and in-outs of
functions and in-outs of function blocks: bound to arrays of any bounds at each call, their
bounds read with LOWER_BOUND and UPPER_BOUND and checked on every access; traced through
`padt sim` (100 ms cycles)."""

from __future__ import annotations

import json
from pathlib import Path

from backend.compiler.pipeline import compile_sources
from backend.compiler.source import SourceFile
from runtime.clock import VirtualClock
from runtime.context import ContextInvalid, load_context, save_context
from runtime.contract.artifact import ProgramConfig, ResourceConfig
from runtime.resource import Resource
from runtime.restart import take_context, warm_start
from tests.compiler.test_checks import diagnostics
from tests.conftest import padt, sim_trace

LIBRARY = """
FUNCTION Sum : DINT
VAR_INPUT v : ARRAY[*] OF INT; END_VAR
VAR i : DINT; END_VAR
FOR i := LOWER_BOUND(v, 1) TO UPPER_BOUND(v, 1) DO
  Sum := Sum + v[i];
END_FOR;
v[LOWER_BOUND(v, 1)] := 0;  (* an input is a copy: the caller's array keeps its value *)
END_FUNCTION
FUNCTION_BLOCK Scale
VAR_INPUT k : INT; END_VAR
VAR_IN_OUT m : ARRAY[*, *] OF INT; END_VAR
VAR i, j : DINT; END_VAR
FOR i := LOWER_BOUND(m, 1) TO UPPER_BOUND(m, 1) DO
  FOR j := LOWER_BOUND(m, 2) TO UPPER_BOUND(m, 2) DO
    m[i, j] := m[i, j] * k;
  END_FOR;
END_FOR;
END_FUNCTION_BLOCK
FUNCTION Poke : BOOL
VAR_IN_OUT v : ARRAY[*] OF INT; END_VAR
VAR_INPUT idx : DINT; END_VAR
v[idx] := 99;
Poke := TRUE;
END_FUNCTION
FUNCTION Bounds : DINT
VAR_IN_OUT v : ARRAY[*, *] OF INT; END_VAR
Bounds := LOWER_BOUND(v, 1) * 1000 + UPPER_BOUND(v, 1) * 100
  + LOWER_BOUND(v, 2) * 10 + UPPER_BOUND(v, 2);
END_FUNCTION
"""

PROGRAM = (
    LIBRARY
    + """
PROGRAM Main
VAR
  a : ARRAY[1..3] OF INT := [1, 2, 3];
  b : ARRAY[-1..5] OF INT := [7(1)];
  g : ARRAY[0..1, 2..3] OF INT := [1, 2, 3, 4];
  s1, s2, gb : DINT; sc : Scale; ok : BOOL; where : DINT := 1;
END_VAR
s1 := Sum(a);
s2 := Sum(v := b);
sc(k := 2, m := g);
gb := Bounds(g);
ok := Poke(a, where);
where := where + 1;
END_PROGRAM
"""
)


def test_open_arrays_take_any_bounds_and_write_through_in_outs(tmp_path: Path) -> None:
    t = sim_trace(tmp_path, PROGRAM, 3)
    # Sum sees a's values before Poke writes 99 into a[where] later in the same cycle
    assert t["Main.a"] == [[99, 2, 3], [99, 99, 3], [99, 99, 99]]
    assert t["Main.s1"] == [6, 104, 201]
    assert t["Main.s2"] == [7, 7, 7]  # -1..5: seven elements, an input copy left unchanged
    assert t["Main.b"] == [[1] * 7] * 3
    assert t["Main.g"] == [[2, 4, 6, 8], [4, 8, 12, 16], [8, 16, 24, 32]]
    assert t["Main.gb"] == [123, 123, 123]  # 0..1, 2..3
    # the block's in-out is the caller's array: it is shown there, not in the instance
    assert "Main.sc.m" not in t


def test_a_function_output_fills_the_array_the_caller_connects(tmp_path: Path) -> None:
    source = """
FUNCTION Ramp : BOOL
VAR_OUTPUT out : ARRAY[*] OF INT; END_VAR
VAR_INPUT step : INT; END_VAR
VAR i : DINT; END_VAR
FOR i := LOWER_BOUND(out, 1) TO UPPER_BOUND(out, 1) DO
  out[i] := out[i] + step;
END_FOR;
Ramp := TRUE;
END_FUNCTION
PROGRAM Main
VAR data : ARRAY[2..4] OF INT; ok : BOOL; END_VAR
ok := Ramp(step := 5, out => data);
END_PROGRAM
"""
    # bound to the caller's array, not reset at the call: it keeps adding up
    assert sim_trace(tmp_path, source, 3)["Main.data"] == [[5, 5, 5], [10, 10, 10], [15] * 3]


def test_an_index_outside_the_bounds_passed_stops_the_program(tmp_path: Path) -> None:
    path = tmp_path / "main.st"
    path.write_text(PROGRAM)
    run = padt("sim", str(path), "--cycles", "5", "--cycle-ms", "100")
    assert run.returncode != 0
    assert "cycle 4: program Main: array index 4 outside 1..3 in POU Poke" in run.stderr
    rows = [json.loads(line)["values"] for line in run.stdout.splitlines()]
    # the program stopped in cycle 4, before `where := where + 1`: nothing moves after it
    assert [row["Main.where"] for row in rows] == [2, 3, 4, 4, 4]


def test_variable_length_arrays_where_they_cannot_be_get_codes() -> None:
    source = """
TYPE S : STRUCT m : ARRAY[*] OF INT; END_STRUCT; END_TYPE
FUNCTION_BLOCK FB
VAR_INPUT i : ARRAY[*] OF INT; END_VAR
END_FUNCTION_BLOCK
FUNCTION F : INT
VAR o : ARRAY[*] OF INT; END_VAR
VAR mix : ARRAY[*, 1..2] OF INT; END_VAR
F := 0;
END_FUNCTION
"""
    only = "only a function's or method's parameters and a function block's VAR_IN_OUT can"
    assert diagnostics(source) == [
        f"t.st:2:17: error: 'm' cannot be a variable-length array (ARRAY[*] OF INT): {only}"
        " [E0704]",
        f"t.st:4:11: error: 'i' cannot be a variable-length array (ARRAY[*] OF INT): {only}"
        " [E0704]",
        f"t.st:7:5: error: 'o' cannot be a variable-length array (ARRAY[*] OF INT): {only} [E0704]",
        "t.st:8:11: error: an array has either all its ranges open (*) or none [E0704]",
    ]


def test_arguments_of_variable_length_arrays_are_checked() -> None:
    source = (
        LIBRARY
        + """
PROGRAM Main
VAR a : ARRAY[1..3] OF INT; r : ARRAY[1..3] OF REAL; x : DINT; sc : Scale; END_VAR
x := Bounds(a);
x := Sum(r);
x := Sum();
sc(k := 2);
END_PROGRAM
"""
    )
    assert diagnostics(source) == [
        "t.st:34:13: error: type mismatch: cannot pass ARRAY[1..3] OF INT as"
        " ARRAY[*, *] OF INT [E0401]",
        "t.st:35:10: error: type mismatch: cannot pass ARRAY[1..3] OF REAL as"
        " ARRAY[*] OF INT [E0401]",
        "t.st:36:6: error: 'Sum' needs an array for its parameter 'v' in every call [E0413]",
        "t.st:37:1: error: 'Scale' needs an array for its parameter 'm' in every call [E0413]",
    ]


def test_a_variable_length_array_is_no_value_to_assign() -> None:
    source = """
FUNCTION G : INT
VAR_IN_OUT v : ARRAY[*] OF INT; END_VAR
VAR a : ARRAY[1..2] OF INT; END_VAR
v := a;
G := v[1];
END_FUNCTION
"""
    assert diagnostics(source) == [
        "t.st:5:6: error: type mismatch: cannot assign ARRAY[1..2] OF INT to ARRAY[*] OF INT"
        " [E0209]"
    ]


def test_a_block_bound_to_an_array_survives_a_warm_start(tmp_path: Path) -> None:
    """A block is bound to the caller's array for the call only: its instance holds no
    binding between cycles, so the context saves and restores like any other."""
    source = """
FUNCTION_BLOCK Fill
VAR_IN_OUT v : ARRAY[*] OF INT; END_VAR
VAR_INPUT x : INT; END_VAR
v[UPPER_BOUND(v, 1)] := x;
END_FUNCTION_BLOCK
PROGRAM Main
VAR a : ARRAY[4..6] OF INT; f : Fill; n : INT; END_VAR
n := n + 1;
IF n = 1 THEN f(v := a, x := 5); END_IF;
END_PROGRAM
"""
    config = ResourceConfig(name="R", target_cycle_ms=10, autostart="off", safety_operation=False)
    result = compile_sources(
        [SourceFile("main.st", source)],
        resource=config,
        programs=[ProgramConfig("Main", "Main", 1)],
    )
    assert result.artifact is not None, [str(d) for d in result.diagnostics]
    first = Resource("R", VirtualClock())
    first.load(result.artifact)
    first.start()
    first.cycle()
    assert first.variables.value("Main.a") == [0, 0, 5]
    context = take_context(first)
    assert context is not None
    save_context(tmp_path / "context.json", context)

    second = Resource("R", VirtualClock())
    second.load(result.artifact)
    saved = load_context(tmp_path / "context.json", result.artifact.crc)
    assert not isinstance(saved, ContextInvalid)
    warm_start(second, saved)
    assert second.status().start == "warm"
    assert second.variables.value("Main.a") == [0, 0, 5]
