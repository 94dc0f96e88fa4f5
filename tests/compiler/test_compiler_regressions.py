"""Bugs found in review, each pinned where a user would notice it."""

from __future__ import annotations

import math
from pathlib import Path

from backend.compiler.pipeline import compile_sources
from backend.compiler.source import SourceFile
from backend.engineering.project import compile_project, load_project
from runtime.clock import VirtualClock
from runtime.contract.values import parse_time_literal
from runtime.resource import Resource


def run(text: str, cycles: int = 1) -> dict[str, object]:
    result = compile_sources([SourceFile("t.st", text)])
    assert result.artifact is not None, [str(d) for d in result.diagnostics]
    resource = Resource("R", VirtualClock())
    resource.load(result.artifact)
    resource.start()
    for _ in range(cycles):
        resource.cycle()
    return resource.variables.values()


def test_a_declared_input_named_en_is_an_input_not_the_implicit_enable() -> None:
    values = run(
        "FUNCTION_BLOCK Cnt\nVAR_INPUT en : BOOL; END_VAR\nVAR_OUTPUT n : INT; END_VAR\n"
        "IF en THEN n := n + 1; END_IF;\nEND_FUNCTION_BLOCK\n"
        "PROGRAM Main\nVAR c : Cnt; END_VAR\nc(en := TRUE);\nEND_PROGRAM\n",
        cycles=3,
    )
    assert values["Main.c.n"] == 3


def test_time_literals_are_exact_to_the_nanosecond() -> None:
    assert parse_time_literal("LT#123456789.123456789s") == (123_456_789_123_456_789, True)
    assert parse_time_literal("LT#9007199.254740993s") == (9_007_199_254_740_993, True)


def test_the_artifact_keeps_string_lengths() -> None:
    result = compile_sources(
        [SourceFile("t.st", "PROGRAM P\nVAR s : STRING[4]; END_VAR\nEND_PROGRAM")]
    )
    assert result.artifact is not None
    assert [v.type for v in result.artifact.pou("P").variables] == ["STRING[4]"]


def test_loose_files_take_resource_and_cycle_from_their_configuration(tmp_path: Path) -> None:
    source = tmp_path / "cfg.st"
    source.write_text(
        "PROGRAM Main\nEND_PROGRAM\nCONFIGURATION C\nRESOURCE Res1 ON PLC\n"
        "TASK Fast (INTERVAL := T#20ms, PRIORITY := 1);\nPROGRAM M WITH Fast : Main;\n"
        "END_RESOURCE\nEND_CONFIGURATION\n"
    )
    artifact = compile_project(load_project([source])).artifact
    assert artifact is not None
    resource = artifact.resource
    assert (resource.name, resource.target_cycle_ms, resource.target_cycle_mode) == (
        "Res1",
        20,
        "fixed",
    )
    assert [(p.name, p.pou, p.priority) for p in artifact.programs] == [("M", "Main", 1)]


def test_max_and_min_of_one_value_are_that_value() -> None:
    # they were Python's max(x) and min(x), which iterate over x: a TypeError that ended
    # `padt exec` on a traceback (the check of the form now refuses both of one value)
    values = run(
        "PROGRAM Main\nVAR x : DINT := 7; hi : DINT; lo : REAL; END_VAR\n"
        "hi := MAX(x); lo := MIN(REAL#2.5);\nEND_PROGRAM\n"
    )
    assert (values["Main.hi"], values["Main.lo"]) == (7, 2.5)


def test_expt_of_a_negative_base_to_a_fraction_is_nan_not_a_complex_number() -> None:
    # Python's power is a complex number there, which the REAL then held (the online
    # values showed `(1.7e-16+2.8j)`)
    values = run(
        "PROGRAM Main\nVAR x : LREAL := -8.0; y : LREAL; r : REAL := -8.0; z : REAL; END_VAR\n"
        "y := EXPT(x, 0.5); z := EXPT(r, REAL#0.5);\nEND_PROGRAM\n"
    )
    assert all(type(values[f"Main.{n}"]) is float for n in "yz"), values
    assert all(math.isnan(values[f"Main.{n}"]) for n in "yz"), values  # type: ignore[arg-type]


def test_an_input_left_out_takes_its_initial_value_at_every_call() -> None:
    """A structure, array or block input left out of a call was the FUNCTION's (or
    method's) one default object, shared by every call and keeping what the function
    wrote into it: Bump() gave 1, 2, 3 over three cycles."""
    values = run(
        "TYPE Pt : STRUCT x : REAL := 0.5; END_STRUCT; END_TYPE\n"
        "FUNCTION Bump : REAL\nVAR_INPUT a : Pt; n : ARRAY[1..2] OF INT; END_VAR\n"
        "a.x := a.x + 1.0; n[1] := n[1] + 1;\nBump := a.x + INT_TO_REAL(n[1]);\nEND_FUNCTION\n"
        "FUNCTION_BLOCK Box\nVAR_OUTPUT y : REAL; END_VAR\n"
        "METHOD PUBLIC Grow : REAL\nVAR_INPUT a : Pt; END_VAR\n"
        "a.x := a.x * 2.0; Grow := a.x;\nEND_METHOD\nEND_FUNCTION_BLOCK\n"
        "PROGRAM Main\nVAR r, q : REAL; b : Box; END_VAR\n"
        "r := Bump(); q := b.Grow();\nEND_PROGRAM\n",
        cycles=3,
    )
    assert (values["Main.r"], values["Main.q"]) == (2.5, 1.0)
