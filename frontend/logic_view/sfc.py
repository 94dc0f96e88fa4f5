"""An SFC chart drawn live (inline SVG), where `backend/engineering/sfc_layout.py` places its
parts: each active step lit, each step's time beside its actions, and beside each
transition bar the value its condition last took in the runtime. A condition is evaluated
only while its transition is enabled (every source step active): otherwise its value is
the last it took, drawn muted. A forced value is drawn red, as in the Online test; a click
on a value chooses it for writing or forcing."""

from __future__ import annotations

from typing import Any

from backend.engineering.logic_view import LiveChart
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
    short,
)
from frontend.logic_view.svg import (
    ACTIVE,
    ACTIVE_FILL,
    FORCED,
    IDLE,
    MUTED,
    Live,
    clickable,
    escape,
    shown,
    value_color,
)

_TRANSITION_TITLE = (
    "the condition's value in the last cycle; muted: not evaluated now (a step it leaves is "
    "not active), the last value it took"
)
TIME_X = ACTION_X + QUALIFIER_W + ACTION_W + 12  # a step's time, right of its actions
_STYLE = (
    "<style>.sfc-live text{font-family:sans-serif;font-size:11px}"
    ".sfc-live .mono{font-family:monospace;font-size:10.5px}"
    ".sfc-live .b{font-weight:bold}</style>"
)


def chart_svg(
    chart: LiveChart,
    values: dict[str, Any],
    types: dict[str, str],
    quality: dict[str, str],
    live: Live,
) -> str:
    """The chart with the values now; its live parts in `live`."""
    layout = chart.layout
    parts: list[str] = []
    for line in layout.lines:
        parts.append(
            f'<line x1="{line.x1}" y1="{line.y1}" x2="{line.x2}" y2="{line.y2}" '
            f'stroke="{IDLE}" stroke-width="1.2"/>'
        )
    active: dict[str, bool] = {}
    for step in layout.steps:
        path = chart.steps[step.name]
        text, how = shown(f"{path}.X", values, types, quality)
        lit = text == "TRUE"
        active[step.name.upper()] = lit
        parts.append(_step(step.name, step.initial, step.y, path, lit, how, live))
        time_text, time_how = shown(f"{path}.T", values, types, quality)
        tint = {"fill": _time_color(lit, time_how)}
        parts.append(
            f'<text x="{TIME_X}" y="{step.y + 17}" class="mono" '
            f'data-step-time="{escape(step.name)}" {live.node(tint)} {clickable(f"{path}.T")}>'
            f"{live.text(f'T = {time_text}')}</text>"
        )
    for action in layout.actions:
        parts.append(
            f'<rect x="{ACTION_X}" y="{action.y}" width="{QUALIFIER_W}" height="{ACTION_H}" '
            f'fill="#f8f9fa" stroke="#868e96" stroke-width="0.8"/>'
            f'<text x="{ACTION_X + QUALIFIER_W // 2}" y="{action.y + 14}" text-anchor="middle" '
            f'class="b">{escape(action.qualifier)}</text>'
            f'<rect x="{ACTION_X + QUALIFIER_W}" y="{action.y}" width="{ACTION_W}" '
            f'height="{ACTION_H}" fill="#f8f9fa" stroke="#868e96" stroke-width="0.8"/>'
            f'<text x="{ACTION_X + QUALIFIER_W + 6}" y="{action.y + 14}">'
            f"{escape(short(action.action, 28))}</text>"
        )
    for bar in layout.transitions:
        path = chart.transitions[bar.number]
        text, how = shown(path, values, types, quality)
        # evaluated in this cycle only while every step it leaves is active
        evaluated = all(active.get(source.upper(), False) for source in bar.sources)
        color = value_color(text, how) if evaluated or how == "forced" else MUTED
        bar_color = ACTIVE if evaluated and text == "TRUE" else IDLE
        shown_value = {
            "fill": color,
            "data-value": text,
            "data-evaluated": str(evaluated).lower(),
            "data-quality": how,
        }
        parts.append(
            f'<line x1="{LINE_X - BAR_HALF}" y1="{bar.y}" x2="{LINE_X + BAR_HALF}" y2="{bar.y}" '
            f'{live.node({"stroke": bar_color})} stroke-width="3"/>'
            f'<text x="{LINE_X - BAR_HALF - 5}" y="{bar.y + 4}" text-anchor="end" class="mono b" '
            f'data-transition="{bar.number + 1}" {live.node(shown_value)} {clickable(path)}>'
            f"<title>{_TRANSITION_TITLE}</title>{live.text(text)}</text>"
            f'<text x="{LABEL_X}" y="{bar.y + 4}" class="mono" fill="{IDLE}">'
            f"{escape(bar.label)}</text>"
        )
    for jump in layout.jumps:
        parts.append(
            f'<path d="M{LINE_X - 5},{jump.y - 6} L{LINE_X},{jump.y} L{LINE_X + 5},{jump.y - 6}" '
            f'fill="none" stroke="{IDLE}" stroke-width="1.2"/>'
            f'<text x="{LINE_X + 10}" y="{jump.y + 1}" class="b">{escape(jump.targets)}</text>'
        )
    # as wide as what is drawn: the work panel is narrow, and the chart is scaled to it
    labels = max((len(bar.label) for bar in layout.transitions), default=0)
    width = min(layout.width, max(TIME_X + 120, LABEL_X + round(6.5 * labels) + 8))
    height = layout.height
    return (
        f'{_STYLE}<svg xmlns="http://www.w3.org/2000/svg" class="sfc-live" '
        f'data-testid="drawing" viewBox="0 0 {width} {height}" '
        f'style="width:100%;max-width:{width * 1.4:.0f}px;height:auto">{"".join(parts)}</svg>'
    )


