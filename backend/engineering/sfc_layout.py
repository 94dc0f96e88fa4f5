"""Where each part of an SFC chart stands in its drawing: the steps top to bottom in
declaration order (the initial step with a double frame), each step's action blocks to its
right (qualifier and action), and below each step the transitions leaving it: a bar with
its condition, continuing to the next step, or ending in an arrow naming the step it jumps
to (IEC 61131-3's jump notation) when that is not the next one.

The geometry only: the printed documentation (`documentation/sfc_chart.py`) and the
browser's live chart (`frontend/logic_view/sfc.py`) each draw it in their own style."""

from __future__ import annotations

import re
from dataclasses import dataclass

from backend.compiler import ast
from backend.compiler.ast import key

WIDTH = 680
STEP_X, STEP_W, STEP_H = 20, 150, 26
ACTION_X, QUALIFIER_W, ACTION_W, ACTION_H = 210, 40, 190, 20
LINE_X = STEP_X + STEP_W // 2
BAR_HALF = 14  # a transition bar reaches this far either side of the flow line
LABEL_X = LINE_X + 22  # where a transition's label starts
_MAX_LABEL = 70  # characters of a condition in the diagram (the listing has all of it)
_CONDITION = re.compile(r":=(.*?);\s*END_TRANSITION", re.DOTALL | re.IGNORECASE)


@dataclass(frozen=True)
class StepBox:
    name: str
    initial: bool
    y: int  # the top; every step is STEP_W x STEP_H at STEP_X


@dataclass(frozen=True)
class ActionBox:
    qualifier: str  # with `*` for a timed one (its time is in the listing)
    action: str
    y: int  # the top; the qualifier at ACTION_X, the action after it


@dataclass(frozen=True)
class TransitionBar:
    number: int  # the transition's place among the chart's transitions, in text order
    label: str  # its name and priority, if any, and its condition as written
    sources: tuple[str, ...]
    y: int  # the bar, across the flow line at LINE_X


@dataclass(frozen=True)
class Jump:
    """An arrow down the flow line, ending at `y`, naming the steps it goes to."""

    targets: str
    y: int


@dataclass(frozen=True)
class Line:
    x1: int
    y1: int
    x2: int
    y2: int


@dataclass(frozen=True)
class ChartLayout:
    width: int
    height: int
    steps: tuple[StepBox, ...]
    actions: tuple[ActionBox, ...]
    transitions: tuple[TransitionBar, ...]
    jumps: tuple[Jump, ...]
    lines: tuple[Line, ...]


def transition_condition(transition: ast.Transition, lines: tuple[str, ...]) -> str:
    """The condition as written, on one line (`lines`: the text the positions count in)."""
    text = "\n".join(lines[transition.pos.line - 1 : transition.pos.line + 20])
    text = text[transition.pos.col - 1 :]
    match = _CONDITION.search(text)
    return " ".join(match.group(1).split()) if match else "?"


def chart_layout(sfc: ast.Sfc, lines: tuple[str, ...]) -> ChartLayout:
    steps: list[StepBox] = []
    actions: list[ActionBox] = []
    bars: list[TransitionBar] = []
    jumps: list[Jump] = []
    flow: list[Line] = []
    numbers = {id(t): n for n, t in enumerate(sfc.transitions)}
    y = 10
    for index, step in enumerate(sfc.steps):
        following = sfc.steps[index + 1].name if index + 1 < len(sfc.steps) else None
        top = y
        steps.append(StepBox(step.name, step.initial, y))
        for number, association in enumerate(step.associations):
            timed = "*" if association.duration is not None else ""
            actions.append(
                ActionBox(association.qualifier + timed, association.action, y + number * ACTION_H)
            )
        if step.associations:
            middle = y + STEP_H // 2
            flow.append(Line(STEP_X + STEP_W, middle, ACTION_X, middle))
        y += max(STEP_H, ACTION_H * len(step.associations))
        leaving = [t for t in sfc.transitions if t.sources and key(t.sources[0]) == key(step.name)]
        continues = False
        for transition in leaving:
            y += 12
            label = _transition_label(transition, lines)
            bars.append(TransitionBar(numbers[id(transition)], label, transition.sources, y))
            targets = [key(t) for t in transition.targets]
            continues = targets == [key(following)] if following else False
            if not continues:
                y += 18
                flow.append(Line(LINE_X, y - 18, LINE_X, y))
                jumps.append(Jump(", ".join(transition.targets), y))
                y += 6
        if leaving:
            flow.append(Line(LINE_X, top + STEP_H, LINE_X, y + (14 if continues else 0)))
        y += 14
    return ChartLayout(
        WIDTH, y + 4, tuple(steps), tuple(actions), tuple(bars), tuple(jumps), tuple(flow)
    )


def short(text: str, limit: int) -> str:
    return text if len(text) <= limit else text[: limit - 1] + "…"


def _transition_label(transition: ast.Transition, lines: tuple[str, ...]) -> str:
    name = transition.name or ""
    if transition.priority is not None:
        name += f" ({transition.priority})"
    if len(transition.sources) > 1:
        name += f" from {', '.join(transition.sources)}"
    condition = short(transition_condition(transition, lines), _MAX_LABEL)
    return f"{name}: {condition}" if name else condition
