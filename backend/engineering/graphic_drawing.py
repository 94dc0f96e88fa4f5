"""An FBD or LD body drawn (SVG): blocks as boxes with their type, instance and pin names,
variables, connectors, jumps, labels and returns, LD's contacts, coils and power rails,
the wires through the points TC6 gave them, and the comments of the sheet. The printed
documentation (`documentation/graphic_chart.py`) and the browser's live drawing
(`frontend/logic_view/fbd_ld.py`) each style and frame these parts their own way.

A body imported from PLCopen XML carries its places (`at`, `size`, pin positions, wire
points) and is drawn as its author laid it out. A body written by hand may carry none: it
is then laid out here, left to right by how far each element is from the inputs.
"""

from __future__ import annotations

import math
import textwrap
from dataclasses import dataclass, replace
from html import escape

from backend.compiler.graphics.model import Element, GraphicBody, Pin, Point, Wire

# the classes the parts are drawn in
CLASSES = (
    "box",  # a block's box
    "var",  # a variable's, connector's or continuation's box
    "note",  # a comment's box
    "wire",
    "sym",  # a contact's or coil's symbol, a jump's arrow, an edge's `>`
    "rail",
    "neg",  # the circle of a negated pin
    "type",  # a block's type
    "inst",  # an FB instance's name
    "pin",  # an input pin's name
    "pinr",  # an output pin's name (right aligned)
    "text",  # a variable's or connector's text
    "mark",  # a contact's or coil's variable and its mark (/, P, N, S, R)
    "order",  # the execution order of a block
    "comment",
)
FONT = 'font-family="DejaVu Sans" font-size="11"'
_CONTACT_MARK = {"NEGATED": "/", "RISING": "P", "FALLING": "N"}
_COIL_MARK = {"NEGATED": "/", "SET": "S", "RESET": "R", "RISING": "P", "FALLING": "N"}
_CHAR = 6.6  # width of a character of the 11 px font, in drawing units (for fitting text)


@dataclass(frozen=True)
class Part:
    """One drawing item with the vertical and horizontal extent it covers."""

    svg: str
    top: float
    bottom: float
    left: float
    right: float
    solid: bool = True  # an element's box, which a cut between pages should not go through
    element: int = 0  # the local id of the element drawn; 0: none
    source: int = 0  # a wire: the local id of the element it comes from
    source_pin: str = ""  # and that element's output pin


# ---- where things are --------------------------------------------------------------------

_DRAWN_WITHOUT_SIZE = ("COMMENT",)
_FARTHEST = 50_000  # drawing units from the origin a place may be (TC6 sheets: a few 1,000)


def laid_out(body: GraphicBody) -> bool:
    """Whether the body says where each element is (an import does; a hand-written body
    may not, and one element without a place would land on the others), within a sheet a
    document can print: a file may give any number, and a place a million units away would
    make a million parts."""
    numbers: list[float] = []
    for element in body.elements:
        if element.kind not in _DRAWN_WITHOUT_SIZE and (element.size.x <= 0 or element.size.y <= 0):
            return False
        numbers += [element.at.x, element.at.y, element.size.x, element.size.y]
        for pin in (*element.inputs, *element.outputs):
            if pin.at is not None:
                numbers += [pin.at.x, pin.at.y]
            numbers += [c for w in pin.wires for p in w.points for c in (p.x, p.y)]
    return all(math.isfinite(n) and abs(n) <= _FARTHEST for n in numbers)


def pin_places(element: Element) -> tuple[list[Point], list[Point]]:
    """Where the element's input and output pins are on the sheet: where TC6 put them, else
    on its left and right edges (a block's pins row by row under its type name)."""
    x, y, w, h = element.at.x, element.at.y, element.size.x, element.size.y

    def default(index: int, count: int, edge: float) -> Point:
        if element.kind == "BLOCK":
            return Point(edge, y + _BLOCK_HEAD + _BLOCK_ROW * index + _BLOCK_ROW / 2)
        return Point(edge, y + h * (index + 1) / (count + 1))

    def place(pins: tuple[Pin, ...], edge: float) -> list[Point]:
        return [
            Point(x + p.at.x, y + p.at.y) if p.at is not None else default(i, len(pins), edge)
            for i, p in enumerate(pins)
        ]

    return place(element.inputs, x), place(element.outputs, x + w)


