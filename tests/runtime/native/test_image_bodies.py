"""Bodies in image mode (runtime/code/native/image_body.py; issue 34, step 5): the C of a
body reads and writes its variables in a memory image at the layouts' offsets. Run side by
side with the Python tier on slot objects: every value equal after every cycle, the same
faults at the same ST lines (the compiler's random programs, every elementary type with
strings and arrays of structures and blocks, the peers' benchmark program), and what image
mode does not do yet left to Python with its reason, running on views."""

from __future__ import annotations

from types import ModuleType

from hypothesis import HealthCheck, given, settings

from runtime.code.native.tier import NativeTier
from tests.compiler.test_differential import CYCLES, programs
from tests.runtime.native.test_image_views import EVERY_TYPE
from tests.support.corpus_paths import SHARED, shared_dir
from tests.support.image_runs import ImageRun, compiled, with_c_bodies


def side_by_side(
    text: str, memory: ModuleType, tier: NativeTier
) -> tuple[ImageRun, list[tuple[str, str]]]:
    run = ImageRun(compiled(text), memory)
    return run, with_c_bodies(run, tier)


def run_alike(run: ImageRun, cycles: int) -> str:
    """Both sides for `cycles` cycles, compared after each; the fault that ended them."""
    for _ in range(cycles):
        on_objects, in_image = run.cycle()
        assert on_objects == in_image
        run.compare()
        if on_objects:
            return on_objects
    return ""


@settings(
    max_examples=12,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
@given(programs())
def test_random_programs_in_the_image_as_on_objects(
    padt_memory: ModuleType, native_tier: NativeTier, program: str
) -> None:
    run, left = side_by_side(program, padt_memory, native_tier)
    assert not [body for body, _ in left if body.startswith("POU_ACC")]  # the block is C
    run_alike(run, CYCLES)


def test_every_elementary_type_strings_arrays_of_structures_and_blocks_as_c(
    padt_memory: ModuleType, native_tier: NativeTier
) -> None:
    run, left = side_by_side(EVERY_TYPE, padt_memory, native_tier)
    assert left == []
    assert run_alike(run, 40) == ""
    main = run.viewed.programs[0].instance
    assert main.name == "abababab" and main.counters[0].n == 120


def test_a_fault_in_the_image_is_the_pythons_at_the_same_st_line(
    padt_memory: ModuleType, native_tier: NativeTier
) -> None:
    text = """
PROGRAM Main
VAR d : INT := 3; q : INT; a : ARRAY[1..4] OF DINT; i : INT := 2; END_VAR
d := d - 1;
a[i] := a[i] + 1;
q := 100 / d;
i := i + 1;
END_PROGRAM
"""
    run, left = side_by_side(text, padt_memory, native_tier)
    assert left == []
    fault = run_alike(run, 10)
    assert fault.startswith("DivisionByZero") and "(prog.st:6)" in fault, fault
    text = text.replace("q := 100 / d;", "q := 100;").replace("i := i + 1;", "i := i + 2;")
    run, left = side_by_side(text, padt_memory, native_tier)
    assert "index" in run_alike(run, 10) and left == []


def test_what_image_mode_does_not_do_yet_runs_as_python_on_views(
    padt_memory: ModuleType, native_tier: NativeTier
) -> None:
    text = """
FUNCTION_BLOCK Counter
VAR_OUTPUT n : INT; END_VAR
METHOD PUBLIC Bump : INT
n := n + 1;
Bump := n;
END_METHOD
n := n + 10;
END_FUNCTION_BLOCK
PROGRAM Main
VAR c : Counter; k : INT; END_VAR
c();
k := c.Bump();
END_PROGRAM
"""
    run, left = side_by_side(text, padt_memory, native_tier)
    assert [(body, "M__BUMP" in why) for body, why in left] == [("POU_MAIN.__call__", True)], left
    run_alike(run, 5)
    assert run.viewed.programs[0].instance.k == 55


def test_the_benchmark_program_in_the_image_as_on_objects(
    padt_memory: ModuleType, native_tier: NativeTier
) -> None:
    peers = shared_dir(SHARED / "peers")
    for name in ("bench.st", "bench_noton.st"):
        run, left = side_by_side((peers / name).read_text(), padt_memory, native_tier)
        assert left == []
        assert run_alike(run, 100) == ""
