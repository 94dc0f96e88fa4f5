"""`padt replay`: run a recorded run again, offline, and compare it cycle by cycle
(docs/recording.md). The recording must hold all inputs: the configuration that ran, its
state when the recording began, and per CPU cycle everything the programs took from outside.

The replay loads the recorded configuration into a resource on virtual time, restores the
recorded start state, and, when the project given is another version, reloads it the way an
online reload would (values carried by name). Then, per recorded cycle, it sets the clock,
the program states, the system variables and every value set from outside, runs the user
programs (`Resource.run_programs`, the code path of the real cycle) and compares every
recorded variable (the outputs among them) with the recording. The programs run on the tier
asked for (`tiers.py`): either must reproduce a recording of either.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from backend.engineering.tiers import left_as_python
from runtime.clock import VirtualClock
from runtime.code.native.tier import NativeTier
from runtime.context_snapshot import ContextMismatch
from runtime.contract.artifact import Artifact, ArtifactError, load_artifact
from runtime.contract.protocol import ProgramState, ResourceState
from runtime.contract.recording import (
    CycleInputs,
    Recording,
    RecordingUnreadable,
    read_recording,
)
from runtime.contract.refusal import Refusal
from runtime.contract.system_variables import SYSTEM_VARIABLES
from runtime.memory import ValueTrees
from runtime.reload_switch import reload
from runtime.resource import Resource

_SYSTEM = frozenset(v.name for v in SYSTEM_VARIABLES)


class ReplayError(ValueError):
    """A recording that cannot be replayed (no inputs, damaged, another resource)."""


@dataclass(frozen=True)
class Difference:
    cycle: int  # the resource's CPU cycle number, as recorded
    index: int  # 1-based position of the cycle in the recording
    variable: str
    recorded: Any
    replayed: Any


@dataclass(frozen=True)
class ReplayResult:
    cycles: int  # cycles compared
    difference: Difference | None
    reloaded: bool  # the project differs from the recorded configuration
    complete: bool  # False: the file was cut short; the cycles up to its end were compared
    recorded_crc: str
    replayed_crc: str
    # the bodies that ran as Python on the native tier, with why (tiers.left_as_python)
    left_as_python: tuple[str, ...] = ()

    def summary(self) -> str:
        if self.difference is None:
            return f"replay: {self.cycles} cycles, identical"
        d = self.difference
        return (
            f"replay: cycle {d.cycle} (the {_ordinal(d.index)} recorded) differs in "
            f"{d.variable}: recorded {d.recorded!r}, replayed {d.replayed!r}"
        )


def read_parts(path: Path) -> Recording:
    """A recording and the parts it was rotated into (`X-1.mcap`, `X-2.mcap`, ... or the
    `padt record` names `F.mcap`, `F-2.mcap`, ...), in order, as one."""
    first = read_recording(path)
    for part in _later_parts(path):
        more = read_recording(part)
        if more.header.recording != first.header.recording:
            break
        if more.header.variables != first.header.variables:  # its rows are of other columns
            raise RecordingUnreadable(f"{part} lists other variables than {path}")
        first.cycles += more.cycles
        first.times_ns += more.times_ns
        first.rows += more.rows
        first.inputs += more.inputs
        first.complete, first.problem = more.complete, more.problem
    return first


def _later_parts(path: Path) -> list[Path]:
    stem = path.stem
    base = stem[: -len("-1")] if stem.endswith("-1") else stem
    parts = []
    for number in range(2, 100_000):
        candidate = path.with_name(f"{base}-{number}{path.suffix}")
        if not candidate.exists():
            break
        parts.append(candidate)
    return parts


def replay(
    recording: Recording, artifact: Artifact, native: NativeTier | None = None
) -> ReplayResult:
    """Replay `recording` with the configuration `artifact` (the project given), on the
    native tier when `native` is given, else all as Python."""
    header = recording.header
    if not header.all_inputs or recording.artifact is None or recording.start is None:
        raise ReplayError("the recording holds no inputs: record with --all-inputs to replay it")
    try:
        recorded = load_artifact(recording.artifact)
    except ArtifactError as exc:
        raise ReplayError(f"the recorded configuration is damaged: {exc}") from None
    try:
        resource = _started(_unsliced(recorded), recording, native)
    except ReplayError:
        raise  # says what is wrong already
    except (KeyError, TypeError, ValueError, ArithmeticError) as exc:
        raise ReplayError(f"the recording's start state is damaged ({exc!r})") from None
    reloaded = artifact.crc != recorded.crc
    if reloaded:
        try:
            reload(resource, _unsliced(artifact), {})
        except (Refusal, ArtifactError) as refusal:
            raise ReplayError(f"the project cannot replace the recorded one: {refusal}") from None
    names = [path for path, _ in header.variables]
    bound = {path: resource.variables.find(path) for path in names}
    clock = resource.clock
    assert isinstance(clock, VirtualClock)
    inputs = {item.cycle: item for item in recording.inputs}
    compared = 0
    crcs, left = (recorded.crc, artifact.crc), tuple(left_as_python(resource.native_report))
    for index, (cycle, row) in enumerate(zip(recording.cycles, recording.rows, strict=True), 1):
        item = inputs.get(cycle)
        if item is None:
            raise ReplayError(f"cycle {cycle} has no recorded inputs (the writer fell behind)")
        if item.cut:
            raise ReplayError(
                f"in cycle {cycle} the time slice cut program(s) {', '.join(item.cut)}: "
                "where it was cut cannot be repeated"
            )
        try:
            _replay_cycle(resource, clock, item)
        except (IndexError, KeyError, TypeError, ValueError, ArithmeticError, Refusal) as exc:
            raise ReplayError(f"the inputs of cycle {cycle} are damaged ({exc!r})") from None
        for path, value in zip(names, row, strict=True):
            where = bound[path]
            mine = resource.variables.read(where) if where is not None else "(no such variable)"
            if not _same(value, mine):
                difference = Difference(cycle, index, path, value, mine)
                return ReplayResult(compared, difference, reloaded, recording.complete, *crcs, left)
        compared += 1
    return ReplayResult(compared, None, reloaded, recording.complete, *crcs, left)


def _unsliced(artifact: Artifact) -> Artifact:
    """Without time slices: a replay runs every program cycle to its end, as the recorded
    run did (a recorded cycle that was cut is refused)."""
    programs = tuple(replace(p, max_duration_us=0) for p in artifact.programs)
    return replace(artifact, programs=programs)


def _started(artifact: Artifact, recording: Recording, native: NativeTier | None) -> Resource:
    """A resource in RUN on the recorded configuration, in the state the recording began;
    the reload of another version takes its native tier along (`reload_switch`)."""
    start = recording.start
    assert start is not None
    first = recording.inputs[0].begin_ns if recording.inputs else 0
    clock = VirtualClock(start_ns=first, epoch_ns=0)
    resource = Resource(recording.header.resource, clock)
    resource.native = native
    try:
        resource.load(artifact)
    except (Refusal, ArtifactError) as refusal:  # its code is checked before it runs
        raise ReplayError(f"the recorded configuration does not load: {refusal}") from None
    # every replayed cycle on the tier asked for: the recorded run may have begun as Python,
    # before its C bodies were built, but either tier gives the same values
    resource.tier_up(wait=True)
    context = start.context
    try:
        values = {p.name: context["programs"][p.name]["values"] for p in resource.programs}
        resource.variables.memory.restore(ValueTrees(context["globals"], values))
    except (ContextMismatch, KeyError, TypeError) as exc:
        raise ReplayError(
            f"the recorded start state does not fit its configuration: {exc}"
        ) from None
    resource.state = ResourceState.RUN
    for program in resource.programs:
        saved = start.programs[program.name]
        program.state = ProgramState(saved["state"])
        program.time_ns = int(saved["time_ns"])
        program.last_start_ns = saved["last_start_ns"]
        program.stats.count = int(saved["count"])
    _set_system(resource, start.system)
    resource.cycle_count = start.cycle
    return resource


def _replay_cycle(resource: Resource, clock: VirtualClock, item: CycleInputs) -> None:
    clock.sleep_until(item.begin_ns)
    for program in resource.programs:
        changed = item.programs.get(program.name)
        if changed is not None:
            program.state = ProgramState(changed[0])
            program.last_start_ns = changed[1]
    _set_system(resource, item.system)
    store_recorded(resource, item.before)
    resource.run_programs(item.begin_ns)
    store_recorded(resource, item.after)
    resource.cycle_count = item.cycle


def _set_system(resource: Resource, values: dict[str, Any]) -> None:
    """System variables as recorded: only those that are system variables."""
    for name, value in values.items():
        if name not in _SYSTEM:
            raise ValueError(f"{name!r} is no system variable")
        setattr(resource.system, name, value)


def store_recorded(resource: Resource, stores: list[tuple[str, Any]]) -> None:
    """Values set from outside, as recorded (`padt test`'s REPLAY feeds them too)."""
    variables = resource.variables
    for path, value in stores:
        bound = variables.find(path)
        if bound is not None:  # a variable the new version no longer has
            variables.store(bound, _as_recorded(value))


def _as_recorded(value: Any) -> Any:
    """JSON gave back non-finite REALs as text."""
    if isinstance(value, str) and value in ("nan", "inf", "-inf"):
        return float(value)
    if isinstance(value, list):
        return [_as_recorded(item) for item in value]
    return value


def _same(recorded: Any, replayed: Any) -> bool:
    """Equal to the bit, as JSON brings values back: NaN equals NaN here."""
    if isinstance(replayed, list):
        return (
            isinstance(recorded, list)
            and len(recorded) == len(replayed)
            and all(_same(a, b) for a, b in zip(recorded, replayed, strict=True))
        )
    recorded = _as_recorded(recorded)
    if isinstance(replayed, float) and isinstance(recorded, float):
        return recorded == replayed or (math.isnan(recorded) and math.isnan(replayed))
    return bool(recorded == replayed)


def _ordinal(n: int) -> str:
    suffix = "th" if 10 <= n % 100 <= 20 else {1: "st", 2: "nd", 3: "rd"}.get(n % 10, "th")
    return f"{n}{suffix}"
