"""The CPU cycle of one code base, measured in a process of its own: run as a script with
that code base (this one, or a baseline checkout) first on PYTHONPATH, it reads a request
as JSON on stdin and prints the figures as JSON on stdout.

It uses only what every version of the project since the artifact's version 3 has
(`compile_sources`, `Resource`, the two clocks), so that `make bench` can print a figure of
today's code beside the same figure of an older commit, measured in the same run.

Request: {"program": ST text, "cycles": n, "check_cycles": m, "fixed_cycles": f,
"native_cache": folder}, each part left out when empty or 0; with `native_cache` (today's
code only) the program runs on the native tier, its modules compiled into that folder.
Reply: {"program_us": median us per cycle of the program (virtual clock), "values": every
variable after `check_cycles` cycles, "fixed_us": median us per cycle of a resource with one
empty program (real clock), "native_build_s": how long the native bodies took to be in
place, "native_bodies": the POUs that run as C}.
"""

from __future__ import annotations

import json
import statistics
import sys
import time
from pathlib import Path
from typing import Any

from backend.compiler.pipeline import compile_sources
from backend.compiler.source import SourceFile
from runtime.clock import RealClock, VirtualClock
from runtime.contract.artifact import ProgramConfig, ResourceConfig
from runtime.resource import Resource

CYCLE_NS = 100_000_000
EMPTY = "PROGRAM Empty\nEND_PROGRAM\n"


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


def fixed_cycles(cycles: int) -> float:
    program = ProgramConfig(name="Empty", pou="Empty", program_id=1)
    resource = _running(EMPTY, RealClock(), [program])
    for _ in range(1_000):  # caches, the watchdog thread waking up
        resource.cycle()
    return _median_us(resource.cycle, cycles)


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
    if request.get("fixed_cycles"):
        reply["fixed_us"] = fixed_cycles(request["fixed_cycles"])
    json.dump(reply, sys.stdout)


if __name__ == "__main__":
    main()
