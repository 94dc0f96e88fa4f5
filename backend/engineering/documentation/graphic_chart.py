"""An FBD or LD body drawn for the printed documentation (inline SVG), as
`backend/engineering/graphic_drawing.py` draws it, in presentation attributes (WeasyPrint's
SVG renderer takes no page style sheet). The drawing is scaled to the page width, down to
a scale where the text stays readable; a drawing wider or taller than a page at that scale
is cut into parts (between elements where possible), each an SVG of its own that a page
takes whole.
"""

from __future__ import annotations

from backend.compiler.graphics.model import GraphicBody
from backend.engineering.graphic_drawing import FONT, draw, placed

WIDTH = 680  # CSS px of the page's text width (A4 less the margins)
HEIGHT = 820  # CSS px a part may take on a page, below its caption (a tenth more: _SLACK)
_SLACK = 1.1
_MIN_SCALE = 0.5  # below it the pin names (10 px) would print under 5 px (3.75 pt)
_MARGIN = 12  # drawing units around the drawing
_SMALL = 'font-family="DejaVu Sans" font-size="10"'
_STYLES = {
    "box": 'fill="#ffffff" stroke="#222222" stroke-width="1.2"',
    "var": 'fill="#f6f8fa" stroke="#555555" stroke-width="0.8"',
    "note": 'fill="#fffbe6" stroke="#b8a24a" stroke-width="0.8"',
    "wire": 'fill="none" stroke="#222222" stroke-width="1"',
    "sym": 'fill="none" stroke="#222222" stroke-width="1.4"',
    "rail": 'fill="#222222" stroke="none"',
    "neg": 'fill="#ffffff" stroke="#222222" stroke-width="1"',
    "type": f'{FONT} text-anchor="middle" font-weight="bold"',
    "inst": f'{FONT} text-anchor="middle"',
    "pin": _SMALL,
    "pinr": f'{_SMALL} text-anchor="end"',
    "text": f'{FONT} text-anchor="middle"',
    "mark": f'{_SMALL} text-anchor="middle" font-weight="bold"',
    "order": 'font-family="DejaVu Sans" font-size="8" fill="#777777" text-anchor="end"',
    "comment": 'font-family="DejaVu Sans" font-size="10" fill="#5a4a00"',
}


def graphic_charts(body: GraphicBody) -> list[str]:
    """The body drawn: one SVG, or its parts (left to right, then top to bottom) when a
    page does not take it whole; none for a body without elements."""
    body = placed(body)
    parts = draw(body)
    if not parts:
        return []
    left = min(p.left for p in parts) - _MARGIN
    right = max(p.right for p in parts) + _MARGIN
    top = min(p.top for p in parts) - _MARGIN
    bottom = max(p.bottom for p in parts) + _MARGIN
    solid = [p for p in parts if p.solid]
    columns = [(left, right)]
    if WIDTH / (right - left) < _MIN_SCALE:
        columns = _cuts([(p.left, p.right) for p in solid], left, right, WIDTH / _MIN_SCALE)
    scale = min(1.0, WIDTH / max(x1 - x0 for x0, x1 in columns))
    rows = _cuts([(p.top, p.bottom) for p in solid], top, bottom, HEIGHT / scale)
    charts = []
    for y0, y1 in rows:
        for x0, x1 in columns:
            inside = [
                p
                for p in parts
                if p.bottom >= y0 and p.top <= y1 and p.right >= x0 and p.left <= x1
            ]
            if not inside:
                continue
            # a part of a wide drawing holds only its own height: no band of white from the
            # parts beside it
            top_y = max(y0, min(p.top for p in inside) - _MARGIN)
            bottom_y = min(y1, max(p.bottom for p in inside) + _MARGIN)
            drawing = "".join(p.svg for p in inside)
            for name, attributes in _STYLES.items():
                drawing = drawing.replace(f'class="{name}"', attributes)
            width, height = round((x1 - x0) * scale), round((bottom_y - top_y) * scale)
            svg = (
                f'<svg xmlns="http://www.w3.org/2000/svg" class="graphic" width="{width}" '
                f'height="{height}" viewBox="{x0:g} {top_y:g} {x1 - x0:g} {bottom_y - top_y:g}">'
                f"{drawing}</svg>"
            )
            charts.append(svg)
    return charts


def _cuts(
    spans: list[tuple[float, float]], start: float, end: float, most: float
) -> list[tuple[float, float]]:
    """[start, end] cut into pieces of about `most`: each cut between the spans (the boxes
    of elements) when there is room for one in the last two thirds of a piece, else where
    it must; a rest of up to a tenth more stays with the piece before (a page takes it at a
    scale a little smaller, rather than a part of a few millimetres)."""
    pieces = []
    while end - start > most * _SLACK:
        limit = start + most
        near = [(t, b) for t, b in spans if b > start and t < limit]
        candidates = [b + 6 for _, b in near] + [t - 6 for t, _ in near]
        free = [
            c
            for c in candidates
            if start + most / 3 < c <= limit and not any(t < c < b for t, b in near)
        ]
        cut = max(free) if free else limit
        pieces.append((start, cut))
        start = cut
    pieces.append((start, end))
    return pieces
