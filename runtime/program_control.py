"""Starting, stopping and single-stepping one user program (spec sections 4 and 12): the
program commands, each checked against the resource's state and the program's parameters,
each an event. The other programs keep running."""

from __future__ import annotations

from runtime.code.user_program import UserProgram
from runtime.contract.protocol import ProgramState, ResourceState
from runtime.contract.refusal import Refusal
from runtime.image_switch import leave_image
from runtime.resource import Resource


def start_program(resource: Resource, name: str) -> None:
    program = resource.variables.program(name)
    if not resource.running():
        raise Refusal("state", "a program starts only while the resource runs")
    if not program.config.start_allowed:
        raise Refusal("not_allowed", f"Start Allowed of {program.name} is OFF")
    if program.state == ProgramState.ERROR:
        program = _restart_cold(resource, program)
    if program.state != ProgramState.STOP:
        return
    program.state, program.last_start_ns, program.held = ProgramState.RUN, None, False
    resource.recorder.record("program", f"program {program.name} started", program=program.name)


def stop_program(resource: Resource, name: str) -> None:
    program = resource.variables.program(name)
    if program.state not in (ProgramState.RUN, ProgramState.RUN_FREEZE, ProgramState.BKPT):
        return
    resource.refuse_read_only("program stop")
    if program.state is ProgramState.BKPT:  # it leaves its breakpoint for STOP
        resource.debugger.forget(resource, "the program stopped")
    program.abandon()
    program.state = ProgramState.STOP
    resource.forcing.end_program(program.name)
    resource.recorder.record("program", f"program {program.name} stopped", program=program.name)


def _restart_cold(resource: Resource, program: UserProgram) -> UserProgram:
    """A program leaves ERROR by a start: from its initial values (its state after the
    error is not to be trusted)."""
    if resource.variables.image is not None:  # back to objects: the tier moves them again
        leave_image(resource.variables)
    code = resource.variables.code
    assert code is not None
    fresh = code.new_instance(program.config.pou)
    replacement = UserProgram(program.config, fresh, program.paths, program.view)
    resource.variables.replace_program(program, replacement)
    replacement.state = ProgramState.STOP
    return replacement


def freeze(resource: Resource, name: str) -> None:
    """Single step on: the program runs one program cycle per `step_program`."""
    program = resource.variables.program(name)
    if not program.config.freeze_allowed:
        raise Refusal("not_allowed", f"Freeze Allowed of {program.name} is OFF")
    if resource.params.safety_operation:
        raise Refusal("safety_operation", "no single step in safety operation")
    if resource.state != ResourceState.RUN or program.state != ProgramState.RUN:
        raise Refusal("state", f"program {program.name} is not running")
    if program.in_progress:
        # finish the program cycle in progress first: a frozen program always stands
        # between two program cycles
        resource.scheduler.run_to_end(program)
    program.state = ProgramState.RUN_FREEZE
    resource.recorder.record("program", f"program {program.name} frozen (single step)")


def unfreeze(resource: Resource, name: str) -> None:
    program = resource.variables.program(name)
    if program.state != ProgramState.RUN_FREEZE:
        raise Refusal("state", f"program {program.name} is not in single step")
    program.state, program.last_start_ns = ProgramState.RUN, None
    resource.recorder.record("program", f"program {program.name} leaves single step")


def step_program(resource: Resource, name: str, interval_ns: int | None = None) -> None:
    """One whole program cycle of a frozen program; its time advances by one cycle
    interval, so its timers behave as in operation."""
    program = resource.variables.program(name)
    if program.state != ProgramState.RUN_FREEZE:
        raise Refusal("state", f"program {program.name} is not in single step")
    step = interval_ns if interval_ns is not None else resource.cycle_ns
    resource.scheduler.guarded(lambda: resource.scheduler.run_to_end(program, step))
    resource.variables.publish([program])
    resource.forcing.apply()
    resource.io.write_outputs(safe=False)
    resource.recorder.record(
        "program",
        f"program {program.name} stepped one cycle (program cycle {program.stats.count})",
        program=program.name,
    )
