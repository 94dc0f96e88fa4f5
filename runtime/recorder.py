"""Recordings of a resource (spec section 15, docs/recording.md): chosen variables every CPU
cycle, or from a trigger with cycles before it, into MCAP files in the state folder; with
all inputs, everything the programs take from outside, for an exact replay; and every
logpoint hit the debugger logs while they write, on a topic of its own.

The cycle thread only copies values into a queue (`TraceWriter.offer`); a writer thread per
recording encodes, compresses and writes, between the cycles. A full queue drops the
cycle and counts it.
A recording ends with its cycle or time limit, at `record_stop`, or when the configuration
it records changes (load, reload, cold start, program restart); one with all inputs also
when the resource stops.
"""

from __future__ import annotations

import base64
import bisect
import json
import operator
import re
import struct
from collections import deque
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from mcap.exceptions import McapError
from mcap.reader import make_reader

from runtime.code.instances import BoundVariable
from runtime.contract import protocol as p
from runtime.contract.recording import (
    ARTIFACT_ATTACHMENT,
    METADATA,
    START_ATTACHMENT,
    CycleInputs,
    LoggedHit,
    RecordingHeader,
    RecordingUnreadable,
    StartState,
    read_recording,
)
from runtime.contract.refusal import Refusal
from runtime.contract.system_variables import SYSTEM_VARIABLES
from runtime.trace_writer import CycleGate, Inputs, Logged, TraceWriter, Values

if TYPE_CHECKING:
    from runtime.resource import Resource

MAX_RUNNING = 4  # recordings at the same time
MAX_VARIABLES = 100_000  # over all the recordings running: each costs the cycle
_SYSTEM = tuple(v.name for v in SYSTEM_VARIABLES)
_FILE = re.compile(r"(?P<id>[A-Za-z0-9_-]{1,64})-(?P<part>[0-9]{1,6})\.mcap")
_COMPARE: dict[str, Callable[[Any, Any], bool]] = {
    "=": operator.eq,
    "<>": operator.ne,
    "<": operator.lt,
    "<=": operator.le,
    ">": operator.gt,
    ">=": operator.ge,
}


@dataclass
class _Trigger:
    bound: BoundVariable
    compare: Callable[[Any, Any], bool]
    value: Any
    text: str
    was: bool = True  # a condition true when the recording starts must fall first


@dataclass
class Recording:
    """One recording: its cycle-side state (what to read, the trigger, the pre-trigger
    ring) and its writer."""

    id: str
    header: RecordingHeader
    bound: list[BoundVariable]
    of_variables: list[BoundVariable]  # the configuration's variable list it was made for
    read: Callable[[], list[Any]]
    writer: TraceWriter
    started_ns: int  # calendar time at the start
    clock_at_start: int  # the resource clock then: cycle times become calendar times
    trigger: _Trigger | None
    pre: deque[Values]
    cycles_limit: int | None
    ns_limit: int | None
    all_inputs: bool
    state: str = "recording"
    cycles: int = 0  # cycles written
    counted: int = 0  # cycles since the start or the trigger, written or dropped
    first_ns: int | None = None  # clock time of the first cycle written (after the trigger)
    trigger_cycle: int | None = None
    ended: str | None = None
    system: dict[str, Any] = field(default_factory=dict)
    programs: dict[str, Any] = field(default_factory=dict)
    logged: int = 0  # logpoint messages queued
    logs_dropped: int = 0  # logpoint messages lost to a full queue since the last queued

    def info(self) -> p.RecordingInfo:
        error = self.writer.error or self.ended
        state = "failed" if self.writer.error else self.state
        if state == "done" and not self.writer.finished:
            state = "recording"  # ended, but its writer is still finishing the file
        return p.RecordingInfo(
            id=self.id,
            state=state,  # type: ignore[arg-type]
            variables=len(self.bound),
            all_inputs=self.all_inputs,
            cycles=self.cycles,
            dropped=self.writer.dropped,
            started_ns=self.started_ns,
            files=[p.RecordingFile(f.name, _size(f)) for f in self.writer.files],
            error=error,
            trigger_cycle=self.trigger_cycle,
        )