def _step(name: str, initial: bool, y: int, path: str, lit: bool, how: str, live: Live) -> str:
    stroke = FORCED if how == "forced" else ACTIVE if lit else IDLE
    frame = {
        "fill": ACTIVE_FILL if lit else "#ffffff",
        "stroke": stroke,
        "stroke-width": "2.2" if lit else "1.2",
    }
    box = f'<rect x="{STEP_X}" y="{y}" width="{STEP_W}" height="{STEP_H}" {live.node(frame)}/>'
    if initial:
        box += (
            f'<rect x="{STEP_X + 3}" y="{y + 3}" width="{STEP_W - 6}" height="{STEP_H - 6}" '
            f'fill="none" {live.node({"stroke": stroke})} stroke-width="1"/>'
        )
    state = {"data-active": str(lit).lower(), "data-quality": how}
    return (
        f'<g data-step="{escape(name)}" {live.node(state)} {clickable(f"{path}.X")}>'
        f"<title>step {escape(name)}</title>{box}"
        f'<text x="{LINE_X}" y="{y + 17}" text-anchor="middle" class="b">'
        f"{escape(short(name, 20))}</text></g>"
    )


def _time_color(lit: bool, how: str) -> str:
    if how == "forced":
        return FORCED
    return ACTIVE if lit else MUTED


def legend() -> str:
    items = (
        f'<span style="color:{ACTIVE};font-weight:600">■ active step</span>',
        f'<span style="color:{ACTIVE}">TRUE</span> / <span style="color:{IDLE}">FALSE</span> '
        "a transition's condition",
        f'<span style="color:{MUTED}">muted</span>: not evaluated now, its last value',
        f'<span style="color:{FORCED};font-weight:600">forced</span>',
        "click a value to write or force it",
    )
    spans = "".join(f'<span style="margin-right:14px">{item}</span>' for item in items)
    return f'<div data-testid="logic-legend" style="font-size:0.8em;line-height:1.6">{spans}</div>'
