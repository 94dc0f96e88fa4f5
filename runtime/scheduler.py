"""The user programs in the CPU cycle (spec section 5): by priority, each in its time slice,
under the resource watchdog; the multitasking modes decide what happens with the time a
program leaves unused; the user-program watchdog and run-time errors put one program in
ERROR while the others go on."""

from __future__ import annotations

import logging
from collections.abc import Callable
from typing import Any, Protocol

from runtime.clock import Clock
from runtime.code.intrinsics import (
    EMERGENCY_STOPS,
    ProgramFault,
    SystemView,
    emergency_switches,
)
from runtime.code.user_program import UserProgram
from runtime.contract.artifact import ResourceConfig
from runtime.contract.protocol import ProgramState
from runtime.event_recorder import EventRecorder
from runtime.slicing import SliceMeter
from runtime.variables import Variables
from runtime.watchdog import Watchdog, WatchdogExpired, process_watchdog

log = logging.getLogger("runtime.resource")

# read every CPU cycle for every program: a member of an enum class costs a lookup that a
# module constant does not (in CPython 3.11 as long as an empty program's whole call)
_RUN = ProgramState.RUN
# the switches `run` tests by name, as BOOL values (every writer stores a bool)
assert tuple(f"EMERGENCY_STOP_{n}" for n in (1, 2, 3, 4)) == EMERGENCY_STOPS, EMERGENCY_STOPS


class SchedulerHost(Protocol):
    """What the scheduler needs of its resource."""

    @property
    def params(self) -> ResourceConfig: ...

    @property
    def system(self) -> SystemView: ...

    @property
    def cycle_ns(self) -> int: ...

    def error_stop(self, cause: str) -> None: ...

    def emergency_stopped(self) -> bool:
        """Asked when an Emergency Stop switch is on (`emergency_switches`): True when it
        has just put the resource in ERROR STOP."""
        ...


class Halted(BaseException):
    """Ends the CPU cycle at once (Emergency Stop); caught by nothing but `run` and
    `guarded`."""