class Recordings:
    """The recordings of a resource, in `folder` (`<state folder>/recordings`)."""

    def __init__(self, folder: Path | None) -> None:
        self.folder = folder
        self._running: dict[str, Recording] = {}
        self._ended: dict[str, Recording] = {}  # of this process, for their counts
        self._serial = 0
        self._found: tuple[dict[str, Any], dict[str, Any]] = ({}, {})  # before_programs
        self._index = _PrefixIndex()  # for `Prefix*` patterns
        self._gate = CycleGate()  # the writers wait while the cycle runs

    @property
    def active(self) -> bool:
        return bool(self._running)

    # ---- commands (the cycle thread, between cycles)
    def start(self, resource: Resource, command: p.RecordStart) -> p.RecordingInfo:
        if self.folder is None:
            raise Refusal("not_allowed", "this resource has no state folder to record into")
        if resource.artifact is None:
            raise Refusal("state", "no configuration is loaded")
        if len(self._running) >= MAX_RUNNING:
            raise Refusal("too_many", f"at most {MAX_RUNNING} recordings run at the same time")
        if command.all_inputs and command.trigger is not None:
            raise Refusal(
                "bad_request", "all inputs are recorded from the start: no trigger with them"
            )
        if command.pre_cycles and command.trigger is None:
            raise Refusal("bad_request", "pre_cycles need a trigger")
        recording_id = command.id or self._new_id(resource)
        if recording_id in self._running or self._files_of(recording_id):
            raise Refusal("bad_request", f"a recording '{recording_id}' exists already")
        variables = resource.variables
        bound = _chosen(resource, command.variables, command.all_inputs, self._index)
        recorded = sum(len(r.bound) for r in self._running.values())
        if recorded + len(bound) > MAX_VARIABLES:
            raise Refusal(
                "too_many",
                f"at most {MAX_VARIABLES:,} variables are recorded at once "
                f"({recorded:,} by the recordings running)",
            )
        trigger = _trigger(resource, command.trigger)
        assert resource.artifact is not None
        header = RecordingHeader(
            resource=resource.name,
            project=resource.artifact.project,
            crc=resource.artifact.crc,
            variables=[(b.path.path, b.path.type) for b in bound],
            all_inputs=command.all_inputs,
            started_ns=resource.clock.wall_ns(),
            recording=recording_id,
            part=1,
            trigger=trigger.text if trigger else "",
            pre_cycles=command.pre_cycles,
        )
        attachments: dict[str, bytes] = {}
        if command.all_inputs:
            attachments = {
                ARTIFACT_ATTACHMENT: resource.artifact.to_json().encode(),
                START_ATTACHMENT: json.dumps(asdict(start_state(resource))).encode(),
            }
            variables.tap = []  # from now on, every store from outside is kept
        self.folder.mkdir(parents=True, exist_ok=True)
        writer = TraceWriter(
            self.folder,
            header,
            attachments,
            command.rotate_mb * 1024 * 1024,
            command.rotate_s * 1_000_000_000 if command.rotate_s else None,
            self._gate,
        )
        recording = Recording(
            id=recording_id,
            header=header,
            bound=bound,
            of_variables=variables.bound,
            read=variables.memory.reader(bound),
            writer=writer,
            started_ns=header.started_ns,
            clock_at_start=resource.clock.now_ns(),
            trigger=trigger,
            pre=deque(maxlen=command.pre_cycles or 1),
            cycles_limit=command.cycles,
            ns_limit=command.seconds * 1_000_000_000 if command.seconds else None,
            all_inputs=command.all_inputs,
            state="waiting" if trigger else "recording",
        )
        if command.all_inputs:
            recording.system = _system(resource)
            recording.programs = _programs(resource)
        self._running[recording_id] = recording
        resource.recorder.record(
            "recording",
            f"recording {recording_id} started: {len(bound)} variables"
            + (", all inputs" if command.all_inputs else "")
            + (f", trigger {trigger.text}" if trigger else ""),
        )
        return recording.info()

    def stop(self, resource: Resource, recording_id: str) -> p.RecordingInfo:
        recording = self._running.get(recording_id)
        if recording is None:
            ended = self._ended.get(recording_id)
            if ended is not None:
                return ended.info()
            raise Refusal("unknown_recording", f"no recording '{recording_id}' is running")
        self._end(resource, recording, "stopped")
        return recording.info()

    def infos(self) -> list[p.RecordingInfo]:
        return self.listing()()

    def listing(self) -> Callable[[], list[p.RecordingInfo]]:
        """The recordings, the running ones first: what this process knows is taken now
        (on the cycle thread); the files are looked at when the result is called (on
        another thread: the cycle never waits on a disk)."""
        known = [*self._running.values()]
        known += [r for key, r in sorted(self._ended.items()) if key not in self._running]

        def infos() -> list[p.RecordingInfo]:
            found = [r.info() for r in known]
            names = {r.id for r in known}
            for recording_id, files in sorted(self._on_disk().items()):
                if recording_id not in names:
                    found.append(_from_disk(recording_id, files))
            return found

        return infos

    def reading(self, name: str, offset: int, length: int) -> Callable[[], p.RecordingChunk]:
        """`record_read`: the name checked now, the file read when the result is called."""
        match = _FILE.fullmatch(name)
        if self.folder is None or match is None:
            raise Refusal("unknown_recording", f"no recording file '{name}'")
        path = self.folder / name

        def read() -> p.RecordingChunk:
            try:
                with path.open("rb") as stream:
                    size = stream.seek(0, 2)
                    stream.seek(min(offset, size))
                    data = stream.read(length)
            except OSError:
                raise Refusal("unknown_recording", f"no recording file '{name}'") from None
            return p.RecordingChunk(base64.b64encode(data).decode("ascii"), offset, size)

        return read

    def delete(self, recording_id: str) -> list[p.RecordingInfo]:
        if recording_id in self._running:
            raise Refusal("state", f"recording '{recording_id}' is running: stop it first")
        recording = self._ended.get(recording_id)
        if recording is not None and not recording.writer.finished:
            raise Refusal("busy", f"recording '{recording_id}' is still being written")
        files = self._files_of(recording_id)
        if not files and recording is None:
            raise Refusal("unknown_recording", f"no recording '{recording_id}'")
        for path in files:
            path.unlink(missing_ok=True)
        self._ended.pop(recording_id, None)
        return self.infos()

    def close(self) -> None:
        """The process ends: every recording finishes its file."""
        for recording in list(self._running.values()):
            recording.writer.close()
        for recording in [*self._running.values(), *self._ended.values()]:
            recording.writer.join(10)

    # ---- the cycle thread, in the CPU cycle
    def before_programs(self, resource: Resource) -> None:
        """Just before the user programs run: the system variables and the programs'
        states and clocks as the programs will find them."""
        self._gate.begins()
        if any(r.all_inputs for r in self._running.values()):
            self._found = (_system(resource), _programs(resource))

    def logged(self, hit: LoggedHit) -> None:
        """A logpoint hit the debugger logged (inside a program, on the cycle thread):
        into every recording that writes (not one waiting for its trigger)."""
        for recording in self._running.values():
            if recording.state != "recording":
                continue
            time_ns = recording.started_ns + (hit.clock_ns - recording.clock_at_start)
            if recording.writer.offer(Logged(time_ns, hit, recording.logs_dropped)):
                recording.logged += 1
                recording.logs_dropped = 0
            else:
                recording.logs_dropped += 1

    def idle(self, resource: Resource) -> None:
        """The resource does not run: a replay cannot cross that, so the recordings of all
        inputs end (recordings of values wait for cycles to come)."""
        for recording in list(self._running.values()):
            if recording.all_inputs:
                self._end(resource, recording, "ended: the resource stopped")

    def cycled(
        self,
        resource: Resource,
        begin_ns: int,
        before: list[tuple[str, Any]],
        after: list[tuple[str, Any]],
    ) -> None:
        """After the outputs of a CPU cycle that ran programs were written."""
        for recording in list(self._running.values()):
            bound = resource.variables.bound
            if recording.of_variables is not bound:
                if recording.of_variables != bound:
                    self._end(resource, recording, "ended: the configuration changed")
                    continue
                # the same variables, their values moved (into the memory image, or back)
                recording.read = resource.variables.memory.reader(recording.bound)
                recording.of_variables = bound
            self._capture(resource, recording, begin_ns, before, after)
        self._gate.ends()

    def _capture(
        self,
        resource: Resource,
        recording: Recording,
        begin_ns: int,
        before: list[tuple[str, Any]],
        after: list[tuple[str, Any]],
    ) -> None:
        time_ns = recording.started_ns + (begin_ns - recording.clock_at_start)
        item = Values(resource.cycle_count, time_ns, recording.read())
        trigger = recording.trigger
        if recording.state == "waiting":
            assert trigger is not None
            now = _holds(resource, trigger)
            fired, trigger.was = now and not trigger.was, now
            if not fired:
                if recording.header.pre_cycles:
                    recording.pre.append(item)
                return
            recording.state = "recording"
            recording.trigger_cycle = resource.cycle_count
            recording.first_ns = begin_ns
            while recording.pre:
                if recording.writer.offer(recording.pre.popleft()):
                    recording.cycles += 1
        if recording.first_ns is None:
            recording.first_ns = begin_ns
        if recording.all_inputs:
            inputs = self._inputs(resource, recording, begin_ns, time_ns, before, after)
            recording.writer.offer(Inputs(time_ns, inputs))
        if recording.writer.offer(item):
            recording.cycles += 1
        recording.counted += 1
        limit, ns_limit = recording.cycles_limit, recording.ns_limit
        if (limit is not None and recording.counted >= limit) or (
            ns_limit is not None and begin_ns - recording.first_ns >= ns_limit
        ):
            self._end(resource, recording, "done")

    def _inputs(
        self,
        resource: Resource,
        recording: Recording,
        begin_ns: int,
        time_ns: int,
        before: list[tuple[str, Any]],
        after: list[tuple[str, Any]],
    ) -> CycleInputs:
        system, programs = self._found
        changed_system = {k: v for k, v in system.items() if recording.system.get(k) != v}
        changed_programs = {k: v for k, v in programs.items() if recording.programs.get(k) != v}
        recording.system, recording.programs = system, programs
        cut = [p.name for p in resource.programs if p.in_progress]
        return CycleInputs(
            cycle=resource.cycle_count,
            begin_ns=begin_ns,
            wall_ns=time_ns,
            before=before,
            after=after,
            system=changed_system,
            programs=changed_programs,
            cut=cut,
        )

    def _end(self, resource: Resource, recording: Recording, why: str) -> None:
        recording.writer.close()
        recording.state = "done"
        if why not in ("done", "stopped"):
            recording.ended = why
        self._running.pop(recording.id, None)
        self._ended[recording.id] = recording
        if recording.all_inputs and not any(r.all_inputs for r in self._running.values()):
            resource.variables.tap = None
        logs = f", {recording.logged} logpoint messages" if recording.logged else ""
        if recording.logs_dropped:
            logs += f" ({recording.logs_dropped} more dropped at the end: the writer was behind)"
        resource.recorder.record(
            "recording", f"recording {recording.id} {why} after {recording.cycles} cycles{logs}"
        )

    # ---- files
    def _new_id(self, resource: Resource) -> str:
        while True:
            self._serial += 1
            stamp = resource.clock.wall_ns() // 1_000_000_000
            candidate = f"rec{stamp}-{self._serial}"
            if candidate not in self._running and not self._files_of(candidate):
                return candidate

    def _files_of(self, recording_id: str) -> list[Path]:
        return self._on_disk().get(recording_id, [])

    def _on_disk(self) -> dict[str, list[Path]]:
        found: dict[str, list[tuple[int, Path]]] = {}
        if self.folder is None or not self.folder.is_dir():
            return {}
        for path in self.folder.iterdir():
            match = _FILE.fullmatch(path.name)
            if match:
                found.setdefault(match["id"], []).append((int(match["part"]), path))
        return {key: [path for _, path in sorted(parts)] for key, parts in found.items()}


