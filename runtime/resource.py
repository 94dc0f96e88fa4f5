"""A resource: one controller with its loaded configuration, user programs and states.

This is the state that the rest of the runtime protects: only the cycle thread calls its
methods (commands reach it through the cycle driver's queue), so it needs no locks.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass, field
from enum import StrEnum
from typing import Any

from runtime.artifact import Artifact, ProgramConfig
from runtime.clock import Clock
from runtime.code_image import (
    CodeImage,
    ValueRejected,
    VariablePath,
    read_path,
    representation,
    write_path,
)
from runtime.intrinsics import ProgramFault, SystemView
from runtime.watchdog import Watchdog, WatchdogExpired, process_watchdog

log = logging.getLogger(__name__)


class ResourceState(StrEnum):
    STOP_INVALID = "STOP/INVALID CONFIGURATION"
    STOP_VALID = "STOP/VALID CONFIGURATION"
    RUN = "RUN"
    ERROR_STOP = "ERROR STOP"


class ProgramState(StrEnum):
    RUN = "RUN"
    STOP = "STOP"
    ERROR = "ERROR"


class CommandRefused(Exception):
    """A command that is not possible in the current state; the reply says why."""

    def __init__(self, code: str, message: str) -> None:
        super().__init__(message)
        self.code = code
        self.message = message


@dataclass
class UserProgram:
    config: ProgramConfig
    instance: Any
    paths: list[VariablePath]
    state: ProgramState = ProgramState.STOP
    time_ns: int = 0  # the program's own time: what its timers see
    cycles: int = 0
    last_wall_ns: int | None = None  # wall time of the last cycle run in RUN
    error: str | None = None


@dataclass(frozen=True)
class BoundVariable:
    """A variable path with the instance it starts from (a program instance or `_G`)."""

    owner: Any
    path: VariablePath


@dataclass
class CycleStats:
    count: int = 0
    last_ns: int = 0
    min_ns: int = 0
    max_ns: int = 0
    total_ns: int = 0

    def record(self, duration_ns: int) -> None:
        self.count += 1
        self.last_ns = duration_ns
        self.min_ns = duration_ns if self.count == 1 else min(self.min_ns, duration_ns)
        self.max_ns = max(self.max_ns, duration_ns)
        self.total_ns += duration_ns

    def as_json(self) -> dict[str, float]:
        mean = self.total_ns / self.count if self.count else 0.0
        return {
            "count": self.count,
            "last_ms": self.last_ns / 1e6,
            "min_ms": self.min_ns / 1e6,
            "max_ms": self.max_ns / 1e6,
            "mean_ms": mean / 1e6,
        }


@dataclass
class Resource:
    name: str
    clock: Clock
    state: ResourceState = ResourceState.STOP_INVALID
    artifact: Artifact | None = None
    programs: list[UserProgram] = field(default_factory=list)
    stats: CycleStats = field(default_factory=CycleStats)
    cycle_count: int = 0  # CPU cycles that ran programs, single steps included
    system: SystemView = field(default_factory=SystemView)
    globals: Any = None  # the instance behind `_G`
    global_paths: list[VariablePath] = field(default_factory=list)
    error: str | None = None  # why the resource is in ERROR STOP
    watchdog: Watchdog = field(default_factory=process_watchdog, repr=False)
    _bound: list[BoundVariable] = field(default_factory=list, init=False, repr=False)
    _by_name: dict[str, BoundVariable] = field(default_factory=dict, init=False, repr=False)

    @property
    def cycle_ns(self) -> int:
        return (self.artifact.resource.cycle_ms if self.artifact else 100) * 1_000_000

    @property
    def watchdog_ns(self) -> int:
        return (self.artifact.resource.watchdog_ms if self.artifact else 200) * 1_000_000

    # ---- commands
    def load(self, artifact: Artifact) -> None:
        """Take a whole configuration (only in STOP); a cold start state follows."""
        if self.state in (ResourceState.RUN, ResourceState.ERROR_STOP):
            raise CommandRefused("state", "a download is only possible in STOP")
        image = CodeImage(artifact, self.system)
        programs = []
        for config in sorted(artifact.programs, key=lambda p: (p.priority, p.program_id)):
            instance = image.new_instance(config.pou)
            # `prog();` in ST reaches the user program of that POU (the first by priority),
            # so a program called from another one is the same instance the task runs
            image.register_program(config.pou, instance)
            programs.append(
                UserProgram(config, instance, image.variable_paths(config.name, config.pou))
            )
        for pou in artifact.pous:  # a PROGRAM that is no user program still has one instance
            if pou.kind == "PROGRAM":
                image.register_program(pou.name, image.new_instance(pou.name))
        self.artifact, self.programs = artifact, programs
        self.globals, self.global_paths = image.globals, image.global_paths()
        self._bound = [
            *(BoundVariable(p.instance, path) for p in programs for path in p.paths),
            *(BoundVariable(self.globals, path) for path in self.global_paths),
        ]
        self._by_name = {}
        for bound in self._bound:
            self._by_name.setdefault(bound.path.path.upper(), bound)
        self.state = ResourceState.STOP_VALID
        log.info("loaded configuration %s (CRC %s)", artifact.project, artifact.crc)

    def init(self) -> None:
        """INIT: leave ERROR STOP for STOP; the next start is a cold start."""
        if self.state != ResourceState.ERROR_STOP:
            raise CommandRefused("state", "INIT leaves ERROR STOP; the resource is not in it")
        assert self.artifact is not None
        self.state, self.error = ResourceState.STOP_VALID, None
        self.load(self.artifact)  # fresh instances: every variable at its initial value

    def start(self) -> None:
        if self.state == ResourceState.STOP_INVALID:
            raise CommandRefused("state", "no valid configuration is loaded")
        if self.state == ResourceState.ERROR_STOP:
            raise CommandRefused("state", f"ERROR STOP ({self.error}): INIT first")
        if self.state == ResourceState.RUN:
            return
        self.state = ResourceState.RUN
        for program in self.programs:
            if program.state == ProgramState.STOP:
                program.state = ProgramState.RUN
            program.last_wall_ns = None

    def stop(self) -> None:
        if self.state != ResourceState.RUN:
            return
        self.state = ResourceState.STOP_VALID
        for program in self.programs:
            if program.state == ProgramState.RUN:
                program.state = ProgramState.STOP

    def step(self) -> None:
        """Run exactly one program cycle of every program, with time advancing one interval."""
        if self.state != ResourceState.STOP_VALID:
            raise CommandRefused("state", "single step needs the resource in STOP")
        self._guarded(
            [p for p in self.programs if p.state != ProgramState.ERROR], lambda p: self.cycle_ns
        )
        self.cycle_count += 1

    # ---- the cycle
    def cycle(self) -> None:
        """One CPU cycle: (inputs, forces,) programs by priority, (outputs, housekeeping)."""
        if self.state != ResourceState.RUN:
            return
        begin = self.clock.now_ns()

        def delta(program: UserProgram) -> int:
            elapsed = self.cycle_ns
            if program.last_wall_ns is not None:
                elapsed = begin - program.last_wall_ns
            program.last_wall_ns = begin
            return elapsed

        self._guarded([p for p in self.programs if p.state == ProgramState.RUN], delta)
        self.cycle_count += 1
        self.stats.record(self.clock.now_ns() - begin)

    def _guarded(self, programs: list[UserProgram], delta: Callable[[UserProgram], int]) -> None:
        """Run programs under the resource watchdog: a cycle longer than the watchdog time
        (an endless loop, say) ends in ERROR STOP, with outputs safe (when there are
        outputs) and the runtime still answering."""
        running: UserProgram | None = None
        try:
            with self.watchdog.guard(self.watchdog_ns):
                for running in programs:
                    self._run_program(running, delta(running))
        except WatchdogExpired:
            cause = f"watchdog: the cycle took longer than {self.watchdog_ns // 1_000_000} ms"
            if running is not None:
                cause += f" (in program {running.config.name})"
                running.error = cause
            self.state, self.error = ResourceState.ERROR_STOP, cause
            for program in self.programs:
                if program.state == ProgramState.RUN:
                    program.state = ProgramState.STOP
            log.error("resource %s: ERROR STOP, %s", self.name, cause)

    def _run_program(self, program: UserProgram, delta_ns: int) -> None:
        if program.cycles > 0:
            program.time_ns += delta_ns
        self.system.now_ns = program.time_ns
        try:
            program.instance()
        except Exception as exc:
            # whatever the generated code raises is a fault of this program alone: the
            # resource and its other programs must go on
            program.state = ProgramState.ERROR
            # a ProgramFault says what went wrong in ST terms; anything else is named by its
            # Python type so that a compiler defect can be told from a program error
            unexpected = not isinstance(exc, ProgramFault | ArithmeticError)
            program.error = f"{type(exc).__name__}: {exc}" if unexpected else str(exc)
            log.error("program %s: %s", program.config.name, program.error)
        program.cycles += 1

    # ---- views
    def status(self) -> dict[str, Any]:
        return {
            "resource": self.name,
            "state": self.state.value,
            "crc": self.artifact.crc if self.artifact else None,
            "error": self.error,
            "project": self.artifact.project if self.artifact else None,
            "cycle": self.cycle_count,
            "cycle_ms": self.cycle_ns / 1e6,
            "stats": self.stats.as_json(),
            "programs": [
                {
                    "name": p.config.name,
                    "id": p.config.program_id,
                    "state": p.state.value,
                    "crc": p.config.crc,
                    "cycles": p.cycles,
                    "error": p.error,
                }
                for p in self.programs
            ],
        }

    def variables(self) -> list[dict[str, str]]:
        return [{"path": bound.path.path, "type": bound.path.type} for bound in self._bound]

    def values(self) -> dict[str, Any]:
        """Every elementary variable: `Program.var`, `Program.fb.var`, globals by their bare
        name; struct and FB members with dots; arrays of elementary values as lists."""
        return {bound.path.path: read_path(bound.owner, bound.path) for bound in self._bound}

    # ---- online test
    def _lookup(self, name: str) -> BoundVariable:
        bound = self._by_name.get(name.upper())  # ST names are case-insensitive
        if bound is None:
            raise CommandRefused(
                "unknown_variable", f"resource {self.name} has no variable '{name}'"
            )
        return bound

    def variable(self, name: str) -> VariablePath:
        """The elementary variable called `name` (a path as `values()` names it)."""
        return self._lookup(name).path

    def read(self, name: str) -> Any:
        """The value of one variable, as `values()` has it."""
        bound = self._lookup(name)
        return read_path(bound.owner, bound.path)

    def write(self, name: str, value: Any) -> None:
        """Set a variable between cycles, as an online-test field does.

        The value must already be in the run-time representation of the variable's type
        (TIME in nanoseconds, REAL as float); it is checked, never wrapped to fit.
        """
        bound = self._lookup(name)
        if bound.path.constant:
            raise CommandRefused("constant", f"'{bound.path.path}' is a constant")
        try:
            stored = representation(bound.path.type, value)
        except ValueRejected as exc:
            raise CommandRefused("bad_value", f"'{bound.path.path}': {exc}") from None
        write_path(bound.owner, bound.path, stored)
