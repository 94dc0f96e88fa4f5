"""The switch of a configuration's values into its memory image and back
(runtime/image_switch.py; issue 34 step 5, not yet called by the runtime): a running
resource's values moved into the image between two cycles and its programs run on, every
value after every cycle that of a twin on objects; values written, the context taken and
restored through the image; back to objects, the same again."""

from __future__ import annotations

from hypothesis import HealthCheck, given, settings

from runtime.code.native.image_plan import ImagePlan, plan_image
from runtime.code.native.tier import NativeTier
from runtime.contract.artifact import Artifact, ProgramConfig
from runtime.image_memory import ImageMemory
from runtime.image_switch import enter_image, leave_image
from runtime.memory import ObjectMemory
from runtime.resource import Resource
from runtime.restart import take_context, warm_start
from tests.compiler.test_differential import CYCLES, programs
from tests.runtime.native.test_image_memory import TWO_PROGRAMS
from tests.runtime.native.test_image_views import EVERY_TYPE
from tests.support.native_runs import Pair, compiled, running, same


def planned(resource: Resource, tier: NativeTier) -> ImagePlan:
    code = resource.variables.code
    assert code is not None and resource.artifact is not None and tier.toolchain is not None
    plan = plan_image(resource.artifact, code.classes(), tier.cache, tier.toolchain)
    assert isinstance(plan, ImagePlan), plan
    return plan


def twins(artifact: Artifact) -> Pair:
    """Two resources of the Python tier: `python` stays on objects, `native` is switched."""
    return Pair(running(artifact, None), running(artifact, None))


def test_values_go_into_the_image_and_back_and_the_programs_run_on(
    native_tier: NativeTier,
) -> None:
    configs = [ProgramConfig("Fill", "Fill", 1), ProgramConfig("Watch", "Watch", 2)]
    for text, config in ((TWO_PROGRAMS, configs), (EVERY_TYPE, None)):
        pair = twins(compiled(text, config))
        pair.cycle_and_compare(3)
        switched = pair.native.variables
        bound_before = switched.bound
        plan = planned(pair.native, native_tier)
        enter_image(switched, plan)
        assert isinstance(switched.memory, ImageMemory) and switched.bound is not bound_before
        assert all(isinstance(p.instance, plan.memory.View) for p in switched.programs)
        pair.cycle_and_compare(5)
        for twin in (pair.python, pair.native):  # a write from outside, into the image
            path = "level" if config else "Main.i16"
            twin.variables.store(twin.variables.lookup(path), 1234)
        pair.cycle_and_compare(2)
        context, expected = take_context(pair.native), take_context(pair.python)
        assert context is not None and expected is not None
        assert context.programs == expected.programs and context.globals == expected.globals
        leave_image(switched)
        assert isinstance(switched.memory, ObjectMemory)
        assert not any(isinstance(p.instance, plan.memory.View) for p in switched.programs)
        pair.cycle_and_compare(5)


def test_a_context_taken_in_the_image_warm_starts_a_resource_on_objects(
    native_tier: NativeTier,
) -> None:
    artifact = compiled(EVERY_TYPE)
    pair = twins(artifact)
    enter_image(pair.native.variables, planned(pair.native, native_tier))
    pair.cycle_and_compare(4)
    context = take_context(pair.native)
    assert context is not None
    fresh = running(artifact, None)
    fresh.stop()
    warm_start(fresh, context)
    assert all(
        same(value, fresh.variables.values()[path])
        for path, value in pair.native.variables.values().items()
    )


@settings(
    max_examples=8,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
@given(programs())
def test_random_programs_run_on_after_the_switch(native_tier: NativeTier, program: str) -> None:
    pair = twins(compiled(program))
    pair.cycle_and_compare(1)
    enter_image(pair.native.variables, planned(pair.native, native_tier))
    pair.cycle_and_compare(CYCLES)
