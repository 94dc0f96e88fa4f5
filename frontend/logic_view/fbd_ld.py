"""An FBD or LD body drawn live (inline SVG): the parts as `backend/engineering/graphic_drawing.py`
draws them (each element at its TC6 place and size, the wires through their points), styled
for the screen; on each output pin the value it puts out, after each OUT the variable it
writes, under each contact and coil its variable; every wire that carries TRUE, and each
contact and coil whose power flow is TRUE, in the active colour (LD's power flow). A forced
value is drawn red, as in the Online test; a click on a value chooses it for writing or
forcing."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from backend.engineering.graphic_drawing import CLASSES
from backend.engineering.logic_view import TRUE, LiveGraphic
from frontend.logic_view.svg import (
    ACTIVE,
    FORCED,
    MUTED,
    Live,
    clickable,
    escape,
    shown,
    value_color,
)

_MARGIN = 14
_LABEL_CHAR = 6.2  # a value label's character width, in drawing units (monospace 10 px)
_ROOM = 12  # characters a value may grow to without leaving the drawing's frame
_INK = "#343a40"
_CLASS_STYLES = {
    "box": f"fill:#fff;stroke:{_INK};stroke-width:1.2",
    "var": "fill:#f8f9fa;stroke:#868e96;stroke-width:0.8",
    "note": "fill:#fff9db;stroke:#b8a24a;stroke-width:0.8",
    "wire": f"fill:none;stroke:{_INK};stroke-width:1",
    "sym": f"fill:none;stroke:{_INK};stroke-width:1.4",
    "rail": f"fill:{_INK}",
    "neg": f"fill:#fff;stroke:{_INK};stroke-width:1",
    "type": "font-size:11px;text-anchor:middle;font-weight:bold",
    "inst": "font-size:11px;text-anchor:middle",
    "pin": "font-size:10px",
    "pinr": "font-size:10px;text-anchor:end",
    "text": "font-size:11px;text-anchor:middle",
    "mark": "font-size:10px;text-anchor:middle;font-weight:bold",
    "order": "font-size:8px;fill:#868e96;text-anchor:end",
    "comment": "font-size:10px;fill:#5c4b00",
}
assert set(_CLASS_STYLES) == set(CLASSES), "every class the drawing uses has a style here"
_STYLE = (
    "<style>.gfx text{font-family:sans-serif}"
    + "".join(f".gfx .{name}{{{style}}}" for name, style in _CLASS_STYLES.items())
    + f".gfx .on .wire,.gfx .on .sym{{stroke:{ACTIVE};stroke-width:2.4}}"
    f".gfx .on .rail{{fill:{ACTIVE}}}"
    f".gfx .forced .sym,.gfx .forced .var{{stroke:{FORCED};stroke-width:2}}"
    ".gfx .val{font-family:monospace;font-size:10px;font-weight:bold;paint-order:stroke;"
    "stroke:#fff;stroke-width:3px;stroke-linejoin:round}</style>"
)


@dataclass(frozen=True)
class PlacedField:
    """An online test field on the drawing: its variable as named in the POU, the path of
    that variable in the resource (None: the resource has none of that name), its place."""

    variable: str
    path: str | None
    x: float
    y: float


_FIELD_H = 18


def graphic_svg(
    graphic: LiveGraphic,
    values: dict[str, Any],
    types: dict[str, str],
    quality: dict[str, str],
    fields: Sequence[PlacedField],
    live: Live,
) -> str:
    """The body with the values now; its live parts in `live`."""

    def carries_true(element: int, pin: str) -> bool:
        path = graphic.carried.get((element, pin))
        return path == TRUE or (path is not None and values.get(path) is True)

    forced = {
        part.element
        for part in graphic.parts
        if part.element and _named_forced(graphic, part.element, quality)
    }
    parts: list[str] = []
    for part in graphic.parts:
        if part.source:  # a wire: lit when what it carries is TRUE
            lit = carries_true(part.source, part.source_pin)
            state = {"class": "on" if lit else "", "data-on": str(lit).lower()}
            parts.append(f'<g data-wire-from="{part.source}" {live.node(state)}>{part.svg}</g>')
        elif part.element:
            lit = carries_true(part.element, "")
            names = " ".join(x for x, on in (("on", lit), ("forced", part.element in forced)) if on)
            state = {"class": names, "data-on": str(lit).lower()}
            parts.append(f'<g data-element="{part.element}" {live.node(state)}>{part.svg}</g>')
        else:
            parts.append(part.svg)
    right = max((p.right for p in graphic.parts), default=0.0)
    for drawn in graphic.values:
        text, how = shown(drawn.path, values, types, quality)
        color = value_color(text, how) if how != "live" or text in ("TRUE", "FALSE") else _INK
        state = {"fill": color, "data-value": text, "data-quality": how}
        parts.append(
            f'<text class="val" x="{drawn.at.x:g}" y="{drawn.at.y:g}" '
            f'data-value-of="{escape(drawn.path)}" {live.node(state)} {clickable(drawn.path)}>'
            f"<title>{escape(drawn.path)}</title>{live.text(text)}</text>"
        )
        right = max(right, drawn.at.x + _LABEL_CHAR * max(len(text), _ROOM))
    left = min((p.left for p in graphic.parts), default=0.0)
    top = min((p.top for p in graphic.parts), default=0.0)
    bottom = max((p.bottom for p in graphic.parts), default=0.0) + 14
    for placed in fields:
        box, width = _field(placed, values, types, quality, live)
        parts.append(box)
        left, top = min(left, placed.x), min(top, placed.y)
        right, bottom = max(right, placed.x + width), max(bottom, placed.y + _FIELD_H)
    left, top, bottom = left - _MARGIN, top - _MARGIN, bottom + _MARGIN
    width, height = right + _MARGIN - left, bottom - top
    # never drawn smaller than 85 % of its own size, where its 10 px labels stay readable:
    # a large drawing scrolls in its frame instead
    return (
        f'{_STYLE}<div data-testid="drawing-frame" style="overflow:auto;max-height:75vh">'
        f'<svg xmlns="http://www.w3.org/2000/svg" class="gfx" data-testid="drawing" '
        f'data-language="{graphic.language}" viewBox="{left:g} {top:g} {width:g} {height:g}" '
        f'style="width:100%;min-width:{width * 0.85:.0f}px;max-width:{width * 1.6:.0f}px;'
        f'height:auto">{"".join(parts)}</svg></div>'
    )


def _field(
    placed: PlacedField,
    values: dict[str, Any],
    types: dict[str, str],
    quality: dict[str, str],
    live: Live,
) -> tuple[str, float]:
    """An online test field's box (`variable = value`) and the width it may take."""
    if placed.path is None:
        text, how = "not in this configuration", "unknown"
    else:
        text, how = shown(placed.path, values, types, quality)
    label = f"{placed.variable} = {text}"
    color = FORCED if how == "forced" else MUTED if how != "live" else _INK
    click = clickable(placed.path) if placed.path is not None else ""
    state = {"data-value": text, "data-quality": how}
    box = (
        f'<g data-field="{escape(placed.variable)}" {live.node(state)} {click}>'
        f'<rect x="{placed.x:g}" y="{placed.y:g}" '
        f'{live.node({"width": f"{10 + _LABEL_CHAR * len(label):g}"})} height="{_FIELD_H}" '
        f'rx="3" fill="#fff3bf" stroke="#f08c00"/>'
        f'<text class="val" x="{placed.x + 5:g}" y="{placed.y + 13:g}" '
        f"{live.node({'fill': color})}>{live.text(label)}</text></g>"
    )
    return box, 10 + _LABEL_CHAR * (len(placed.variable) + 3 + max(len(text), _ROOM))


def _named_forced(graphic: LiveGraphic, element: int, quality: dict[str, str]) -> bool:
    """Whether the variable drawn at an element (its contact's, its OUT's) is forced."""
    return any(quality.get(v.path) == "forced" for v in graphic.values if v.element == element)


def legend() -> str:
    items = (
        f'<span style="color:{ACTIVE};font-weight:600">━ TRUE</span>: a wire that carries '
        "TRUE, power flow in LD",
        f'<span style="color:{FORCED};font-weight:600">forced</span>',
        f'<span style="color:{MUTED}">…</span> no value yet',
        "click a value to write or force it, the drawing to place a field",
    )
    spans = "".join(f'<span style="margin-right:14px">{item}</span>' for item in items)
    return f'<div data-testid="graphic-legend" style="font-size:0.8em">{spans}</div>'
