"""The usual CPU cycle of a resource in C (`code/native/padt_cycle.c`; docs/native-code.md,
"The CPU cycle in C"): on the native tier, `Resource.cycle` asks its core first, which runs
the cycle when it is a usual one and leaves any other to the Python cycle, the reference.

`padt_cycle.c` is compiled once per machine into the native cache, like `padt_memory`, and
loaded once per process (`NativeTier.cycle_module`).
"""

from __future__ import annotations

from types import ModuleType
from typing import Any, Protocol

from runtime.clock import RealClock, VirtualClock
from runtime.code.intrinsics import SystemView
from runtime.code.user_program import DIRECT, ProgramCycleStats, UserProgram, copy_globals
from runtime.contract.protocol import ProgramState, ResourceState
from runtime.cycle_stats import MIN_TOLERANCE_NS, CycleStats
from runtime.force_table import ForceTable
from runtime.scheduler import Halted
from runtime.watchdog import WatchdogExpired

_CLOCK_KINDS = {RealClock: 0, VirtualClock: 1}  # padt_cycle.c's CLOCK_REAL, CLOCK_VIRTUAL


class CycleCore(Protocol):
    def cycle(self) -> bool:
        """The usual CPU cycle, run: True; False when it is not a usual one (nothing
        changed), for the Python cycle to run."""
        ...


def cycle_core(module: ModuleType, resource: Any) -> CycleCore | None:
    """The core of `resource`'s cycle, or None where its clock is neither a real nor a
    virtual one (the Python cycle runs every cycle then)."""
    kind = _CLOCK_KINDS.get(type(resource.clock))
    if kind is None:
        return None
    watchdog = resource.scheduler.watchdog
    core: CycleCore = module.Core(
        resource,
        resource.clock,
        kind,
        resource.io,
        resource.forcing,
        resource.debugger,
        resource.variables,
        resource.scheduler,
        watchdog,
        resource.system,
        watchdog.deadlines,
        (SystemView, CycleStats, UserProgram, ProgramCycleStats, ForceTable),
        (ResourceState.RUN, ResourceState.RUN_UP_STOP),
        ProgramState.RUN,
        DIRECT,
        copy_globals,
        WatchdogExpired,
        Halted,
        MIN_TOLERANCE_NS,
    )
    return core
