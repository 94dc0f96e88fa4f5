"""Views of a memory image (runtime/code/native/image_views.py, padt_memory.c; issue 34
step 5): the Python tier's generated code run on views of the image gives every value it
gives on slot objects, cycle after cycle (the compiler's random programs, an SFC chart,
strings, arrays of structures and blocks, every elementary type); a view refuses what a
slot would never be given and keeps its value; arrays read as lists when copied, a
structure copies whole."""

from __future__ import annotations

import copy
import math
from types import ModuleType

import pytest
from hypothesis import HealthCheck, given, settings

from tests.compiler.test_differential import CYCLES, programs
from tests.conftest import REPO
from tests.support.image_runs import ImageRun, compiled, values

EVERY_TYPE = """\
TYPE Color : (Red, Green, Blue); END_TYPE
TYPE Pt : STRUCT x : INT; y : LREAL; tag : STRING[4]; END_STRUCT; END_TYPE
FUNCTION_BLOCK Counter
VAR_INPUT step : SINT; END_VAR
VAR_OUTPUT n : UDINT; END_VAR
n := n + SINT_TO_UDINT(step);
END_FUNCTION_BLOCK
PROGRAM Main
VAR
  b : BOOL; s8 : SINT := -5; u8 : BYTE := 16#F0; i16 : INT; u16 : WORD; i32 : DINT;
  u32 : UDINT; i64 : LINT; u64 : ULINT; r : REAL := 1.5; lr : LREAL; t : TIME;
  c : Color := Green; name : STRING[8]; wide : WSTRING[4] := "ab";
  pts : ARRAY[1..3] OF Pt; grid : ARRAY[0..1, 0..2] OF INT; counters : ARRAY[1..2] OF Counter;
  k : INT; timer : TON;
END_VAR
b := NOT b;
s8 := s8 + 1; u8 := ROL(u8, 1); i16 := i16 - 300; u16 := u16 + 4000;
i32 := i32 * 3 + 7; u32 := u32 + 16#1000_0000; i64 := i64 - 123456789012;
u64 := u64 + 16#1234_5678_9ABC; r := r * 1.25; lr := lr + 0.1; t := t + T#150ms;
IF c = Green THEN c := Blue; ELSE c := Green; END_IF;
name := CONCAT(LEFT(name, 6), 'ab');
FOR k := 1 TO 3 DO
  pts[k].x := pts[k].x + INT_TO_INT(k);
  pts[k].y := pts[k].y + 0.5;
  pts[k].tag := LEFT(CONCAT(pts[k].tag, 'xy'), 4);
  grid[k MOD 2, k - 1] := grid[k MOD 2, k - 1] + k;
END_FOR;
pts[1] := pts[2];
counters[1](step := 3);
counters[2](step := s8);
timer(IN := b, PT := T#250ms);
END_PROGRAM
"""


@settings(
    max_examples=15,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
@given(programs())
def test_random_programs_run_alike_on_objects_and_on_views(
    padt_memory: ModuleType, program: str
) -> None:
    run = ImageRun(compiled(program), padt_memory)
    for _ in range(CYCLES):
        on_objects, on_views = run.cycle()
        assert on_objects == on_views
        run.compare()
        if on_objects:
            break


def test_every_elementary_type_strings_arrays_of_structures_and_blocks(
    padt_memory: ModuleType,
) -> None:
    run = ImageRun(compiled(EVERY_TYPE), padt_memory)
    for _ in range(40):
        assert run.cycle() == ("", "")
        run.compare()
    main = run.viewed.programs[0].instance
    assert (main.s8, main.u64, main.c) == (35, 40 * 0x1234_5678_9ABC, 1)
    assert main.name == "abababab" and main.wide == "ab"
    assert main.pts[1].tag == "xyxy" and main.counters[0].n == 120


def test_an_sfc_chart_goes_round_alike(padt_memory: ModuleType) -> None:
    # the template's Batch: steps, their times, the actions' control blocks
    sequence = REPO / "backend" / "projects" / "templates" / "sequence"
    text = "\n".join(path.read_text() for path in sorted(sequence.glob("*.st")))
    run = ImageRun(compiled(text), padt_memory)
    seen = set()
    for _ in range(120):
        assert run.cycle() == ("", "")
        run.compare()
        batch = run.viewed.programs[0].instance
        seen |= {step for step in ("Idle", "Fill", "Heat", "Drain") if getattr(batch, step).X}
    assert seen == {"Idle", "Fill", "Heat", "Drain"} and batch.batches >= 1


@pytest.mark.parametrize(
    ("name", "value", "refused"),
    [
        ("b", 1, "BOOL cannot hold 1"),
        ("i16", 40000, "outside the range"),
        ("i16", True, "an integer type cannot hold True"),
        ("u64", -1, "outside the range"),
        ("u64", 2**64, "outside the range"),
        ("r", 0.1, "rounded to 32 bits"),
        ("lr", 1, "REAL or LREAL cannot hold 1"),
        ("name", "123456789", "longer than the variable's 8 characters"),
        ("name", "€", "a character beyond one byte"),
        ("wide", "😀", "a character beyond two bytes"),
        ("pts", [1, 2], "an array of 3 elements cannot take 2"),
        ("grid", [1, 2, 3, 4, 5, "6"], "an integer type cannot hold '6'"),
    ],
)
def test_a_view_refuses_what_a_slot_is_never_given_and_keeps_its_value(
    padt_memory: ModuleType, name: str, value: object, refused: str
) -> None:
    run = ImageRun(compiled(EVERY_TYPE), padt_memory)
    main = run.viewed.programs[0].instance
    before = values(getattr(main, name))
    with pytest.raises((TypeError, ValueError, OverflowError), match=refused):
        setattr(main, name, value)
    assert values(getattr(main, name)) == before


def test_arrays_copy_as_lists_structures_whole_and_the_members_are_listed(
    padt_memory: ModuleType,
) -> None:
    run = ImageRun(compiled(EVERY_TYPE), padt_memory)
    main = run.viewed.programs[0].instance
    main.grid[4] = 9
    grid = copy.deepcopy(main.grid)
    assert grid == [0, 0, 0, 0, 9, 0] and type(grid) is list and main.grid == grid
    detached = copy.deepcopy(main.pts[2])
    detached.x, detached.tag = 7, "ok"
    assert main.pts[2].x == 0  # a copy: the image keeps its value
    main.pts[0] = detached  # a structure assigned whole
    assert (main.pts[0].x, main.pts[0].tag) == (7, "ok")
    # an object of the structure's own class (what a FUNCTION's Python gives) assigned
    # whole: its members written; one the variable cannot hold leaves the bytes as they were
    made = run.objects.image.classes()["STRUCT_PT"]()
    made.x, made.tag = 11, "new"
    main.pts[1] = made
    assert (main.pts[1].x, main.pts[1].y, main.pts[1].tag) == (11, 0.0, "new")
    made.x, made.tag = 12, 3
    with pytest.raises(TypeError, match="cannot hold 3"):
        main.pts[1] = made
    assert (main.pts[1].x, main.pts[1].tag) == (11, "new")
    assert type(main).__slots__[:3] == ("b", "s8", "u8")
    main.lr = math.nan
    assert math.isnan(main.lr)
    with pytest.raises(IndexError):
        main.grid[6] = 1
