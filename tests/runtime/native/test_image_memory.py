"""`ImageMemory` (runtime/image_memory.py; issue 34 step 5): the services' one way to the
values of a configuration, over its memory image. Beside `ObjectMemory` over the Python
tier's objects, run alike: the same values read one by one and many at once, a global
stored everywhere the programs read it, the same context trees (what a warm start
restores, on either side), and a tree that does not fit refused with the image as it
was."""

from __future__ import annotations

from types import ModuleType

import pytest
from hypothesis import HealthCheck, given, settings

from runtime.context import Context, encode_context
from runtime.context_snapshot import ContextMismatch
from runtime.contract.artifact import ProgramConfig
from runtime.image_memory import ImageMemory
from runtime.memory import ObjectMemory, ValueTrees
from tests.compiler.test_differential import CYCLES, programs
from tests.runtime.native.test_image_views import EVERY_TYPE
from tests.support.image_runs import ImageRun, values
from tests.support.native_runs import compiled

TWO_PROGRAMS = """
VAR_GLOBAL level : INT; names : ARRAY[1..2] OF STRING[6]; END_VAR
PROGRAM Fill
VAR_EXTERNAL level : INT; names : ARRAY[1..2] OF STRING[6]; END_VAR
VAR n : DINT; END_VAR
level := level + 1; n := n + level; names[1] := 'full';
END_PROGRAM
PROGRAM Watch
VAR_EXTERNAL level : INT; END_VAR
VAR seen : INT; r : REAL := 1.5; END_VAR
seen := level; r := r * 2.0;
END_PROGRAM
"""


def memories(run: ImageRun) -> tuple[ObjectMemory, ImageMemory]:
    names = [program.name for program in run.viewed.programs]
    image = ImageMemory(run.image, run.layouts, run.placement, run.class_names, names)
    return ObjectMemory(run.objects.globals, run.objects.programs), image


def same_reads(run: ImageRun) -> None:
    on_objects, in_image = memories(run)
    assert values(on_objects.reader(run.objects.bound)()) == values(
        in_image.reader(run.viewed.bound)()
    )
    for objects_bound, image_bound in zip(run.objects.bound, run.viewed.bound, strict=True):
        assert values(on_objects.read(objects_bound)) == values(in_image.read(image_bound))
        # a reader of one variable (a text or an array alone: no elementary value at all)
        alone = in_image.reader([image_bound])()
        assert values(on_objects.reader([objects_bound])()) == values(alone)
    assert on_objects.reader([])() == in_image.reader([])() == []  # what an empty watch reads
    assert on_objects.take() == in_image.take()


@settings(
    max_examples=10,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
@given(programs())
def test_random_programs_read_alike_from_objects_and_the_image(
    padt_memory: ModuleType, program: str
) -> None:
    run = ImageRun(compiled(program), padt_memory)
    for _ in range(CYCLES):
        faults = run.cycle()
        same_reads(run)
        if faults[0]:
            break


def test_every_type_and_two_programs_read_stored_and_restored_alike(
    padt_memory: ModuleType,
) -> None:
    for text, configs in (
        (EVERY_TYPE, None),
        (TWO_PROGRAMS, [ProgramConfig("Fill", "Fill", 1), ProgramConfig("Watch", "Watch", 2)]),
    ):
        run = ImageRun(compiled(text, configs), padt_memory)
        for _ in range(5):
            run.cycle()
        same_reads(run)
        on_objects, in_image = memories(run)
        for objects_bound, image_bound in zip(run.objects.bound, run.viewed.bound, strict=True):
            if objects_bound.path.path in ("level", "Main.i16", "Main.name"):
                value = {"level": 7, "Main.i16": -3, "Main.name": "neu"}[objects_bound.path.path]
                on_objects.store(objects_bound, value)
                in_image.store(image_bound, value)
        same_reads(run)
        # a warm start: the objects' trees into a fresh image of the same configuration
        fresh = ImageRun(compiled(text, configs), padt_memory)
        _, fresh_image = memories(fresh)
        fresh_image.restore(on_objects.take())
        assert fresh_image.take() == on_objects.take()


def encoded(trees: ValueTrees) -> bytes:
    programs = {name: {"values": tree} for name, tree in trees.programs.items()}
    return encode_context(Context("00", 0, {}, programs, trees.globals))


def test_the_periodic_save_copies_the_image_and_builds_its_trees_when_encoded(
    padt_memory: ModuleType,
) -> None:
    two = [ProgramConfig("Fill", "Fill", 1), ProgramConfig("Watch", "Watch", 2)]
    # EVERY_TYPE: arrays of structures with a text (as trees) and of blocks (as rows)
    for text, configs in ((EVERY_TYPE, None), (TWO_PROGRAMS, two)):
        run = ImageRun(compiled(text, configs), padt_memory)
        for _ in range(3):
            run.cycle()
        on_objects, in_image = memories(run)
        taken = in_image.take(deferred=True)  # the cycle thread's share: a copy of the bytes
        expected = encoded(in_image.take())
        assert encoded(on_objects.take(deferred=True)) == expected
        run.cycle()  # what the programs change after the take is not in it
        assert encoded(taken) == expected != encoded(in_image.take())


def test_a_tree_that_does_not_fit_is_refused_and_the_image_kept(padt_memory: ModuleType) -> None:
    run = ImageRun(compiled(EVERY_TYPE), padt_memory)
    run.cycle()
    _, in_image = memories(run)
    trees = in_image.take()
    before = bytes(run.image)
    main = trees.programs["Main"]
    for change, refused in (
        ({"i16": "7"}, "expected a whole number"),
        ({"b": 1}, "expected TRUE or FALSE"),
        ({"i16": 40_000}, "i16"),
        ({"name": "123456789"}, "name"),
        ({"grid": [1, 2]}, "expected an array of 6"),
        ({"unknown": 1}, "fields differ"),
    ):
        changed = {**main, "v": {**main["v"], **change}}
        with pytest.raises(ContextMismatch, match=refused):
            in_image.restore(ValueTrees(trees.globals, {"Main": changed}))
        assert bytes(run.image) == before