def _source_point(body: GraphicBody, wire: Wire, towards: Point) -> Point | None:
    """Where a wire without points starts: the source's output pin (a rail's at the height
    of the pin it feeds, as a rung runs straight from it)."""
    source = body.element(wire.element)
    if source is None:
        return None
    if source.kind == "LEFT_RAIL":
        return Point(source.at.x + source.size.x, towards.y)
    return output_place(source, wire.pin)


def output_place(source: Element, pin: str) -> Point:
    _, outputs = pin_places(source)
    if not outputs:
        return Point(source.at.x + source.size.x, source.at.y + source.size.y / 2)
    names = [p.name.upper() for p in source.outputs]
    return outputs[names.index(pin.upper()) if pin.upper() in names else 0]


# ---- a layout for a body that has none ---------------------------------------------------

_BLOCK_HEAD, _BLOCK_ROW = 22, 20
_COLUMN_GAP, _ROW_GAP = 50, 18
_INSTANCE_ROOM = 16  # an FB instance's name is written above its box


def _natural_size(element: Element) -> Point:
    kind = element.kind
    if kind == "BLOCK":
        left = max((min(len(p.name), _MAX_TEXT) for p in element.inputs), default=0)
        right = max((min(len(p.name), _MAX_TEXT) for p in element.outputs), default=0)
        width = max(70, (left + right) * 6.2 + 30, min(len(element.text), _MAX_TEXT) * 7.5 + 20)
        rows = max(len(element.inputs), len(element.outputs), 1)
        return Point(width, _BLOCK_HEAD + _BLOCK_ROW * rows + 6)
    if kind in ("CONTACT", "COIL"):
        return Point(34, 18)
    if kind in ("LEFT_RAIL", "RIGHT_RAIL"):
        return Point(4, 20)
    if kind == "COMMENT":
        return Point(300, 16 + 13 * len(_comment_lines(element.text, 300)))
    return Point(max(50, min(len(element.text), _MAX_TEXT) * _CHAR + 18), 26)


def auto_layout(body: GraphicBody) -> GraphicBody:
    """Columns by the longest path from an element without inputs (a feedback wire does not
    count), a left rail before them and a right rail after them, LD's coils that end a rung
    in the last column; rows in body order, each element level with the source of its first
    input where its column leaves room, a rung that starts at the left rail below what is
    placed; rails span the rungs; comments below."""
    depth: dict[int, int] = {}

    def depth_of(element: Element, visiting: frozenset[int]) -> int:
        if element.id not in depth:
            sources = [
                body.element(w.element)
                for p in element.inputs
                for w in p.wires
                if w.element not in visiting
            ]
            found = [depth_of(s, visiting | {element.id}) + 1 for s in sources if s is not None]
            depth[element.id] = -1 if element.kind == "LEFT_RAIL" else max(found, default=0)
        return depth[element.id]

    drawn = [e for e in body.elements if e.kind != "COMMENT"]
    for element in drawn:
        depth_of(element, frozenset())
    fed: dict[int, set[str]] = {}  # what each element's outputs are wired to, by kind
    for element in drawn:
        for wire in (w for p in element.inputs for w in p.wires):
            fed.setdefault(wire.element, set()).add(element.kind)
    inner = [depth[e.id] for e in drawn if e.kind not in ("LEFT_RAIL", "RIGHT_RAIL")]
    last = max(inner, default=0)
    for element in drawn:
        if element.kind == "COIL" and fed.get(element.id, set()) <= {"RIGHT_RAIL"}:
            depth[element.id] = last
        elif element.kind == "RIGHT_RAIL":
            depth[element.id] = last + 1
    sizes = {e.id: _natural_size(e) for e in body.elements}
    widths: dict[int, float] = {}
    for element in drawn:
        column = depth[element.id]
        widths[column] = max(widths.get(column, 0), sizes[element.id].x)
    lefts, x = {}, 0.0
    for column in sorted(widths):
        lefts[column] = x
        x += widths[column] + _COLUMN_GAP
    placed: dict[int, Element] = {}
    free = dict.fromkeys(widths, 20.0)  # the next free y in each column
    for element in drawn:
        column, size = depth[element.id], sizes[element.id]
        want = free[column] + (_INSTANCE_ROOM if element.instance else 0)
        first = next((w for p in element.inputs for w in p.wires), None)
        source = placed.get(first.element) if first else None
        if first is not None and source is not None and source.kind == "LEFT_RAIL":
            want = max(want, *free.values())  # a new rung
        elif first is not None and source is not None:
            start = output_place(source, first.pin)
            pins = pin_places(replace(element, at=Point(0, 0), size=size))[0]
            want = max(want, start.y - pins[0].y) if pins else want
        shift = widths[column] - size.x if element.kind == "LEFT_RAIL" else 0
        placed[element.id] = replace(element, at=Point(lefts[column] + shift, want), size=size)
        free[column] = want + size.y + _ROW_GAP
    bottom = max((e.at.y + e.size.y for e in placed.values()), default=20.0)
    for element_id, element in list(placed.items()):
        if element.kind in ("LEFT_RAIL", "RIGHT_RAIL"):
            placed[element_id] = replace(
                element, at=Point(element.at.x, 10), size=Point(element.size.x, bottom)
            )
    y = bottom + 30
    for element in body.elements:
        if element.kind == "COMMENT":
            placed[element.id] = replace(element, at=Point(0, y), size=sizes[element.id])
            y += sizes[element.id].y + _ROW_GAP
    return replace(body, elements=tuple(placed.get(e.id, e) for e in body.elements))


