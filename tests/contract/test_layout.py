"""Layouts in native memory (runtime/contract/layout.py, issue 34 step 5): each kind of
variable at the offset and size the C ABI gives it, a derived block beginning with its
base's members, the image of a configuration in its order, the refusals of what cannot be
laid out, and a C compiler holding the layout to its word (a wrong offset fails the
build). Every unit of the corpus and of the repository's programs gets a layout too
(tests/contract/test_generated_code.py)."""

from __future__ import annotations

from dataclasses import replace

import pytest

from backend.compiler.pipeline import compile_sources
from backend.compiler.source import SourceFile
from runtime.contract.artifact import Artifact, PouCode, ProgramConfig, VarInfo
from runtime.contract.layout import (
    Bound,
    Chars,
    Elements,
    Handle,
    LayoutRefused,
    Nested,
    Offset,
    Scalar,
    Slice,
    class_layouts,
    image_layout,
    runtime_layouts,
)
from tests.support.c_structs import compile_errors, struct_source

EVERY_KIND = """\
TYPE Color : (Red, Green, Blue); END_TYPE
TYPE Pt : STRUCT x : INT; y : LREAL; END_STRUCT; END_TYPE
INTERFACE IRun END_INTERFACE
FUNCTION_BLOCK Motor IMPLEMENTS IRun
VAR_INPUT on : BOOL; END_VAR
END_FUNCTION_BLOCK
FUNCTION_BLOCK FastMotor EXTENDS Motor
END_FUNCTION_BLOCK
FUNCTION_BLOCK Sum
VAR_IN_OUT a : ARRAY[*] OF INT; m : Motor; p : Pt; n : INT; total : Sum2; END_VAR
VAR_OUTPUT s : DINT; END_VAR
s := a[LOWER_BOUND(a, 1)] + n;
END_FUNCTION_BLOCK
FUNCTION_BLOCK Sum2
VAR_INPUT x : DINT; END_VAR
END_FUNCTION_BLOCK
PROGRAM Main
VAR
  b : BOOL; big : ULINT; t : TIME; f : REAL; c : Color := Blue;
  name : STRING[10]; wide : WSTRING[3]; ch : CHAR;
  r : REF_TO INT; i : IRun; motors : ARRAY[1..2] OF Motor;
  grid : ARRAY[1..2, 0..1] OF ARRAY[1..3] OF BOOL; pt : Pt; sum : Sum; q : ARRAY[1..3] OF INT;
  s2 : Sum2;
END_VAR
sum(a := q, m := motors[1], p := pt, n := q[1], total := s2);
END_PROGRAM
"""


def compiled(text: str, programs: list[ProgramConfig] | None = None) -> Artifact:
    result = compile_sources([SourceFile("t.st", text)], programs=programs)
    assert result.artifact is not None, [str(d) for d in result.diagnostics]
    return result.artifact


def shapes_and_offsets(artifact: Artifact, cls: str) -> dict[str, tuple[object, int, int]]:
    layout = class_layouts(artifact.units())[cls]
    return {m.name: (m.shape, m.offset, m.size) for m in layout.members}


