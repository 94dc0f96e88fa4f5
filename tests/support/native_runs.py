"""Run the same ST text on the Python tier and on the native tier, side by side on virtual
clocks, and compare every variable after every cycle."""

from __future__ import annotations

import math
from dataclasses import dataclass

from backend.compiler.pipeline import compile_sources
from backend.compiler.source import SourceFile
from runtime.clock import VirtualClock
from runtime.code.native.tier import NativeReport, NativeTier
from runtime.contract.artifact import Artifact, ProgramConfig, ResourceConfig
from runtime.online_writes import simulate
from runtime.resource import Resource

CYCLE_NS = 100_000_000
Writes = dict[int, list[tuple[str, object]]]  # cycle: (variable, value) written before it


def compiled(text: str, programs: list[ProgramConfig] | None = None) -> Artifact:
    config = ResourceConfig(name="R", watchdog_ms=5_000, safety_time_ms=10_000)
    result = compile_sources([SourceFile("prog.st", text)], resource=config, programs=programs)
    assert result.artifact is not None, "\n".join(str(d) for d in result.diagnostics)
    return result.artifact


def running(artifact: Artifact, tier: NativeTier | None) -> Resource:
    """A started resource on a virtual clock; with `tier`, its native bodies in place."""
    resource = Resource("R", VirtualClock())
    resource.native = tier
    resource.load(artifact)
    resource.tier_up(wait=True)
    resource.start()
    return resource


def advance(resource: Resource) -> None:
    resource.cycle()
    clock = resource.clock
    assert isinstance(clock, VirtualClock)
    clock.advance(CYCLE_NS)


def same(a: object, b: object) -> bool:
    """Identical values: the same Python type, REALs bit for bit (NaN equals NaN)."""
    if type(a) is not type(b):
        return False
    if isinstance(a, float) and isinstance(b, float):
        if math.isnan(a) or math.isnan(b):
            return math.isnan(a) and math.isnan(b)
        return a == b and math.copysign(1.0, a) == math.copysign(1.0, b)
    if isinstance(a, list) and isinstance(b, list):
        return len(a) == len(b) and all(same(x, y) for x, y in zip(a, b, strict=True))
    if isinstance(a, str):  # a reference is its place's path; its objects are one resource's
        return str(a) == str(b)
    return a == b


@dataclass
class Pair:
    python: Resource
    native: Resource

    @property
    def report(self) -> NativeReport:
        code = self.native.variables.code
        assert code is not None and code.native is not None
        return code.native

    def cycle_and_compare(self, cycles: int, writes: Writes | None = None) -> None:
        """`writes`: what is written into both before a cycle (as `padt sim --set`)."""
        for cycle in range(1, cycles + 1):
            for path, value in (writes or {}).get(cycle, []):
                simulate(self.python, path, value)
                simulate(self.native, path, value)
            advance(self.python)
            advance(self.native)
            expected, found = self.python.variables.values(), self.native.variables.values()
            differences = {
                path: (expected[path], found.get(path))
                for path in expected
                if not same(expected[path], found.get(path))
            }
            assert not differences, f"cycle {cycle}: Python vs native {differences}"
            assert _states(self.python) == _states(self.native), f"cycle {cycle}"

    def fault_of_the_next_cycle(self) -> str:
        """The program error the next cycle ends in, on both tiers alike (none before)."""
        assert not program_error(self.native), program_error(self.native)
        self.cycle_and_compare(1)
        return program_error(self.native)


def _states(resource: Resource) -> list[object]:
    """The resource's state and error, and each program's."""
    programs = [(p.name, p.state, p.error) for p in resource.programs]
    return [resource.state, resource.error, *programs]


def program_error(resource: Resource) -> str:
    return " ".join(p.error for p in resource.programs if p.error)


def side_by_side(text: str, tier: NativeTier, programs: list[ProgramConfig] | None = None) -> Pair:
    artifact = compiled(text, programs)
    return Pair(running(artifact, None), running(artifact, tier))