# ---- drawing -----------------------------------------------------------------------------

_MAX_TEXT = 40  # characters of an expression drawn (the listing has all of it)
_LANES = 4


def draw(body: GraphicBody) -> list[Part]:
    """The body drawn, part by part, in the classes of `CLASSES` (each drawing styles them
    its own way): each element, then the wires into its pins."""
    parts: list[Part] = []
    # a routed wire turns down or up in one of four lanes after its source, by the source's
    # place among the sources that end where it ends, so that the wires of sources one
    # above the other do not run down one line
    ends: dict[float, list[Element]] = {}
    for element in body.elements:
        ends.setdefault(round(element.at.x + element.size.x), []).append(element)
    lanes = {
        element.id: rank % _LANES
        for column in ends.values()
        for rank, element in enumerate(sorted(column, key=lambda e: e.at.y))
    }
    for element in body.elements:
        parts += [replace(p, element=element.id) for p in _element(element)]
        inputs, _ = pin_places(element)
        for pin, at in zip(element.inputs, inputs, strict=True):
            if element.kind != "BLOCK" and pin.flag:  # a block draws its own
                parts.append(Part(_pin_flag(pin.flag, at, inward=1), at.y, at.y, at.x, at.x))
            for wire in pin.wires:
                # a right rail drawn without pin places takes each rung at its height
                level = element.kind == "RIGHT_RAIL" and pin.at is None
                parts += _wire(body, wire, at, level, lanes.get(wire.element, 0))
    return parts


def _box(element: Element, svg: str, above: float = 0) -> Part:
    x, y, w, h = element.at.x, element.at.y, element.size.x, element.size.y
    return Part(svg, y - above, y + h, x, x + w)


def _short(text: str, limit: int) -> str:
    text = " ".join(text.split())
    return text if len(text) <= limit else text[: max(limit - 1, 1)] + "…"


