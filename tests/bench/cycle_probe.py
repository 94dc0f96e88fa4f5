"""The CPU cycle of one code base, measured in a process of its own: run as a script with
that code base (this one, or a baseline checkout) first on PYTHONPATH, it reads a request
as JSON on stdin and prints the figures as JSON on stdout.

It uses only what every version of the project since the artifact's version 3 has
(`compile_sources`, `Resource`, the two clocks), so that `make bench` can print a figure of
today's code beside the same figure of an older commit, measured in the same run.

Request: {"program": ST text, "cycles": n, "check_cycles": m, "fixed_cycles": f,
"fixed_native_cache": folder,
"native_cache": folder, "image_cache": folder, "state_variables": v, "reload": r,
"state_native_cache": folder}, each part
left out when empty or 0; with
`native_cache` (today's code only) the program runs on the native tier, its modules
compiled into that folder; with `image_cache` (today's code only) its body is timed alone
as image-mode C too (`image_body`).
Reply: {"program_us": median us per cycle of the program (virtual clock), "values": every
variable after `check_cycles` cycles, "fixed_us": median us per cycle of a resource with one
empty program (real clock; with `fixed_native_cache`, today's code only, on the native tier,
its usual cycle in C), "native_build_s": how long the native bodies took to be in
place, "native_bodies": the POUs that run as C, "image_body_us", "image_build_s",
"image_left": `image_body`'s figures, "read_ms", "values_ms", "take_ms",
"save_ms", "pause_ms": for a resource of `state_variables` variables (`scale_source`), the
best of a few rounds of reading every value (the online test's `values`: the read on the
cycle thread, and the whole read with the values built), taking the periodic context
(cycle thread), encoding and saving it (saver thread), and with `reload` the pause of a
reload of its small program; with `state_native_cache` (today's code only) the same on the
native tier, the values in the memory image, and "leave_ms", "enter_ms": the moves of the
values out of the image and back in}. The state figures take what every version since the
issue 34 baseline (tests/bench/baseline.py) has.
"""

from __future__ import annotations

import json
import statistics
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from backend.compiler.pipeline import compile_sources
from backend.compiler.source import SourceFile
from runtime.clock import RealClock, VirtualClock
from runtime.context import save_context
from runtime.contract.artifact import ProgramConfig, ResourceConfig
from runtime.reload_switch import reload
from runtime.resource import Resource
from runtime.restart import take_context

CYCLE_NS = 100_000_000
EMPTY = "PROGRAM Empty\nEND_PROGRAM\n"
BEST_OF = 3  # rounds of `best_ms`
STATE_ROUNDS = 7  # rounds of each state figure: each is short beside the process's compile


def _running(
    text: str,
    clock: Any,
    programs: list[ProgramConfig] | None = None,
    native_cache: str = "",
    reply: dict[str, Any] | None = None,
) -> Resource:
    # a long watchdog: a shared machine's stall must not stop the resource mid-measurement
    config = ResourceConfig(name="R", watchdog_ms=5_000, safety_time_ms=10_000)
    result = compile_sources([SourceFile("bench.st", text)], resource=config, programs=programs)
    assert result.artifact is not None, [str(d) for d in result.diagnostics]
    resource = Resource("R", clock)
    if native_cache:
        from runtime.code.native.tier import NativeTier  # today's code only

        resource.native = NativeTier(Path(native_cache))
    started = time.perf_counter()
    resource.load(result.artifact)
    if native_cache and reply is not None:
        resource.tier_up(wait=True)
        reply["native_build_s"] = time.perf_counter() - started
        code = resource.variables.code
        reply["native_bodies"] = list(code.native.bodies) if code and code.native else []
    resource.start()
    return resource


def _median_us(cycle: Any, cycles: int) -> float:
    samples = []
    for _ in range(cycles):
        started = time.perf_counter_ns()
        cycle()
        samples.append(time.perf_counter_ns() - started)
    return statistics.median(samples) / 1000


def program_cycles(
    text: str, cycles: int, check_cycles: int, native_cache: str, reply: dict[str, Any]
) -> tuple[float, dict[str, Any]]:
    clock = VirtualClock()
    resource = _running(text, clock, native_cache=native_cache, reply=reply)

    def cycle() -> None:
        resource.cycle()
        clock.advance(CYCLE_NS)

    for _ in range(check_cycles):  # the same work on both sides, compared by value
        cycle()
    values = resource.variables.values()
    return _median_us(cycle, cycles), values


def image_body(text: str, cycles: int, cache: str, reply: dict[str, Any]) -> None:
    """The program's body as image-mode C on a memory image beside the Python tier's
    objects: the time it takes to translate,
    build and put the bodies in place into `cache`, what stays Python, and the median
    time of the body alone per cycle (no cycle around it: the fixed cost of a cycle adds
    to it once it runs in the runtime)."""
    from runtime.code.native.image_views import memory_module  # today's code only
    from runtime.code.native.tier import NativeTier
    from tests.support.image_runs import ImageRun, compiled, with_c_bodies

    tier = NativeTier(Path(cache))
    assert tier.toolchain is not None
    run = ImageRun(compiled(text), memory_module(tier.cache, tier.toolchain))
    started = time.perf_counter()
    reply["image_left"] = with_c_bodies(run, tier)
    reply["image_build_s"] = time.perf_counter() - started
    program = run.viewed.programs[0]

    def body() -> None:
        run.system.now_ns += CYCLE_NS
        run.viewed.image.use(program.view, None)
        program.instance.__call__()

    reply["image_body_us"] = _median_us(body, cycles)


