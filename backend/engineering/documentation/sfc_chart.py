"""An SFC chart drawn as a diagram (inline SVG): the steps top to bottom in declaration
order (the initial step with a double frame), each step's action blocks to its right
(qualifier and action), and below each step the transitions leaving it: a bar with its
condition, continuing to the next step, or ending in an arrow naming the step it jumps to
(IEC 61131-3's jump notation) when that is not the next one."""

from __future__ import annotations

import re

from backend.compiler import ast
from backend.compiler.ast import key
from backend.engineering.documentation.markup import escape

WIDTH = 680
_STEP_X, _STEP_W, _STEP_H = 20, 150, 26
_ACTION_X, _QUALIFIER_W, _ACTION_W, _ACTION_H = 210, 40, 190, 20
_LINE_X = _STEP_X + _STEP_W // 2
_MAX_LABEL = 70  # characters of a condition in the diagram (the listing has all of it)
# presentation attributes, not CSS: WeasyPrint's SVG renderer takes no page style sheet
_FONT = 'font-family="DejaVu Sans" font-size="11"'
_STYLES = {
    "step": 'fill="#ffffff" stroke="#222222" stroke-width="1.2"',
    "act": 'fill="#f6f8fa" stroke="#555555" stroke-width="0.8"',
    "flow": 'stroke="#222222" stroke-width="1.2"',
    "bar": 'stroke="#222222" stroke-width="3"',
    "arrow": 'fill="none" stroke="#222222" stroke-width="1.2"',
    "name": f'{_FONT} text-anchor="middle" font-weight="bold"',
    "qual": f'{_FONT} text-anchor="middle" font-weight="bold"',
    "action": _FONT,
    "cond": 'font-family="DejaVu Sans Mono" font-size="10"',
    "jump": f'{_FONT} font-weight="bold"',
}
_CLASS = re.compile(r'class="([a-z]+)"')
_CONDITION = re.compile(r":=(.*?);\s*END_TRANSITION", re.DOTALL | re.IGNORECASE)


def transition_condition(transition: ast.Transition, lines: tuple[str, ...]) -> str:
    """The condition as written, on one line."""
    text = "\n".join(lines[transition.pos.line - 1 : transition.pos.line + 20])
    text = text[transition.pos.col - 1 :]
    match = _CONDITION.search(text)
    return " ".join(match.group(1).split()) if match else "?"


def chart_svg(sfc: ast.Sfc, lines: tuple[str, ...]) -> str:
    parts: list[str] = []
    y = 10
    steps = list(sfc.steps)
    for index, step in enumerate(steps):
        following = steps[index + 1].name if index + 1 < len(steps) else None
        top = y
        parts.append(_step_box(step, y))
        for number, association in enumerate(step.associations):
            parts.append(_action_block(association, y + number * _ACTION_H))
        if step.associations:
            middle = y + _STEP_H // 2
            parts.append(_line(_STEP_X + _STEP_W, middle, _ACTION_X, middle))
        y += max(_STEP_H, _ACTION_H * len(step.associations))
        leaving = [t for t in sfc.transitions if t.sources and key(t.sources[0]) == key(step.name)]
        line_top = top + _STEP_H
        continues = False
        for transition in leaving:
            y += 12
            label = _transition_label(transition, lines)
            parts.append(
                f'<line x1="{_LINE_X - 14}" y1="{y}" x2="{_LINE_X + 14}" y2="{y}" class="bar"/>'
                f'<text x="{_LINE_X + 22}" y="{y + 4}" class="cond">{escape(label)}</text>'
            )
            targets = [key(t) for t in transition.targets]
            continues = targets == [key(following)] if following else False
            if not continues:
                y += 18
                names = ", ".join(transition.targets)
                parts.append(
                    f'<line x1="{_LINE_X}" y1="{y - 18}" x2="{_LINE_X}" y2="{y}" class="flow"/>'
                    f'<path d="M{_LINE_X - 5},{y - 6} L{_LINE_X},{y} L{_LINE_X + 5},{y - 6}" '
                    f'class="arrow"/><text x="{_LINE_X + 10}" y="{y + 1}" class="jump">'
                    f"{escape(names)}</text>"
                )
                y += 6
        if leaving:
            parts.append(
                f'<line x1="{_LINE_X}" y1="{line_top}" x2="{_LINE_X}" '
                f'y2="{y + (14 if continues else 0)}" class="flow"/>'
            )
        y += 14
    height = y + 4
    drawing = _CLASS.sub(lambda m: _STYLES[m.group(1)], "".join(parts))
    return (
        f'<svg xmlns="http://www.w3.org/2000/svg" class="sfc" width="{WIDTH}" height="{height}" '
        f'viewBox="0 0 {WIDTH} {height}">{drawing}</svg>'
    )


def _step_box(step: ast.Step, y: int) -> str:
    box = f'<rect x="{_STEP_X}" y="{y}" width="{_STEP_W}" height="{_STEP_H}" class="step"/>'
    if step.initial:
        box += (
            f'<rect x="{_STEP_X + 3}" y="{y + 3}" width="{_STEP_W - 6}" '
            f'height="{_STEP_H - 6}" class="step"/>'
        )
    text = f'<text x="{_LINE_X}" y="{y + 17}" class="name">{escape(_short(step.name, 20))}</text>'
    return box + text


def _action_block(association: ast.ActionAssociation, y: int) -> str:
    qualifier = association.qualifier
    if association.duration is not None:
        qualifier += "*"  # a timed qualifier: the time is in the listing
    return (
        f'<rect x="{_ACTION_X}" y="{y}" width="{_QUALIFIER_W}" height="{_ACTION_H}" class="act"/>'
        f'<text x="{_ACTION_X + _QUALIFIER_W // 2}" y="{y + 14}" class="qual">'
        f"{escape(qualifier)}</text>"
        f'<rect x="{_ACTION_X + _QUALIFIER_W}" y="{y}" width="{_ACTION_W}" '
        f'height="{_ACTION_H}" class="act"/>'
        f'<text x="{_ACTION_X + _QUALIFIER_W + 6}" y="{y + 14}" class="action">'
        f"{escape(_short(association.action, 28))}</text>"
    )


def _transition_label(transition: ast.Transition, lines: tuple[str, ...]) -> str:
    name = transition.name or ""
    if transition.priority is not None:
        name += f" ({transition.priority})"
    if len(transition.sources) > 1:
        name += f" from {', '.join(transition.sources)}"
    condition = _short(transition_condition(transition, lines), _MAX_LABEL)
    return f"{name}: {condition}" if name else condition


def _short(text: str, limit: int) -> str:
    return text if len(text) <= limit else text[: limit - 1] + "…"


def _line(x1: int, y1: int, x2: int, y2: int) -> str:
    return f'<line x1="{x1}" y1="{y1}" x2="{x2}" y2="{y2}" class="flow"/>'