class Scheduler:
    # slots: the CPU cycle in C reads them at their offsets (padt_cycle.c)
    __slots__ = (
        "_clock",
        "_host",
        "_recorder",
        "_variables",
        "meter",
        "used_ns",
        "watchdog",
    )

    def __init__(
        self, host: SchedulerHost, variables: Variables, recorder: EventRecorder, clock: Clock
    ) -> None:
        self._host, self._variables = host, variables
        self._recorder, self._clock = recorder, clock
        self.watchdog: Watchdog = process_watchdog()
        self.meter = SliceMeter(virtual=clock.virtual)
        # the time the metered slices of the current CPU cycle used: what a virtual clock
        # counts as the cycle's duration, and what the multitasking modes budget with
        self.used_ns = 0

    @property
    def watchdog_ns(self) -> int:
        return self._host.params.watchdog_ms * 1_000_000

    def run(self, begin: int, finished: list[UserProgram]) -> bool:
        """The programs of a CPU cycle by priority, each in its slice, under the resource
        watchdog, as `guarded` runs other work; multitasking modes 2 and 3 decide what
        happens with the time a program leaves unused. Written out for the CPU cycle, the
        usual program (no slice, no debugging) in one call (`UserProgram.run_whole`): each
        Python call saved is a fiftieth of an empty CPU cycle. False when the resource
        halted."""
        watchdog, host, variables = self.watchdog, self._host, self._variables
        try:
            watchdog.arm(host.params.watchdog_ms * 1_000_000)
            try:
                self.used_ns = unused_ns = 0
                code, system, master = variables.code, host.system, variables.globals
                assert code is not None
                names = code.namespace
                # no copy of the list: a program run never changes it (a restart replaces a
                # program between cycles, and in place)
                for program in variables.programs:
                    if program.state is not _RUN:
                        continue
                    if program.run is None:  # a new program cycle: its time advances by
                        # the clock's time since its last program cycle started
                        last = program.last_start_ns
                        program.last_start_ns = begin
                        delta = host.cycle_ns if last is None else begin - last
                        if program.whole:
                            try:
                                program.run_whole(delta, master, system, names)
                                finished.append(program)
                            except (Exception, RecursionError) as exc:
                                self._program_fault(program, exc)
                            if (  # `emergency_switches` written out (a fifth of the loop)
                                system.EMERGENCY_STOP_1
                                or system.EMERGENCY_STOP_2
                                or system.EMERGENCY_STOP_3
                                or system.EMERGENCY_STOP_4
                            ) and host.emergency_stopped():
                                raise Halted()
                            continue
                        program.begin_cycle(delta, master)
                    unused_ns += self._sliced(program, finished)
                if host.params.multitasking_mode == 2:
                    self._extra_slices(unused_ns, finished)
            finally:
                fired = watchdog.disarm()
            if fired:  # it fired just as the work ended: too long all the same
                raise WatchdogExpired()
            return True
        except Halted:  # an Emergency Stop: already in ERROR STOP
            return False
        except WatchdogExpired as exc:
            self._watchdog_expired(exc)
            return False

    def _sliced(self, program: UserProgram, finished: list[UserProgram]) -> int:
        """A program with a time slice (or debugged) on in its slice; the time it left
        unused, which mode 3 waits out."""
        budget = program.config.max_duration_us * 1000 or None
        used, done = self._slice(program, budget)
        if done:
            finished.append(program)
        elif program.state is _RUN:
            self._check_program_watchdog(program)
        if budget is None:
            return 0
        if self._host.params.multitasking_mode == 3 and used < budget:
            self._wait(budget - used)  # every cycle as long as the worst case
        return max(0, budget - used)

    def _extra_slices(self, unused_ns: int, finished: list[UserProgram]) -> None:
        """Mode 2: the time the programs left unused goes to those still in their program
        cycle, by priority."""
        for program in list(self._variables.programs):
            if unused_ns <= 0:
                break
            if program.state is _RUN and program.in_progress:
                used, done = self._slice(program, unused_ns, extra=True)
                unused_ns -= used
                if done:
                    finished.append(program)

    def run_to_end(self, program: UserProgram, step_ns: int | None = None) -> None:
        """A whole program cycle at once (single step, a debugging step): no slice limit."""
        if not program.in_progress:
            program.begin_cycle(
                step_ns if step_ns is not None else self._host.cycle_ns, self._variables.globals
            )
        # until it ends, fails or stops at a breakpoint
        while program.in_progress and program.state not in (ProgramState.ERROR, ProgramState.BKPT):
            self._slice(program, None)

    def guarded(self, work: Callable[..., None], *args: Any) -> bool:
        """Work under the resource watchdog (single steps; `run` for a CPU cycle): work
        longer than the watchdog time (an endless loop, say) ends in ERROR STOP, and the
        runtime still answers. False when the resource halted."""
        watchdog = self.watchdog
        try:
            watchdog.arm(self._host.params.watchdog_ms * 1_000_000)
            try:
                work(*args)
            finally:
                fired = watchdog.disarm()
            if fired:  # it fired just as the work ended: too long all the same
                raise WatchdogExpired()
            return True
        except Halted:  # an Emergency Stop: already in ERROR STOP
            return False
        except WatchdogExpired as exc:
            self._watchdog_expired(exc)
            return False

    def _watchdog_expired(self, exc: WatchdogExpired) -> None:
        """ERROR STOP, saying where the cycle was when the watchdog struck."""
        running = [p.name for p in self._variables.programs if p.in_progress]
        cause = f"watchdog: the cycle took longer than {self.watchdog_ns // 1_000_000} ms"
        if running:
            cause += f" (in program {running[-1]})"
        # the endless loop, as a rule
        code = self._variables.code
        where = code.locate(exc) if code is not None else None
        if where is not None:
            cause += f" in {where}"
        self._host.error_stop(cause)

    def _slice(
        self, program: UserProgram, budget_ns: int | None, extra: bool = False
    ) -> tuple[int, bool]:
        """Run a program on for at most `budget_ns`; (time used, program cycle ended).
        A run-time error puts the program in ERROR; the others go on."""
        code, meter = self._variables.code, self.meter
        assert code is not None
        done = False
        try:
            if extra:  # more time for a program in its CPU cycle: not another CPU cycle
                program.cpu_cycles -= 1
            self._host.system.now_ns = program.cycle_time_ns
            code.use(program.view, meter.tick if budget_ns is not None else None)
            meter.begin(budget_ns)
            done = program.resume()
        except (Exception, RecursionError) as exc:
            self._program_fault(program, exc)
        used = meter.used_ns()
        self.used_ns += used
        if True in emergency_switches(self._host.system) and self._host.emergency_stopped():
            raise Halted()
        return used, done

    def _check_program_watchdog(self, program: UserProgram) -> None:
        """A program cycle may span Max. Cycles CPU cycles of Max. Duration each."""
        config = program.config
        if program.cpu_cycles >= config.max_cycles:
            program.abandon()
            program.state = ProgramState.ERROR
            program.error = (
                f"program watchdog: the program cycle did not end within {config.max_cycles} "
                f"CPU cycle(s) of {config.max_duration_us} us"
            )
            self._recorder.record(
                "error", f"program {program.name}: {program.error}", long_term=True
            )

    def _program_fault(self, program: UserProgram, exc: BaseException) -> None:
        code = self._variables.code
        assert code is not None
        program.abandon()
        program.state = ProgramState.ERROR
        # a ProgramFault says what went wrong in ST terms; anything else is named by its
        # Python type so that a compiler defect can be told from a program error
        if isinstance(exc, RecursionError):
            cause = "calls nested too deep (recursion)"
        elif isinstance(exc, ProgramFault | ArithmeticError):
            cause = str(exc)
        else:
            cause = f"{type(exc).__name__}: {exc}"
        where = code.locate(exc)
        program.error = f"{cause} in {where}" if where is not None else cause
        details: dict[str, Any] = {"program": program.name, "cause": cause}
        if where is not None:
            details.update(pou=where.pou, file=where.file, line=where.line)
        self._recorder.record(
            "error", f"program {program.name}: {program.error}", long_term=True, **details
        )
        log.error("program %s: %s", program.name, program.error)

    def _wait(self, duration_ns: int) -> None:
        if self._clock.virtual:
            self.used_ns += duration_ns
        else:
            self._clock.sleep_until(self._clock.now_ns() + duration_ns)
