"""An SFC chart drawn for the printed documentation (inline SVG), where
`backend/engineering/sfc_layout.py` places its parts: the steps top to bottom (the initial
step with a double frame), each step's action blocks to its right, and below each step the
transitions leaving it, with their conditions, and jumps to steps that do not follow."""

from __future__ import annotations

import re

from backend.compiler import ast
from backend.engineering.documentation.markup import escape
from backend.engineering.sfc_layout import (
    ACTION_H,
    ACTION_W,
    ACTION_X,
    BAR_HALF,
    LABEL_X,
    LINE_X,
    QUALIFIER_W,
    STEP_H,
    STEP_W,
    STEP_X,
    ActionBox,
    StepBox,
    chart_layout,
    short,
)

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


def chart_svg(sfc: ast.Sfc, lines: tuple[str, ...]) -> str:
    layout = chart_layout(sfc, lines)
    parts = [_step_box(step) for step in layout.steps]
    parts += [_action_block(action) for action in layout.actions]
    parts += [
        f'<line x1="{line.x1}" y1="{line.y1}" x2="{line.x2}" y2="{line.y2}" class="flow"/>'
        for line in layout.lines
    ]
    parts += [
        f'<line x1="{LINE_X - BAR_HALF}" y1="{bar.y}" x2="{LINE_X + BAR_HALF}" y2="{bar.y}" '
        f'class="bar"/><text x="{LABEL_X}" y="{bar.y + 4}" class="cond">{escape(bar.label)}</text>'
        for bar in layout.transitions
    ]
    parts += [
        f'<path d="M{LINE_X - 5},{jump.y - 6} L{LINE_X},{jump.y} L{LINE_X + 5},{jump.y - 6}" '
        f'class="arrow"/><text x="{LINE_X + 10}" y="{jump.y + 1}" class="jump">'
        f"{escape(jump.targets)}</text>"
        for jump in layout.jumps
    ]
    drawing = _CLASS.sub(lambda m: _STYLES[m.group(1)], "".join(parts))
    width, height = layout.width, layout.height
    return (
        f'<svg xmlns="http://www.w3.org/2000/svg" class="sfc" width="{width}" height="{height}" '
        f'viewBox="0 0 {width} {height}">{drawing}</svg>'
    )


def _step_box(step: StepBox) -> str:
    y = step.y
    box = f'<rect x="{STEP_X}" y="{y}" width="{STEP_W}" height="{STEP_H}" class="step"/>'
    if step.initial:
        box += (
            f'<rect x="{STEP_X + 3}" y="{y + 3}" width="{STEP_W - 6}" '
            f'height="{STEP_H - 6}" class="step"/>'
        )
    text = f'<text x="{LINE_X}" y="{y + 17}" class="name">{escape(short(step.name, 20))}</text>'
    return box + text


def _action_block(action: ActionBox) -> str:
    y = action.y
    return (
        f'<rect x="{ACTION_X}" y="{y}" width="{QUALIFIER_W}" height="{ACTION_H}" class="act"/>'
        f'<text x="{ACTION_X + QUALIFIER_W // 2}" y="{y + 14}" class="qual">'
        f"{escape(action.qualifier)}</text>"
        f'<rect x="{ACTION_X + QUALIFIER_W}" y="{y}" width="{ACTION_W}" '
        f'height="{ACTION_H}" class="act"/>'
        f'<text x="{ACTION_X + QUALIFIER_W + 6}" y="{y + 14}" class="action">'
        f"{escape(short(action.action, 28))}</text>"
    )
