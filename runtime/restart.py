"""Warm start (spec section 10): the context a resource saves between two cycles, and
taking a valid one back at power-up. Safety-related programs always cold-start."""

from __future__ import annotations

from runtime.code.user_program import share_globals
from runtime.context import Context
from runtime.context_snapshot import ContextMismatch, capture, restore, snapshot
from runtime.contract.protocol import ProgramState
from runtime.resource import Resource


def take_context(resource: Resource, *, deferred: bool = False) -> Context | None:
    """A consistent image of everything a warm start needs (taken between cycles). With
    `deferred`, arrays of value-only structs are taken as rows and made tree nodes when
    the context is encoded (`capture`): what the periodic save on the cycle thread uses."""
    if resource.artifact is None:
        return None
    take = capture if deferred else snapshot
    programs = {
        p.name: {"state": p.state.value, "time_ns": p.time_ns, "values": take(p.instance)}
        for p in resource.programs
    }
    globals_ = resource.variables.globals
    return Context(
        signature=resource.artifact.crc,
        saved_ns=resource.clock.wall_ns(),
        resource={"state": resource.state.value, "cycle": resource.cycle_count},
        programs=programs,
        globals=take(globals_) if globals_ is not None else None,
    )


def warm_start(resource: Resource, context: Context) -> list[str]:
    """Take the values of a valid context (in STOP, after a load): the next start is a warm
    start. Safety-related programs keep their initial values: they always cold-start.
    Returns the programs restored."""
    resource.require_stop("a warm start")
    restored = []
    try:
        restore(resource.variables.globals, context.globals)
        for program in resource.programs:
            saved = context.programs.get(program.name)
            if saved is None or program.config.safety_related:
                continue
            restore(program.instance, saved["values"])
            # timers and step times hold absolute program time: it comes back too
            program.time_ns = int(saved["time_ns"])
            program.held = saved["state"] in (ProgramState.STOP, ProgramState.ERROR)
            restored.append(program.name)
    except (ContextMismatch, KeyError, TypeError, ValueError) as exc:
        resource.instantiate()  # nothing half-restored
        resource.recorder.record("state", f"cold start: the saved context does not fit ({exc})")
        return []
    share_globals(resource.variables.globals, resource.programs)
    resource.start_kind = "warm"
    resource.recorder.record(
        "state", f"warm start prepared from the context saved at {context.saved_ns}"
    )
    return restored
