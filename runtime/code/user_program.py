"""A user program on a resource: its instance, state, own time, and its program cycle in
progress (which may span several CPU cycles when it has a time slice)."""

from __future__ import annotations

import copy
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from runtime.code.code_image import VariablePath, slot_names
from runtime.contract.artifact import ProgramConfig
from runtime.contract.protocol import ProgramState
from runtime.slicing import ProgramRun

_SCALARS = (bool, int, float, str)


def copy_globals(source: Any, target: Any, attrs: tuple[str, ...]) -> None:
    """Copy globals between views by value: a view must never share a list or a struct
    with another, or a write in one program would show in another at once. Views of a
    memory image copy their members' bytes (padt_memory's `__padt_copy__`), at once."""
    by_bytes = getattr(source, "__padt_copy__", None)
    if by_bytes is not None and type(target) is type(source):
        by_bytes(target, attrs)
        return
    for attr in attrs:
        setattr(target, attr, _copied(getattr(source, attr)))


def _copied(value: Any) -> Any:
    """A value no other holder shares: a scalar as it is, an array of scalars as a new list
    (every element of an array has one type: a tenth of `deepcopy`'s time), the rest deep."""
    if isinstance(value, _SCALARS):
        return value
    if type(value) is list and (not value or isinstance(value[0], _SCALARS)):
        return value[:]
    return copy.deepcopy(value)


def share_globals(master: Any, programs: list[UserProgram]) -> None:
    """Every global as `master` holds it, into every program's own view (after values
    came from elsewhere: a warm start, a reload)."""
    if master is None:
        return
    attrs = tuple(slot_names(master))
    for program in programs:
        if program.view is not master:
            copy_globals(master, program.view, attrs)


@dataclass(slots=True)  # slots: the CPU cycle in C writes them (padt_cycle.c)
class ProgramCycleStats:
    count: int = 0  # completed program cycles
    last_cpu_cycles: int = 0  # CPU cycles the last program cycle spanned
    max_cpu_cycles: int = 0


class _Direct:
    """The program cycle of a program without a time slice: a plain call."""


DIRECT = _Direct()  # the run of every program cycle without a slice


class UserProgram:
    """State of one user program; only the CPU cycle (through the resource) changes it."""

    # slots: the CPU cycle in C reads and writes them (padt_cycle.c)
    __slots__ = (
        "_debug_run",
        "config",
        "cpu_cycles",
        "cycle_time_ns",
        "error",
        "held",
        "instance",
        "last_start_ns",
        "paths",
        "run",
        "state",
        "stats",
        "time_ns",
        "view",
        "whole",
    )

    def __init__(
        self, config: ProgramConfig, instance: Any, paths: list[VariablePath], view: Any
    ) -> None:
        self.config = config
        self.instance = instance
        self.paths = paths
        self.view = view  # the globals this program reads and writes (`_G` while it runs)
        self.state = ProgramState.STOP
        self.held = False  # stays in STOP when the resource starts (warm start of a stopped one)
        self.time_ns = 0  # the program's own time: what its timers see
        self.last_start_ns: int | None = None  # clock time its last program cycle started
        self.error: str | None = None
        self.stats = ProgramCycleStats()
        self.run: ProgramRun | _Direct | None = None  # a program cycle in progress
        self.cpu_cycles = 0  # CPU cycles the program cycle in progress has had so far
        self.cycle_time_ns = 0  # program time during the program cycle in progress
        # while a breakpoint may stop it: makes its program cycle's run (runtime/debugging)
        self._debug_run: Callable[[Any], ProgramRun] | None = None
        # a plain call does the whole program cycle: no time slice, no debugging (read by
        # the scheduler every CPU cycle, so kept as one attribute)
        self.whole = not self.sliced

    @property
    def name(self) -> str:
        return self.config.name

    @property
    def sliced(self) -> bool:
        return self.config.max_duration_us > 0

    @property
    def debug_run(self) -> Callable[[Any], ProgramRun] | None:
        return self._debug_run

    @debug_run.setter
    def debug_run(self, make: Callable[[Any], ProgramRun] | None) -> None:
        self._debug_run = make
        self.whole = make is None and not self.sliced

    @property
    def in_progress(self) -> bool:
        return self.run is not None

    def begin_cycle(self, delta_ns: int, master: Any) -> None:
        """Start a program cycle: time advances by `delta_ns` (not for the very first one),
        and the globals it reads are taken as they are now."""
        if self.stats.count > 0:
            self.time_ns += delta_ns
        self.cycle_time_ns = self.time_ns
        if self.view is not master:
            copy_globals(master, self.view, self.config.reads)
        # only a program that may be suspended needs a stack of its own
        if self._debug_run is not None:
            self.run = self._debug_run(self.instance)
        else:
            self.run = ProgramRun(self.instance) if self.config.max_duration_us > 0 else DIRECT
        self.cpu_cycles = 0

    def run_whole(self, delta_ns: int, master: Any, system: Any, names: dict[str, Any]) -> None:
        """A whole program cycle in one call: what `begin_cycle`, `CodeImage.use` (into
        `names`, its namespace) and `resume` do for a program without a time slice or
        debugging, written out, since it is the usual case of every CPU cycle (each Python
        call saved is a fiftieth of an empty one). Raises what the program raises, leaving
        the program cycle in progress (the scheduler abandons it)."""
        stats = self.stats
        if stats.count > 0:
            self.time_ns += delta_ns
        system.now_ns = self.cycle_time_ns = self.time_ns
        view = self.view
        if view is not master:
            copy_globals(master, view, self.config.reads)
        names["_G"] = view
        names["_tick"] = None  # loop passes are not metered
        self.run = DIRECT  # in progress: the watchdog names the program it struck in
        self.cpu_cycles = 1
        self.instance()
        stats.count += 1
        stats.last_cpu_cycles = 1
        if not stats.max_cpu_cycles:
            stats.max_cpu_cycles = 1
        self.run = None

    def resume(self) -> bool:
        """Run the program cycle on until it ends (True) or its slice is used (False)."""
        assert self.run is not None
        self.cpu_cycles += 1
        run = self.run
        if run is DIRECT:  # the usual case: a test of identity, not an isinstance() call
            self.instance()
        else:
            assert isinstance(run, ProgramRun)
            if not run.resume():
                return False
        stats = self.stats
        stats.count += 1
        stats.last_cpu_cycles = self.cpu_cycles
        if self.cpu_cycles > stats.max_cpu_cycles:  # a comparison, not a max() call
            stats.max_cpu_cycles = self.cpu_cycles
        self.run = None
        return True

    def publish(self, master: Any) -> None:
        """The end of a program cycle: what it wrote to its own view of the globals
        becomes visible."""
        copy_globals(self.view, master, self.config.writes)

    def abandon(self) -> None:
        """Drop the program cycle in progress (stop, ERROR): a warm restart begins its
        program cycle from the start."""
        if isinstance(self.run, ProgramRun):
            self.run.abandon()
        self.run = None
        self.cpu_cycles = 0