def fixed_cycles(cycles: int, native_cache: str = "") -> float:
    """The median CPU cycle of a resource with one empty program on a real clock; with
    `native_cache` (today's code only), on the native tier, whose usual cycle is C."""
    program = ProgramConfig(name="Empty", pou="Empty", program_id=1)
    resource = _running(EMPTY, RealClock(), [program], native_cache=native_cache, reply={})
    for _ in range(1_000):  # caches, the watchdog thread waking up
        resource.cycle()
    return _median_us(resource.cycle, cycles)


def scale_source(variables: int, step: int = 1) -> str:
    """`variables` elementary variables: an array of structures of five members in the
    globals, and a small program that changes some of them every cycle."""
    points = variables // 5
    return "\n".join(
        [
            "TYPE Point : STRUCT x, y : REAL; n : DINT; ok : BOOL; t : TIME; END_STRUCT; END_TYPE",
            f"VAR_GLOBAL points : ARRAY[1..{points}] OF Point; END_VAR",
            "PROGRAM Small",
            "VAR i, k : DINT; END_VAR",
            f"k := k + {step};",
            "FOR i := 1 TO 100 DO points[(k + i) MOD "
            f"{points} + 1].n := k; points[i].x := DINT_TO_REAL(k); END_FOR;",
            "END_PROGRAM",
        ]
    )


def best_ms(work: Callable[[], object], rounds: int = BEST_OF) -> float:
    """The best of `rounds` runs of `work`, in milliseconds."""
    times = []
    for _ in range(rounds):
        started = time.perf_counter()
        work()
        times.append(time.perf_counter() - started)
    return min(times) * 1000


def state_figures(variables: int, reloads: bool, native_cache: str = "") -> dict[str, float]:
    config = ResourceConfig(name="R", target_cycle_ms=10, watchdog_ms=60_000)
    program = [ProgramConfig("Small", "Small", 1)]
    artifacts = []
    for step in (1, 2) if reloads else (1,):  # the second: the reload's
        text = scale_source(variables, step)
        result = compile_sources([SourceFile("scale.st", text)], resource=config, programs=program)
        assert result.artifact is not None, [str(d) for d in result.diagnostics]
        artifacts.append(result.artifact)
    resource = Resource("R", VirtualClock())
    figures: dict[str, float] = {}
    if native_cache:
        from runtime.code.native.tier import NativeTier  # today's code only

        resource.native = NativeTier(Path(native_cache))
    resource.load(artifacts[0])
    if native_cache:
        resource.tier_up(wait=True)
        figures.update(image_moves(resource))
    resource.start()
    for _ in range(20):  # past Python's warm-up of new code
        resource.cycle()
    figures["read_ms"] = best_ms(resource.variables.read_values, STATE_ROUNDS)
    figures["values_ms"] = best_ms(resource.variables.values, STATE_ROUNDS)
    figures["take_ms"] = best_ms(lambda: take_context(resource, deferred=True), STATE_ROUNDS)
    context = take_context(resource, deferred=True)
    assert context is not None
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "context"
        figures["save_ms"] = best_ms(lambda: save_context(path, context), STATE_ROUNDS)
    if reloads:
        pauses = []
        for n in range(STATE_ROUNDS):  # to the other version and back
            pauses.append(reload(resource, artifacts[(n + 1) % 2], {}).pause_us / 1000)
            for _ in range(20):
                resource.cycle()
                resource.tier_up(wait=True)  # a reload's values back into the image
        figures["pause_ms"] = min(pauses)
    return figures


def image_moves(resource: Resource) -> dict[str, float]:
    """With the values in the memory image: how long the cycle thread takes to move them
    out to objects (as a reload's job and the debugger begin) and back in (the next
    `tier_up`), the best of a few rounds each."""
    from runtime.image_switch import enter_image, leave_image  # today's code only

    variables = resource.variables
    code = variables.code
    assert variables.image is not None and code is not None and code.image is not None
    leave, enter = [], []
    for _ in range(STATE_ROUNDS):
        started = time.perf_counter()
        leave_image(variables)
        left = time.perf_counter()
        enter_image(variables, code.image)
        leave.append(left - started)
        enter.append(time.perf_counter() - left)
    return {"leave_ms": min(leave) * 1000, "enter_ms": min(enter) * 1000}


def main() -> None:
    request = json.load(sys.stdin)
    reply: dict[str, Any] = {}
    if request.get("program"):
        program_us, values = program_cycles(
            request["program"],
            request["cycles"],
            request["check_cycles"],
            request.get("native_cache", ""),
            reply,
        )
        reply.update(program_us=program_us, values=values)
    if request.get("image_cache"):
        image_body(request["program"], request["cycles"], request["image_cache"], reply)
    if request.get("fixed_cycles"):
        native_cache = request.get("fixed_native_cache", "")
        reply["fixed_us"] = fixed_cycles(request["fixed_cycles"], native_cache)
    if request.get("state_variables"):
        reply.update(
            state_figures(
                request["state_variables"],
                request.get("reload", False),
                request.get("state_native_cache", ""),
            )
        )
    json.dump(reply, sys.stdout)


if __name__ == "__main__":
    main()
