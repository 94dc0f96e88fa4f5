"""The memory an artifact's forms make a runtime allocate is counted before anything is
allocated: counts that multiply (lists of lists, arrays of instances of classes holding
arrays) beyond what any resource the compiler accepts allocates refuse the artifact,
and the largest data the compiler accepts loads."""

from __future__ import annotations

from dataclasses import replace

import pytest

from backend.compiler.pipeline import compile_sources
from backend.compiler.source import SourceFile
from runtime.contract.artifact import Artifact, ArtifactError, PouCode, crc32_hex, load_artifact
from runtime.contract.code.form_json import encode_unit
from runtime.contract.code.form_size import MAX_CELLS
from runtime.contract.code.statements import Assign
from runtime.contract.code.typed_form import Binary, Call, Const, Repeated, Sequence, Var
from runtime.contract.code.units import Class, Slot
from tests.support.crafted_units import first_in_body, memory_bomb

INT = "INT"
PROGRAM = """
FUNCTION_BLOCK Cell VAR_INPUT x : INT; END_VAR VAR y : INT; END_VAR y := x; END_FUNCTION_BLOCK
PROGRAM Main VAR c : Cell; n : INT; END_VAR c(x := n); END_PROGRAM
"""


def compiled(text: str = PROGRAM) -> Artifact:
    result = compile_sources([SourceFile("main.st", text)])
    assert result.artifact is not None, [str(d) for d in result.diagnostics]
    return result.artifact


def refusal(artifact: Artifact) -> str:
    with pytest.raises(ArtifactError) as refused:
        load_artifact(artifact.to_json())
    return str(refused.value)


def class_of(artifact: Artifact, pou: str) -> Class:
    unit = artifact.pou(pou).unit
    assert isinstance(unit, Class)
    return unit


def with_class(artifact: Artifact, pou: str, unit: Class) -> Artifact:
    """`artifact` whose POU `pou` is `unit`, every CRC redone."""
    form = encode_unit(unit)
    changed = replace(artifact.pou(pou), form=form, crc=crc32_hex(form))
    pous = tuple(changed if p.name == pou else p for p in artifact.pous)
    return replace(artifact, pous=pous).with_crc()


def with_slot(artifact: Artifact, pou: str, initial: Repeated | Call) -> Artifact:
    unit = class_of(artifact, pou)
    return with_class(artifact, pou, replace(unit, slots=(*unit.slots, Slot("extra", initial))))


def ints(count: int) -> Repeated:
    return Repeated(Const(0, INT), count, False, "")


def test_a_list_of_a_million_lists_of_a_million_values_is_refused_before_it_is_made() -> None:
    artifact = compiled()
    message = refusal(with_class(artifact, "Main", memory_bomb(class_of(artifact, "Main"))))
    assert message.startswith("Class POU_MAIN: an expression makes 1,000,00"), message
    assert message.endswith(f"cells or more; at most {MAX_CELLS:,}"), message


def test_instances_count_the_slots_of_their_class_however_deep() -> None:
    # each Cell holds a million INTs, Main a hundred Cells: each count within bounds, and
    # within what one expression makes, 10**8 cells together
    artifact = with_slot(compiled(), "Cell", ints(1_000_000))
    message = refusal(
        with_slot(artifact, "Main", Repeated(Call("POU_CELL", (), ""), 100, True, ""))
    )
    assert message.startswith("POU_MAIN: an instance makes 1"), message


def test_a_class_that_holds_an_instance_of_itself_is_refused() -> None:
    artifact = compiled()
    message = refusal(with_slot(artifact, "Main", Call("POU_MAIN", (), "")))
    assert "POU_MAIN: an instance holds an instance of its own class" in message, message


def test_an_expression_of_a_body_is_counted_as_it_runs() -> None:
    artifact = compiled()
    rows = Repeated(ints(10_000), 10_000, True, "")
    bomb = first_in_body(artifact, Assign(Var("x", "local", ""), rows, 1))
    assert "Class POU_CELL: an expression makes 100,010,000 cells or more" in refusal(bomb)


def test_a_list_or_text_repeated_by_a_number_is_refused() -> None:
    artifact = compiled()
    for repeated in (Sequence((Const(0, INT),), ""), Const("ab", "STRING")):
        times = Binary("*", repeated, Const(10**9, "DINT"), "")
        message = refusal(first_in_body(artifact, Assign(Var("x", "local", ""), times, 1)))
        assert "repeated by `*`" in message, message


def test_the_resource_counts_every_program_it_sets_up() -> None:
    # one POU of a million values, scheduled as nine user programs: each instance within
    # the limit, the resource beyond it
    artifact = compiled(
        "PROGRAM Main VAR a : ARRAY[1..990000] OF INT; END_VAR a[1] := 1; END_PROGRAM"
    )
    program = artifact.programs[0]
    nine = tuple(replace(program, name=f"P{n}", program_id=n + 1) for n in range(9))
    message = refusal(replace(artifact, programs=nine).with_crc())
    assert "the resource's instances make" in message, message


@pytest.mark.parametrize(
    "declarations",
    [
        "a : ARRAY[1..990000] OF INT;",
        "a : ARRAY[1..100000] OF TON;",
        "a : ARRAY[1..1000, 1..990] OF BOOL;",
        "a : ARRAY[1..240000] OF Pair;",
    ],
)
def test_the_largest_data_the_compiler_takes_loads(declarations: str) -> None:
    artifact = compiled(
        "TYPE Pair : STRUCT a : INT; b : REAL; c : BOOL; d : DINT; END_STRUCT; END_TYPE\n"
        f"PROGRAM Main VAR {declarations} END_VAR END_PROGRAM"
    )
    assert load_artifact(artifact.to_json()).crc == artifact.crc


def test_a_cycle_through_thousands_of_classes_is_found_without_recursion() -> None:
    artifact = compiled()
    count = 3_000
    chain = []
    for n in range(count):
        held = Call(f"STRUCT_S{(n + 1) % count}", (), "")
        form = encode_unit(Class(f"STRUCT_S{n}", (Slot("next", held),)))
        unit = PouCode(f"S{n}", "STRUCT", f"STRUCT_S{n}", form, crc32_hex(form), ())
        chain.append(unit)
    message = refusal(replace(artifact, types=tuple(chain)).with_crc())
    assert message.endswith(": an instance holds an instance of its own class"), message