def test_each_kind_of_variable_has_its_c_type_size_and_alignment() -> None:
    artifact = compiled(EVERY_KIND)
    main = shapes_and_offsets(artifact, "POU_MAIN")
    assert main["b"] == (Scalar("?"), 0, 1)
    assert main["big"] == (Scalar("Q"), 8, 8)  # ULINT: aligned to 8 after the BOOL
    assert main["t"] == (Scalar("q"), 16, 8)  # TIME: 64 bits of nanoseconds
    assert main["f"] == (Scalar("f"), 24, 4)
    assert main["c"] == (Scalar("q"), 32, 8)  # an enumeration: a 64-bit integer
    # a length and 11 characters of one byte: 13, rounded to the length's alignment
    assert main["name"] == (Chars(10, wide=False), 40, 14)
    assert main["wide"] == (Chars(3, wide=True), 54, 10)
    assert main["ch"] == (Chars(1, wide=False), 64, 4)
    assert main["r"] == (Offset(), 68, 4)
    assert main["i"] == (Handle(), 72, 8)
    motors, offset, size = main["motors"]
    assert motors == Elements(Nested("POU_MOTOR"), 2) and (offset, size) == (80, 4)
    assert main["grid"][0] == Elements(Elements(Scalar("?"), 3), 4)
    assert main["grid"][2] == 12
    assert main["pt"][0] == Nested("STRUCT_PT") and main["pt"][1] % 8 == 0
    sum_block = shapes_and_offsets(artifact, "POU_SUM")
    # in-outs: an open array, a block another extends (a derived one may come), a structure
    # and a block nobody extends referred to; an elementary one is copied in and out, so it
    # is the value itself
    assert sum_block["a"] == (Slice(Scalar("h"), 1), 0, 24)
    assert sum_block["m"] == (Handle(), 24, 8)
    # where a call bound it, then one of its own (aligned)
    assert sum_block["p"] == (Bound(Nested("STRUCT_PT")), 32, 24)
    assert sum_block["n"] == (Scalar("h"), 56, 2)
    assert sum_block["total"] == (Bound(Nested("POU_SUM2")), 60, 12)
    point = class_layouts(artifact.units())["STRUCT_PT"]
    assert (point.size, point.align) == (16, 8)


def test_sfc_steps_and_action_control_blocks_are_the_runtimes_classes() -> None:
    artifact = compiled(
        "PROGRAM Main\nVAR go : BOOL; END_VAR\nINITIAL_STEP Idle : Lamp(N); END_STEP\n"
        "STEP Run : END_STEP\nTRANSITION FROM Idle TO Run := go; END_TRANSITION\n"
        "TRANSITION FROM Run TO Idle := NOT go; END_TRANSITION\n"
        "ACTION Lamp : go := go; END_ACTION\nEND_PROGRAM\n"
    )
    layouts = class_layouts(artifact.units())
    main = shapes_and_offsets(artifact, "POU_MAIN")
    idle = main["Idle"][0]
    assert isinstance(idle, Nested)
    step = layouts[idle.cls]
    assert [(m.name, m.offset) for m in step.members] == [("X", 0), ("T", 8), ("since", 16)]
    assert main["_ac_LAMP"][0] == Nested("_ActionControl")
    assert layouts["_ActionControl"].size == 56


def test_a_derived_block_begins_with_its_bases_members_at_the_same_offsets() -> None:
    artifact = compiled(
        "FUNCTION_BLOCK Base\nVAR_INPUT step : INT; END_VAR\nVAR_OUTPUT n : LINT; END_VAR\n"
        "n := n + step;\nEND_FUNCTION_BLOCK\n"
        "FUNCTION_BLOCK Mid EXTENDS Base\nVAR m : BOOL; END_VAR\nSUPER^();\n"
        "END_FUNCTION_BLOCK\n"
        "FUNCTION_BLOCK Top EXTENDS Mid\nVAR t : INT; END_VAR\nSUPER^();\nEND_FUNCTION_BLOCK\n"
        "PROGRAM Main\nVAR x : Top; END_VAR\nx();\nEND_PROGRAM\n"
    )
    layouts = class_layouts(artifact.units())
    base, mid, top = (layouts[f"POU_{n}"] for n in ("BASE", "MID", "TOP"))
    assert mid.members[: len(base.members)] == base.members
    assert top.members[: len(mid.members)] == mid.members
    assert [m.name for m in top.members][len(mid.members) :] == ["t"]