def start_state(resource: Resource) -> StartState:
    """Where an all-inputs recording begins: the warm-start context with each program's
    clock and every system variable."""
    from runtime.restart import take_context

    context = take_context(resource)
    assert context is not None
    return StartState(
        context={
            "signature": context.signature,
            "resource": context.resource,
            "programs": context.programs,
            "globals": context.globals,
        },
        programs={
            p.name: {
                "state": p.state.value,
                "time_ns": p.time_ns,
                "last_start_ns": p.last_start_ns,
                "count": p.stats.count,
            }
            for p in resource.programs
        },
        system=_system(resource),
        cycle=resource.cycle_count,
    )


def _system(resource: Resource) -> dict[str, Any]:
    system = resource.system
    return {name: getattr(system, name) for name in _SYSTEM}


def _programs(resource: Resource) -> dict[str, Any]:
    return {p.name: [p.state.value, p.last_start_ns] for p in resource.programs}


def _chosen(
    resource: Resource, patterns: list[str], all_inputs: bool, index: _PrefixIndex
) -> list[BoundVariable]:
    """The elementary variables the patterns name, in the configuration's order; with all
    inputs, every output (%Q) too, as a replay compares them."""
    variables = resource.variables
    chosen: dict[str, BoundVariable] = {}
    for pattern in patterns:
        if pattern.endswith("*"):
            hits = index.starting_with(variables.bound, pattern[:-1])
            if not hits:
                raise Refusal("unknown_variable", f"no variable matches '{pattern}'")
            for bound in hits:
                chosen[bound.path.path] = bound
        else:
            bound = variables.lookup(pattern)
            chosen[bound.path.path] = bound
        if len(chosen) > MAX_VARIABLES:
            break
    if all_inputs:
        for bound in variables.outputs:
            chosen[bound.path.path] = bound
    if not chosen:
        raise Refusal("bad_request", "name at least one variable to record")
    if len(chosen) > MAX_VARIABLES:
        raise Refusal("too_many", f"at most {MAX_VARIABLES:,} variables are recorded at once")
    order = {id(b): n for n, b in enumerate(variables.bound)}
    return sorted(chosen.values(), key=lambda b: order[id(b)])


