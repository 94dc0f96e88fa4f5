"""A resource: one controller with its loaded configuration, user programs and states.

This is the state that the rest of the runtime protects: only the cycle thread calls its
methods (commands reach it through the cycle driver's queue), so it needs no locks.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from enum import StrEnum
from typing import Any

from runtime.artifact import Artifact, ProgramConfig
from runtime.clock import Clock
from runtime.code_image import CodeImage, VariablePath, read_path
from runtime.intrinsics import ProgramFault, SystemView

log = logging.getLogger(__name__)


class ResourceState(StrEnum):
    STOP_INVALID = "STOP/INVALID CONFIGURATION"
    STOP_VALID = "STOP/VALID CONFIGURATION"
    RUN = "RUN"


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

    @property
    def cycle_ns(self) -> int:
        return (self.artifact.resource.cycle_ms if self.artifact else 100) * 1_000_000

    # ---- commands
    def load(self, artifact: Artifact) -> None:
        """Take a whole configuration (only in STOP); a cold start state follows."""
        if self.state == ResourceState.RUN:
            raise CommandRefused("state", "a download is only possible in STOP")
        image = CodeImage(artifact, self.system)
        programs = []
        for config in sorted(artifact.programs, key=lambda p: (p.priority, p.program_id)):
            instance = image.new_instance(config.pou)
            programs.append(
                UserProgram(config, instance, image.variable_paths(config.name, config.pou))
            )
        self.artifact, self.programs = artifact, programs
        self.state = ResourceState.STOP_VALID
        log.info("loaded configuration %s (CRC %s)", artifact.project, artifact.crc)

    def start(self) -> None:
        if self.state == ResourceState.STOP_INVALID:
            raise CommandRefused("state", "no valid configuration is loaded")
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
        for program in self.programs:
            if program.state != ProgramState.ERROR:
                self._run_program(program, self.cycle_ns)
        self.cycle_count += 1

    # ---- the cycle
    def cycle(self) -> None:
        """One CPU cycle: (inputs, forces,) programs by priority, (outputs, housekeeping)."""
        if self.state != ResourceState.RUN:
            return
        begin = self.clock.now_ns()
        for program in self.programs:
            if program.state != ProgramState.RUN:
                continue
            delta = self.cycle_ns
            if program.last_wall_ns is not None:
                delta = begin - program.last_wall_ns
            program.last_wall_ns = begin
            self._run_program(program, delta)
        self.cycle_count += 1
        self.stats.record(self.clock.now_ns() - begin)

    def _run_program(self, program: UserProgram, delta_ns: int) -> None:
        if program.cycles > 0:
            program.time_ns += delta_ns
        self.system.now_ns = program.time_ns
        try:
            program.instance()
        except (ProgramFault, ArithmeticError, RecursionError, ValueError, TypeError) as exc:
            program.state = ProgramState.ERROR
            program.error = str(exc)
            log.error("program %s: %s", program.config.name, exc)
        program.cycles += 1

    # ---- views
    def status(self) -> dict[str, Any]:
        return {
            "resource": self.name,
            "state": self.state.value,
            "crc": self.artifact.crc if self.artifact else None,
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
        return [
            {"path": path.path, "type": path.type}
            for program in self.programs
            for path in program.paths
        ]

    def values(self) -> dict[str, Any]:
        return {
            path.path: read_path(program.instance, path)
            for program in self.programs
            for path in program.paths
        }
