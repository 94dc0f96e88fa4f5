"""What the state of a resource and of its programs allows, so that the screens enable
only the commands that would do something and say why the others are greyed out; and the
states in the words of the docs ("RUN (frozen)", not `RUN_FREEZE`). The resource checks
its state itself all the same (a command it would refuse or ignore)."""

from __future__ import annotations

import html
from typing import Any

from frontend.permissions import Allowed
from runtime.contract import protocol as p

_WORDS: dict[str, str] = {p.ProgramState.RUN_FREEZE.value: "RUN (frozen)"}
_RUNNING = (p.ResourceState.RUN, p.ResourceState.RUN_UP_STOP)


def state_words(state: str) -> str:
    """A state of a resource or a program as the docs name it."""
    return _WORDS.get(state, state)


def resource_allows(command: type[p.Command[Any]], status: p.Status) -> Allowed:
    """Whether the resource's state lets `command` (Start, Stop, Cold start, Init, Step)
    do anything."""
    state = status.state
    if command is p.Start:
        if state == p.ResourceState.STOP_INVALID:
            return Allowed(False, "no valid configuration is loaded")
        if state == p.ResourceState.ERROR_STOP:
            return Allowed(False, "ERROR STOP: Init first")
        if state in _RUNNING:
            return Allowed(False, "the resource runs already")
    if command is p.Stop and state not in _RUNNING:
        return Allowed(False, "the resource is not running")
    if command in (p.ColdStart, p.Step) and state != p.ResourceState.STOP_VALID:
        return Allowed(False, "only in STOP")
    if command is p.Init and state != p.ResourceState.ERROR_STOP:
        return Allowed(False, "only in ERROR STOP")
    return Allowed(True)


def program_allows(
    command: type[p.Command[Any]], status: p.Status, program: p.ProgramStatus
) -> Allowed:
    """Whether the states of the resource and of `program` let `command` (Start program,
    Stop program, Freeze, Unfreeze, Step) do anything."""
    state, name = program.state, program.name
    running = status.state in _RUNNING
    if command is p.StartProgram:
        if not running:
            return Allowed(False, "a program starts only while the resource runs")
        if state not in (p.ProgramState.STOP, p.ProgramState.ERROR):
            return Allowed(False, f"{name} runs already")
    if command is p.StopProgram and state not in (
        p.ProgramState.RUN,
        p.ProgramState.RUN_FREEZE,
        p.ProgramState.BKPT,  # it leaves its breakpoint for STOP
    ):
        return Allowed(False, f"{name} is not running")
    if command is p.Freeze and (status.state != p.ResourceState.RUN or state != p.ProgramState.RUN):
        frozen = state == p.ProgramState.RUN_FREEZE
        return Allowed(False, f"{name} is frozen already" if frozen else f"{name} is not running")
    if command in (p.Unfreeze, p.StepProgram) and state != p.ProgramState.RUN_FREEZE:
        return Allowed(False, f"freeze {name} first")
    return Allowed(True)


def disabled_note(testid: str, reasons: list[str]) -> str:
    """Beside the buttons, why they are greyed out (viser shows no tooltip on a disabled
    button): the levels' reasons, then each state's, "Start: the resource runs already"."""
    if not reasons:
        return ""
    text = "; ".join(html.escape(reason) for reason in reasons)
    return f'<div data-testid="{testid}" style="color:#868e96">Disabled: {text}</div>'