class _PrefixIndex:
    """The variables sorted by upper-case path, made once per configuration: a `Prefix*`
    pattern is found by bisection, not by a scan of every variable (4096 patterns over
    100,000 variables would hold the cycle thread for seconds)."""

    def __init__(self) -> None:
        self._of: list[BoundVariable] | None = None
        self._keys: list[str] = []
        self._bound: list[BoundVariable] = []

    def starting_with(self, bound: list[BoundVariable], prefix: str) -> list[BoundVariable]:
        if self._of is not bound:
            ordered = sorted(bound, key=lambda b: b.path.path.upper())
            self._of, self._bound = bound, ordered
            self._keys = [b.path.path.upper() for b in ordered]
        prefix = prefix.upper()
        start = bisect.bisect_left(self._keys, prefix)
        end = start
        while end < len(self._keys) and self._keys[end].startswith(prefix):
            end += 1
        return self._bound[start:end]


def _trigger(resource: Resource, trigger: p.Trigger | None) -> _Trigger | None:
    if trigger is None:
        return None
    variables = resource.variables
    bound = variables.lookup(trigger.variable)
    value = variables.checked(bound, trigger.value)
    if isinstance(value, list | str) and trigger.op not in ("=", "<>"):
        raise Refusal("bad_value", f"'{bound.path.path}' can only be compared with = or <>")
    text = f"{bound.path.path} {trigger.op} {json.dumps(value)}"
    return _Trigger(bound, _COMPARE[trigger.op], value, text)


