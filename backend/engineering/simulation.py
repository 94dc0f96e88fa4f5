"""`padt sim`: run a resource's user programs on virtual time and trace their values.

Cycle k (from 1) runs with the clock at (k-1) x the cycle interval. Time comes from a
`VirtualClock` only, so the same project and options give the same output bit for bit.
Values are set and read through the resource (`online_writes.simulate`, `Variables.values`), the
same way online test does it. The bodies run on the tier asked for (`tiers.py`), as a runtime
runs them.
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Any

from backend.compiler.diagnostics import clipped, shortened
from backend.engineering.literals import LiteralError, parse_literal
from runtime.clock import VirtualClock
from runtime.code.intrinsics import to_bytes
from runtime.code.native.tier import NativeTier
from runtime.contract.artifact import Artifact, ArtifactError
from runtime.contract.protocol import ProgramState, ResourceState
from runtime.contract.refusal import Refusal
from runtime.contract.values import (
    TIME_TYPES,
    ValueRejected,
    array_shape,
    is_reference_type,
    representation,
)
from runtime.online_writes import simulate
from runtime.resource import Resource

NS_PER_MS = 1_000_000


class SimulationError(ValueError):
    """Options that cannot be run (unknown name, bad value); found before the first cycle.
    What the user typed is cut when it is long (`shortened`, and `clipped` for names that
    messages quote)."""

    def __init__(self, message: str) -> None:
        super().__init__(clipped(message))


@dataclass(frozen=True)
class Setting:
    """`--set NAME=VALUE[@CYCLE]`: write VALUE (an ST literal) before cycle CYCLE."""

    name: str
    literal: str
    cycle: int = 1


@dataclass(frozen=True)
class Plan:
    cycles: int = 10
    cycle_ms: int | None = None  # None: `sim_cycle_ms` of the artifact
    settings: tuple[Setting, ...] = ()
    trace: tuple[str, ...] | None = None  # None: every elementary variable


@dataclass(frozen=True)
class CycleRecord:
    cycle: int
    t_ms: int
    values: dict[str, Any]  # JSON-ready: TIME in ms, strings decoded
    faults: tuple[str, ...] = ()  # "Program: cause" for programs that went to ERROR now
    stopped: str | None = None  # the cause, when the resource went to ERROR STOP now

    def as_json(self) -> str:
        # allow_nan=False: non-finite REALs are already strings, so every line is strict JSON
        record = {"cycle": self.cycle, "t_ms": self.t_ms, "values": self.values}
        return json.dumps(record, ensure_ascii=True, allow_nan=False)


@dataclass
class Simulation:
    resource: Resource
    clock: VirtualClock
    cycles: int
    cycle_ns: int
    traced: list[str]  # canonical variable paths, in output order
    types: dict[str, str]  # path -> type name
    writes: dict[int, list[tuple[str, Any]]] = field(default_factory=dict)  # cycle -> writes


# ---- options


_SETTING = re.compile(r"(?P<name>[^=]+)=(?P<value>.*?)(?:@(?P<cycle>[0-9]+))?", re.DOTALL)


def parse_setting(text: str) -> Setting:
    """`NAME=VALUE[@CYCLE]`; an `@` inside a quoted string is part of the value."""
    match = _SETTING.fullmatch(text)
    if match is None or not match["value"].strip():
        raise SimulationError(f"--set {shortened(text)}: expected NAME=VALUE or NAME=VALUE@CYCLE")
    cycle = int(match["cycle"]) if match["cycle"] is not None else 1
    if cycle < 1:
        raise SimulationError(f"--set {shortened(text)}: cycles count from 1")
    return Setting(match["name"].strip(), match["value"].strip(), cycle)


def trace_names(options: list[str] | None) -> tuple[str, ...] | None:
    """`--trace A,B --trace C` -> ("A", "B", "C"); a comma between brackets belongs to
    the name (`--trace m[1,0],n`)."""
    if options is None:
        return None
    return tuple(name.strip() for option in options for name in _names(option) if name.strip())


def _names(option: str) -> list[str]:
    names, start, depth = [], 0, 0
    for index, char in enumerate(option):
        depth += {"[": 1, "]": -1}.get(char, 0)
        if char == "," and depth <= 0:
            names.append(option[start:index])
            start, depth = index + 1, 0
    return [*names, option[start:]]


# ---- run-time values -> JSON


def display(value: Any, type_name: str) -> Any:
    """A value as `padt sim` prints it: TIME in milliseconds (an int when whole), text
    decoded, non-finite REALs as "NaN" / "Infinity" / "-Infinity"."""
    if is_reference_type(type_name):
        return "NULL" if value is None else str(value)  # the path it refers to
    if isinstance(value, list):
        shape = array_shape(type_name)
        element = shape.element if shape is not None else ""
        return [display(item, element) for item in value]
    if isinstance(value, bool):
        return value
    if isinstance(value, int):
        if type_name.upper() in TIME_TYPES:
            return value // NS_PER_MS if value % NS_PER_MS == 0 else value / NS_PER_MS
        return value
    if isinstance(value, float):
        if math.isnan(value):
            return "NaN"
        if math.isinf(value):
            return "Infinity" if value > 0 else "-Infinity"
        return value
    if isinstance(value, str):
        return _text(value, type_name.upper() in ("WSTRING", "WCHAR"))
    return repr(value)  # no such value in a valid artifact; never fail the trace for it


def _text(value: str, wide: bool) -> str:
    """A STRING holds UTF-8 bytes one per character, a WSTRING UTF-16 code units: both are
    shown as the text they encode."""
    if wide:
        units = b"".join(ord(ch).to_bytes(2, "little") for ch in value if ord(ch) < 0x10000)
        return units.decode("utf-16-le", "replace")
    return to_bytes(value).decode("utf-8", "replace")


# ---- the run


DEFAULT_CYCLE_MS = 100


def sim_cycle_ms(artifact: Artifact) -> int:
    """Virtual time per CPU cycle: the target cycle time, or 100 ms without one."""
    return artifact.resource.target_cycle_ms or DEFAULT_CYCLE_MS


def prepare(artifact: Artifact, plan: Plan, native: NativeTier | None = None) -> Simulation:
    """Load the artifact into a resource on a virtual clock, on the native tier when
    `native` is given (else all as Python), and check every option; raises SimulationError
    before anything has run."""
    if plan.cycles < 1:
        raise SimulationError("--cycles must be at least 1")
    cycle_ms = plan.cycle_ms if plan.cycle_ms is not None else sim_cycle_ms(artifact)
    if cycle_ms < 1:
        raise SimulationError("--cycle-ms must be at least 1")
    clock = VirtualClock()
    resource = Resource(artifact.resource.name, clock)
    resource.native = native
    try:
        resource.load(artifact)
    except (Refusal, ArtifactError) as exc:  # the check of generated code before it runs
        raise SimulationError(f"the compiled configuration does not load: {exc}") from None
    types = {v.path: v.type for v in resource.variables.infos()}
    traced = list(types) if plan.trace is None else _select(resource, types, plan.trace)
    simulation = Simulation(resource, clock, plan.cycles, cycle_ms * NS_PER_MS, traced, types)
    for setting in plan.settings:
        if setting.cycle > plan.cycles:
            raise SimulationError(
                f"--set {shortened(setting.name)}: cycle {setting.cycle} is after the last cycle "
                f"({plan.cycles})"
            )
        path, value = _checked_write(resource, setting)
        simulation.writes.setdefault(setting.cycle, []).append((path, value))
    # a runtime runs as Python until its C bodies are built; waiting for them (once the
    # options are good: a refusal need not) makes every cycle run on the tier asked for
    resource.tier_up(wait=True)
    return simulation


def _select(resource: Resource, types: dict[str, str], names: tuple[str, ...]) -> list[str]:
    """Trace names as canonical paths. A name that is no elementary variable but an
    instance, struct or step (`Main.t`, `Seq.Fill`) stands for all the values below it."""
    selected: dict[str, None] = {}  # an ordered set
    for name in names:
        try:
            selected[resource.variables.lookup(name).path.path] = None
            continue
        except Refusal:
            pass
        below = [p for p in types if p.upper().startswith((f"{name.upper()}.", f"{name.upper()}["))]
        if not below:
            raise SimulationError(f"--trace: resource {resource.name} has no variable '{name}'")
        selected.update(dict.fromkeys(below))
    return list(selected)


def _checked_write(resource: Resource, setting: Setting) -> tuple[str, Any]:
    try:
        path = resource.variables.lookup(setting.name).path
    except Refusal as exc:
        raise SimulationError(f"--set {shortened(setting.name)}: {exc.message}") from None
    if path.constant:
        raise SimulationError(f"--set {shortened(setting.name)}: '{path.path}' is a constant")
    try:
        value = parse_literal(setting.literal, path.type)
        representation(path.type, value)  # refuse now what Resource.simulate would refuse later
    except (LiteralError, ValueRejected) as exc:
        raise SimulationError(f"--set {shortened(setting.name)}: {exc}") from None
    return path.path, value


def run(simulation: Simulation) -> Iterator[CycleRecord]:
    """Cycle k runs with the clock at (k-1) x the interval; the resource advances each
    program's time by the clock's difference between cycles, i.e. exactly one interval.
    A cycle that puts the resource in ERROR STOP (its watchdog: an endless loop) is the
    last: nothing runs after it until INIT."""
    resource, clock = simulation.resource, simulation.clock
    resource.start()
    for cycle in range(1, simulation.cycles + 1):
        for path, value in simulation.writes.get(cycle, []):
            simulate(resource, path, value)
        before = {p.config.name: p.state for p in resource.programs}
        resource.cycle()
        faults = tuple(
            f"{p.config.name}: {p.error}"
            for p in resource.programs
            if p.state == ProgramState.ERROR and before[p.config.name] != ProgramState.ERROR
        )
        shown = {
            path: display(resource.variables.value(path), simulation.types[path])
            for path in simulation.traced
        }
        stopped = resource.error if resource.state == ResourceState.ERROR_STOP else None
        t_ms = (cycle - 1) * simulation.cycle_ns // NS_PER_MS
        yield CycleRecord(cycle, t_ms, shown, faults, stopped)
        if stopped is not None:
            return
        clock.advance(simulation.cycle_ns)
