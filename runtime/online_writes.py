"""Setting a variable from outside the programs (spec section 11): a write from an OLT
field (once, not forcing; refused in safety operation; an event with the old and new
value), and a simulated plant setting a value (`padt sim --set`: no event, allowed in
safety operation, since no real plant is behind it)."""

from __future__ import annotations

from runtime.contract.refusal import Refusal
from runtime.contract.values import format_value
from runtime.resource import Resource


def write(resource: Resource, name: str, value: object, user: str | None = None) -> None:
    """Write a value once: a forced variable keeps its force value at the next cycle.
    `user`: who wrote it, where not the sender of the command being carried out (an OPC
    UA client's write)."""
    if resource.params.safety_operation:
        raise Refusal("safety_operation", "no writes from OLT in safety operation")
    variables = resource.variables
    bound = variables.lookup_to_write(name)
    stored = variables.checked(bound, value)
    old = variables.read(bound)
    variables.store(bound, stored)
    kind = bound.path.type
    resource.recorder.record(
        "write",
        # as people write values (T#1s500ms, TRUE); the details keep the run-time values
        f"{bound.path.path} written: {format_value(old, kind)} -> {format_value(stored, kind)}",
        user=user,
        variable=bound.path.path,
        old=old,
        new=stored,
    )


def simulate(resource: Resource, name: str, value: object) -> None:
    variables = resource.variables
    bound = variables.lookup(name)
    variables.store(bound, variables.checked(bound, value))