def _element(element: Element) -> list[Part]:
    kind = element.kind
    x, y, w, h = element.at.x, element.at.y, element.size.x, element.size.y
    mid_x, mid_y = x + w / 2, y + h / 2
    if kind == "BLOCK":
        return [_block(element)]
    if kind in ("IN", "OUT", "INOUT"):
        label = _short(element.text, max(int(w / _CHAR), _MAX_TEXT))
        marks = "".join(f" ({m[0]})" for m in element.modifiers)  # SET/RESET storage
        svg = (
            f'<rect x="{x:g}" y="{y:g}" width="{w:g}" height="{h:g}" rx="4" class="var"/>'
            f'<text x="{mid_x:g}" y="{mid_y + 4:g}" class="text">{escape(label + marks)}</text>'
        )
        return [_box(element, svg, above=0)]
    if kind in ("CONNECTOR", "CONTINUATION"):
        notch = min(10, h / 2)
        if kind == "CONNECTOR":  # the value leaves: a flag pointing right
            tip = x + w - notch
            shape = f"M{x:g},{y:g} H{tip:g} L{x + w:g},{mid_y:g} L{tip:g},{y + h:g} H{x:g} Z"
        else:  # the value arrives: a notch on the left
            shape = f"M{x:g},{y:g} H{x + w:g} V{y + h:g} H{x:g} L{x + notch:g},{mid_y:g} Z"
        svg = (
            f'<path d="{shape}" class="var"/><text x="{mid_x:g}" y="{mid_y + 4:g}" class="text">'
            f"{escape(_short(element.text, _MAX_TEXT))}</text>"
        )
        return [_box(element, svg)]
    if kind in ("JUMP", "RETURN"):
        word = f"{element.text}" if kind == "JUMP" else "RETURN"
        arrow = (
            f'<path d="M{x:g},{mid_y:g} H{x + 14:g} M{x + 8:g},{mid_y - 4:g} L{x + 14:g},'
            f"{mid_y:g} L{x + 8:g},{mid_y + 4:g} M{x + 13:g},{mid_y - 4:g} L{x + 19:g},{mid_y:g}"
            f' L{x + 13:g},{mid_y + 4:g}" class="sym"/>'
        )
        svg = (
            f'{arrow}<text x="{x + 22:g}" y="{mid_y + 4:g}" {FONT} font-weight="bold">'
            f"{escape(_short(word, _MAX_TEXT))}</text>"
        )
        return [Part(svg, y, y + h, x, x + 22 + len(word) * _CHAR)]
    if kind == "LABEL":
        svg = (
            f'<text x="{x:g}" y="{mid_y + 4:g}" {FONT} font-weight="bold">'
            f"{escape(_short(element.text, _MAX_TEXT))}:</text>"
        )
        return [Part(svg, y, y + h, x, x + (len(element.text) + 1) * _CHAR)]
    if kind == "COMMENT":
        lines = _comment_lines(element.text, w)
        fit = max(int((h - 4) / 13), 1)  # what the author's box holds: the listing has the rest
        lines = lines if len(lines) <= fit else [*lines[: fit - 1], lines[fit - 1] + " …"]
        text = "".join(
            f'<tspan x="{x + 6:g}" y="{y + 15 + 13 * i:g}">{escape(line)}</tspan>'
            for i, line in enumerate(lines)
        )
        svg = (
            f'<rect x="{x:g}" y="{y:g}" width="{w:g}" height="{h:g}" class="note"/>'
            f'<text class="comment">{text}</text>'
        )
        return [_box(element, svg)]
    if kind in ("LEFT_RAIL", "RIGHT_RAIL"):  # its wires reach it: no stubs of its own
        edge = x + w - 3 if kind == "LEFT_RAIL" else x
        svg = f'<rect x="{edge:g}" y="{y:g}" width="3" height="{h:g}" class="rail"/>'
        return [_box(element, svg)]
    if kind in ("CONTACT", "COIL"):
        return [_contact_or_coil(element)]
    return []


def _comment_lines(text: str, width: float) -> list[str]:
    per_line = max(int((width - 12) / 6), 8)
    lines: list[str] = []
    for paragraph in text.splitlines() or [""]:
        lines += textwrap.wrap(paragraph, per_line) or [""]
    return lines


def _contact_or_coil(element: Element) -> Part:
    x, y, w, h = element.at.x, element.at.y, element.size.x, element.size.y
    inputs, _ = pin_places(element)
    pin_y = inputs[0].y if inputs else y + h / 2
    left, right = x + w * 0.25, x + w * 0.75  # room for a mark (/, P, N, S, R) between
    top, bottom = pin_y - h / 2, pin_y + h / 2
    mark = ""
    modifier = element.modifiers[0] if element.modifiers else ""
    if element.kind == "CONTACT":
        symbol = (
            f"M{x:g},{pin_y:g} H{left:g} M{left:g},{top:g} V{bottom:g} "
            f"M{right:g},{top:g} V{bottom:g} M{right:g},{pin_y:g} H{x + w:g}"
        )
        mark = _CONTACT_MARK.get(modifier, "")
    else:
        bend = (right - left) * 0.2  # two arcs, ( and ), with room for the mark between
        symbol = (
            f"M{x:g},{pin_y:g} H{left:g} M{left + bend:g},{top:g} Q{left - bend:g},{pin_y:g} "
            f"{left + bend:g},{bottom:g} M{right - bend:g},{top:g} Q{right + bend:g},"
            f"{pin_y:g} {right - bend:g},{bottom:g} M{right:g},{pin_y:g} H{x + w:g}"
        )
        mark = _COIL_MARK.get(modifier, "")
    name = _short(element.text, _MAX_TEXT)
    svg = (
        f'<path d="{symbol}" class="sym"/>'
        f'<text x="{x + w / 2:g}" y="{top - 4:g}" class="mark">{escape(name)}</text>'
    )
    if mark:
        svg += f'<text x="{x + w / 2:g}" y="{pin_y + 4:g}" class="mark">{escape(mark)}</text>'
    half = max(w, len(name) * 6.2) / 2
    return Part(svg, top - 16, bottom, x + w / 2 - half, x + w / 2 + half)