def _holds(resource: Resource, trigger: _Trigger) -> bool:
    try:
        return bool(trigger.compare(resource.variables.read(trigger.bound), trigger.value))
    except TypeError:
        return False


def _size(path: Path) -> int:
    try:
        return path.stat().st_size
    except OSError:
        return 0


def _from_disk(recording_id: str, files: list[Path]) -> p.RecordingInfo:
    """A recording of an earlier run of the runtime, known by its files: its header and
    the count of its values messages, from the MCAP summary (a file cut short by a crash
    has none: it is read through)."""
    header: RecordingHeader | None = None
    cycles = 0
    problem: str | None = None
    for path in files:
        try:
            with path.open("rb") as stream:
                reader = make_reader(stream)
                summary = reader.get_summary()
                if summary is None or summary.statistics is None:
                    raise McapError("no summary")
                for metadata in reader.iter_metadata():
                    if metadata.name == METADATA and header is None:
                        header = RecordingHeader.from_metadata(dict(metadata.metadata))
                values = [
                    channel.id
                    for channel in summary.channels.values()
                    if channel.topic.endswith("/values")
                ]
                counts = summary.statistics.channel_message_counts
                cycles += sum(counts.get(channel, 0) for channel in values)
        except (OSError, McapError, ValueError, struct.error):
            try:  # cut short: read through it
                recording = read_recording(path)
            except (OSError, RecordingUnreadable) as exc:
                problem = f"{path.name}: {exc}"
                continue
            header = header or recording.header
            cycles += len(recording.rows)
            if not recording.complete:
                problem = f"{path.name} was cut short ({recording.problem})"
    return p.RecordingInfo(
        id=recording_id,
        state="done",
        variables=len(header.variables) if header else 0,
        all_inputs=header.all_inputs if header else False,
        cycles=cycles,
        dropped=0,
        started_ns=header.started_ns if header else 0,
        files=[p.RecordingFile(f.name, _size(f)) for f in files],
        error=problem,
        from_files=True,
    )
