"""The Single step screen: per program Freeze, Step, Step N and Unfreeze while the other
programs keep running; and, in STOP, one cycle of the whole resource. Shows the chosen
program's state and cycle counter, so each step is seen to be exactly one cycle."""

from __future__ import annotations

import html
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import viser

from frontend.permissions import Allowed
from frontend.screen_registry import Now, Screen, Work
from frontend.state_rules import disabled_note, program_allows, resource_allows, state_words
from runtime.contract import protocol as p

MAX_STEPS = 1000

# (label, command for the chosen program, asks first)
PROGRAM_ACTIONS: tuple[tuple[str, type[p.Freeze | p.Unfreeze], bool], ...] = (
    ("Freeze", p.Freeze, True),
    ("Unfreeze", p.Unfreeze, False),
)


@dataclass
class SingleStepScreen:
    program: viser.GuiDropdownHandle[str]
    info: viser.GuiHtmlHandle
    steps: viser.GuiNumberHandle[int]
    buttons: dict[type[p.Command[Any]], list[viser.GuiButtonHandle]]
    reason: viser.GuiHtmlHandle
    shown: str = ""
    shown_reason: str = ""


def build(
    gui: viser.GuiApi,
    act: Callable[[str, Callable[[], p.Command[p.StatusReply]], str | None, int], None],
) -> SingleStepScreen:
    """`act(label, make_command, question, times)` sends `make_command()` `times` times to
    the selected resource, asking `question` first when it is not None."""
    program = gui.add_dropdown("Program", ("-",))
    info = gui.add_html("")
    buttons: dict[type[p.Command[Any]], list[viser.GuiButtonHandle]] = {}

    def add(label: str, kind: type[p.Command[Any]], clicked: Callable[[], None]) -> None:
        button = gui.add_button(label, disabled=True)
        button.on_click(lambda _: clicked())
        buttons.setdefault(kind, []).append(button)

    for label, kind, asks in PROGRAM_ACTIONS:
        question = (
            "freeze {}: it stops between cycles, its outputs hold, the other programs run on"
            if asks
            else None
        )

        def send(label: str = label, kind: Any = kind, question: str | None = question) -> None:
            name = program.value
            act(f"{label} {name}", lambda: kind(name), question and question.format(name), 1)

        add(label, kind, send)
    add("Step", p.StepProgram, lambda: act(f"Step {program.value}", _step(program), None, 1))
    steps = gui.add_number("Steps", 10, min=1, max=MAX_STEPS, step=1)
    add(
        "Step N",
        p.StepProgram,
        lambda: act(f"{steps.value} steps of {program.value}", _step(program), None, steps.value),
    )
    with gui.add_folder("Whole resource (in STOP)"):
        add("Step resource", p.Step, lambda: act("Step resource", p.Step, None, 1))
    reason = gui.add_html("")
    return SingleStepScreen(program, info, steps, buttons, reason)


def _step(program: viser.GuiDropdownHandle[str]) -> Callable[[], p.Command[p.StatusReply]]:
    name = program.value
    return lambda: p.StepProgram(name)


def refresh(
    screen: SingleStepScreen,
    status: p.Status | None,
    allowed: Callable[[type[p.Command[Any]]], Allowed],
) -> None:
    programs = tuple(x.name for x in status.programs) if status is not None else ()
    programs = programs or ("-",)  # a dropdown needs an option (no configuration: no program)
    if tuple(screen.program.options) != programs:
        screen.program.options = programs
    chosen = (
        next((x for x in status.programs if x.name == screen.program.value), None)
        if (status is not None)
        else None
    )
    page = render(status, chosen)
    reasons: list[str] = []  # the levels' first, then each button's state's
    by_state: list[str] = []
    for kind, buttons in screen.buttons.items():
        verdict = allowed(kind) if status is not None else Allowed(False, "no resource")
        if verdict.reason and verdict.reason not in reasons:
            reasons.append(verdict.reason)
        if verdict.ok and status is not None:
            verdict = (
                resource_allows(kind, status)
                if kind is p.Step
                else program_allows(kind, status, chosen)
                if chosen is not None
                else Allowed(False, "choose a program")
            )
            if verdict.reason:
                labels = ", ".join(button.label for button in buttons)
                by_state.append(f"{labels}: {verdict.reason}")
        for button in buttons:
            button.disabled = not verdict.ok
            button.hint = verdict.reason or None
    note = disabled_note("step-disabled", reasons + by_state)
    if page != screen.shown:
        screen.info.content = page
        screen.shown = page
    if note != screen.shown_reason:
        screen.reason.content = note
        screen.shown_reason = note


def render(status: p.Status | None, chosen: p.ProgramStatus | None) -> str:
    if status is None:
        return "<p>Select a resource you are logged in to.</p>"
    rows = [("Resource", f"{state_words(status.state)}, cycle {status.cycle}")]
    if chosen is not None:
        rows += [
            ("Program state", state_words(chosen.state)),
            ("Program cycles", str(chosen.cycles)),
        ]
    cells = "".join(
        f'<tr><td style="color:#868e96;padding:2px 12px 2px 0">{name}</td>'
        f'<td data-step="{name}" style="font-family:monospace">{html.escape(value)}</td></tr>'
        for name, value in rows
    )
    return f'<table style="font-size:0.9em">{cells}</table>'


class SingleStep(Screen):
    name = "Single step"
    icon = viser.Icon.PLAYER_TRACK_NEXT

    def __init__(self, work: Work) -> None:
        super().__init__(work)
        self.screen = build(work.gui, work.act)

    def refresh(self, now: Now) -> None:
        refresh(self.screen, now.status, self.work.allowed)
