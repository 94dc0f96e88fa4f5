"""Warm start (spec section 10): the context a resource saves between two cycles, and
taking a valid one back at power-up. Safety-related programs always cold-start."""

from __future__ import annotations

from runtime.context import Context
from runtime.context_snapshot import ContextMismatch
from runtime.contract.protocol import ProgramState
from runtime.memory import ValueTrees
from runtime.resource import Resource


def take_context(resource: Resource, *, deferred: bool = False) -> Context | None:
    """A consistent image of everything a warm start needs (taken between cycles). With
    `deferred`, arrays of value-only structs are taken as rows and made tree nodes when
    the context is encoded (`capture`): what the periodic save on the cycle thread uses."""
    if resource.artifact is None:
        return None
    trees = resource.variables.memory.take(deferred=deferred)
    programs = {
        p.name: {"state": p.state.value, "time_ns": p.time_ns, "values": trees.programs[p.name]}
        for p in resource.programs
    }
    return Context(
        signature=resource.artifact.crc,
        saved_ns=resource.clock.wall_ns(),
        resource={"state": resource.state.value, "cycle": resource.cycle_count},
        programs=programs,
        globals=trees.globals,
    )


def warm_start(resource: Resource, context: Context) -> list[str]:
    """Take the values of a valid context (in STOP, after a load): the next start is a warm
    start. Safety-related programs keep their initial values: they always cold-start.
    Returns the programs restored."""
    resource.require_stop("a warm start")
    taken = [
        (program, saved)
        for program in resource.programs
        if (saved := context.programs.get(program.name)) is not None
        and not program.config.safety_related
    ]
    try:
        values = {program.name: saved["values"] for program, saved in taken}
        resource.variables.memory.restore(ValueTrees(context.globals, values))
        for program, saved in taken:
            # timers and step times hold absolute program time: it comes back too
            program.time_ns = int(saved["time_ns"])
            program.held = saved["state"] in (ProgramState.STOP, ProgramState.ERROR)
    except (ContextMismatch, KeyError, TypeError, ValueError) as exc:
        resource.instantiate()  # nothing half-restored
        resource.recorder.record("state", f"cold start: the saved context does not fit ({exc})")
        return []
    resource.start_kind = "warm"
    resource.recorder.record(
        "state", f"warm start prepared from the context saved at {context.saved_ns}"
    )
    return [program.name for program, _ in taken]