def _block(element: Element) -> Part:
    x, y, w, h = element.at.x, element.at.y, element.size.x, element.size.y
    inputs, outputs = pin_places(element)
    # the type inside the box above its pins, or above the box when a pin is too near its
    # top edge to leave a line for it (a drawing may put pins anywhere)
    inside = min((p.y for p in (*inputs, *outputs)), default=y + h) - y >= 22
    type_y = y + 14 if inside else y - 4
    svg = [
        f'<rect x="{x:g}" y="{y:g}" width="{w:g}" height="{h:g}" class="box"/>'
        f'<text x="{x + w / 2:g}" y="{type_y:g}" class="type">'
        f"{escape(_short(element.text, int(w / 7.5) + 2))}</text>"
    ]
    above = 0.0 if inside else _INSTANCE_ROOM
    if element.instance:
        above += _INSTANCE_ROOM
        svg.append(
            f'<text x="{x + w / 2:g}" y="{y - 4 - (0 if inside else _INSTANCE_ROOM):g}" '
            f'class="inst">{escape(_short(element.instance, _MAX_TEXT))}</text>'
        )
    if element.order:
        svg.append(
            f'<text x="{x + w - 2:g}" y="{y + h - 3:g}" class="order">{element.order}</text>'
        )
    half = int(w / 2 / 6.2)
    for pin, at in zip(element.inputs, inputs, strict=True):
        indent = 13 if pin.flag in ("R_EDGE", "F_EDGE") else 5  # room for the `>`
        svg.append(
            f'<text x="{x + indent:g}" y="{at.y + 3.5:g}" class="pin">'
            f"{escape(_short(pin.name, half))}</text>"
        )
        svg.append(_pin_flag(pin.flag, at, inward=1))
    for pin, at in zip(element.outputs, outputs, strict=True):
        indent = 13 if pin.flag in ("R_EDGE", "F_EDGE") else 5
        svg.append(
            f'<text x="{x + w - indent:g}" y="{at.y + 3.5:g}" class="pinr">'
            f"{escape(_short(pin.name, half))}</text>"
        )
        svg.append(_pin_flag(pin.flag, at, inward=-1))
    return Part("".join(svg), y - above, y + h, x, x + w)


def _pin_flag(flag: str, at: Point, inward: int) -> str:
    """NOT as a small circle outside the box; an edge as `>` (rising) or `<` (falling)
    inside it, at the pin."""
    if flag == "NOT":
        return f'<circle cx="{at.x - 4 * inward:g}" cy="{at.y:g}" r="3.5" class="neg"/>'
    if flag in ("R_EDGE", "F_EDGE"):
        tip, back = (at.x + 7 * inward, at.x) if flag == "R_EDGE" else (at.x, at.x + 7 * inward)
        shape = f"M{back:g},{at.y - 4:g} L{tip:g},{at.y:g} L{back:g},{at.y + 4:g}"
        return f'<path d="{shape}" class="sym"/>'
    return ""


def _wire(body: GraphicBody, wire: Wire, to: Point, level: bool, lane: int) -> list[Part]:
    points = list(wire.points)
    if len(points) < 2:
        start = _source_point(body, wire, to)
        if start is None:
            return []
        points = _route(start, Point(to.x, start.y) if level else to, lane)
    path = "M" + " L".join(f"{p.x:g},{p.y:g}" for p in points)
    xs, ys = [p.x for p in points], [p.y for p in points]
    svg = f'<path d="{path}" class="wire"/>'
    return [Part(svg, min(ys), max(ys), min(xs), max(xs), False, 0, wire.element, wire.pin)]


def _route(start: Point, end: Point, lane: int) -> list[Point]:
    """Right from the source, across in its lane, right into the pin; a wire back to the
    left (a feedback) goes round below both ends."""
    if end.x - start.x >= 16:
        middle = start.x + (end.x - start.x) * (lane + 1) / (_LANES + 1)
        return [start, Point(middle, start.y), Point(middle, end.y), end]
    low = max(start.y, end.y) + 24
    return [
        start,
        Point(start.x + 8, start.y),
        Point(start.x + 8, low),
        Point(end.x - 8, low),
        Point(end.x - 8, end.y),
        end,
    ]


def placed(body: GraphicBody) -> GraphicBody:
    """The body with a place for every element: its own when it has them, else laid out."""
    return body if laid_out(body) else auto_layout(body)