def test_the_image_holds_the_header_globals_programs_and_their_copies_in_order() -> None:
    text = (
        "VAR_GLOBAL g : INT; END_VAR\n"
        "PROGRAM Fast\nVAR_EXTERNAL g : INT; END_VAR\ng := g + 1;\nEND_PROGRAM\n"
        "PROGRAM Slow\nVAR x : LREAL; END_VAR\nx := 1.0;\nEND_PROGRAM\n"
        "PROGRAM Helper\nVAR y : BOOL; END_VAR\ny := TRUE;\nEND_PROGRAM\n"
    )
    programs = [ProgramConfig("S", "Slow", 2, priority=1), ProgramConfig("F", "Fast", 7)]
    artifact = compiled(text, programs)
    layouts = class_layouts(artifact.units())
    image = image_layout(artifact, layouts)
    assert [(p.name, p.cls) for p in image.placements] == [
        ("_SYS", "_SYS"),
        ("_G", "GLOBALS"),
        ("F", "POU_FAST"),  # priority 0 first
        ("S", "POU_SLOW"),
        ("_P.Helper", "POU_HELPER"),  # a PROGRAM no user program runs
        ("F._G", "GLOBALS"),  # two programs: each its own view of the globals
        ("S._G", "GLOBALS"),
    ]
    header = runtime_layouts()["_SYS"]
    assert image.placements[1].offset == header.size  # nothing of a program at offset 0
    for placement in image.placements:
        assert placement.offset % {**layouts, **runtime_layouts()}[placement.cls].align == 0
    assert image.size % 8 == 0 and image.size >= image.placements[-1].offset + 2
    lone = compiled("PROGRAM Main\nVAR\nEND_VAR\nEND_PROGRAM\n")
    alone = class_layouts(lone.units())
    assert alone["GLOBALS"].size == 1  # a class without slots takes a byte
    assert [p.name for p in image_layout(lone, alone).placements] == ["_SYS", "_G", "Main"]


def with_variable_type(artifact: Artifact, cls: str, attr: str, type_name: str) -> Artifact:
    """`artifact` with the declared type of one variable changed (as a crafted one may)."""

    def changed(variable: VarInfo) -> VarInfo:
        return replace(variable, type=type_name) if variable.attr == attr else variable

    def unit_of(pou: PouCode) -> PouCode:
        if pou.class_name != cls:
            return pou
        return replace(pou, variables=tuple(changed(v) for v in pou.variables))

    return replace(
        artifact,
        pous=tuple(unit_of(p) for p in artifact.pous),
        types=tuple(unit_of(t) for t in artifact.types),
    )


@pytest.mark.parametrize(
    ("type_name", "refused"),
    [
        ("Pt", "class STRUCT_PT holds itself"),
        ("NoSuchType", "STRUCT_PT.y: no layout for the type NoSuchType"),
        ("ARRAY[0..1000000000] OF Pt", "STRUCT_PT.y: class STRUCT_PT holds itself"),
        ("ARRAY[0..1000000000] OF LINT", "class STRUCT_PT passes 4 GiB at y"),
        ("ARRAY[0..x] OF INT", "bounds that are no integers"),
    ],
)
def test_what_cannot_be_laid_out_is_refused_with_the_reason(type_name: str, refused: str) -> None:
    artifact = compiled(EVERY_KIND)
    # y starts as 0.0: a named type of a variable that starts as an integer is taken for an
    # enumeration (a 64-bit integer, as the Python tier holds it)
    crafted = with_variable_type(artifact, "STRUCT_PT", "y", type_name)
    with pytest.raises(LayoutRefused, match=refused.replace("[", r"\[")):
        class_layouts(crafted.units())


def test_a_c_compiler_lays_the_structs_out_so_and_refuses_a_wrong_offset() -> None:
    artifact = compiled(EVERY_KIND)
    layouts = class_layouts(artifact.units())
    assert compile_errors(struct_source([layouts])) == ""
    sum_block = layouts["POU_SUM"]
    shifted = (sum_block.members[0], replace(sum_block.members[1], offset=28))
    wrong = {**layouts, "POU_SUM": replace(sum_block, members=shifted + sum_block.members[2:])}
    assert 'static assertion failed: "POU_SUM.m"' in compile_errors(struct_source([wrong]))
