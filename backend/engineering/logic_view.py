"""The logic of a program or FB instance of a running resource, for a live drawing: which
instances have a body to draw (an SFC chart, an FBD or LD body), and its geometry with the
path of the variable that holds each live value: a step's `.X` and `.T`, the kept value of
a transition condition (`backend/compiler/resolve.py` `transition_variable`); in FBD and LD
what each output pin puts out, as the lowering keeps it
(`backend/compiler/graphics/lower.py` `value_variable`), and the variable an IN, OUT,
contact or coil names.

Only the runtime's values are shown: nothing here evaluates anything of the source."""

from __future__ import annotations

import re
from collections.abc import Callable, Collection
from dataclasses import dataclass

from backend.compiler import ast
from backend.compiler.graphics.lower import value_variable
from backend.compiler.graphics.model import Element, GraphicBody, Point
from backend.compiler.parse import parse_source
from backend.compiler.resolve import transition_variable
from backend.engineering.graphic_drawing import Part, draw, output_place, pin_places, placed
from backend.engineering.sfc_layout import ChartLayout, chart_layout
from backend.engineering.sources import ConfigurationSources, PouSource

TRUE = "TRUE"  # what a left rail puts out


@dataclass(frozen=True)
class LiveChart:
    """An SFC chart of one instance: where its parts stand, and the variables of its values."""

    instance: str  # `Batch`, `Line.filler`
    pou: str
    file: str
    layout: ChartLayout
    steps: dict[str, str]  # step name -> the path of its SFC_STEP variable (`Batch.Fill`)
    transitions: tuple[str, ...]  # by number: the path of the kept condition value

    def watched(self) -> list[str]:
        """Every variable the chart shows."""
        steps = [f"{path}.{member}" for path in self.steps.values() for member in ("X", "T")]
        return steps + list(self.transitions)


@dataclass(frozen=True)
class DrawnValue:
    """A live value drawn on an FBD or LD body: the variable's path, and where its label
    goes (the drawing's units: left end of the text, its baseline)."""

    path: str
    at: Point
    element: int  # the element it belongs to


@dataclass(frozen=True)
class LiveGraphic:
    """An FBD or LD body of one instance: its parts as drawn, the values on it, and what
    each wire carries (to colour the ones that carry TRUE: LD's power flow)."""

    instance: str
    pou: str
    file: str
    language: str  # FBD, LD
    parts: tuple[Part, ...]
    values: tuple[DrawnValue, ...]
    carried: dict[tuple[int, str], str]  # (element, output pin) -> TRUE or a variable's path

    def watched(self) -> list[str]:
        paths = [v.path for v in self.values] + list(self.carried.values())
        return list(dict.fromkeys(p for p in paths if p != TRUE))


class LogicBodies:
    """The POUs of one running configuration parsed for drawing, each once, when first
    asked (a configuration's sources do not change)."""

    def __init__(self, sources: ConfigurationSources) -> None:
        self.sources = sources
        self._parsed: dict[str, ast.Pou | None] = {}

    def kind(self, instance: str) -> str | None:
        """`SFC` when the instance's body is a chart, `FBD` or `LD` when it is drawn; None
        when it has nothing to draw. A chart is known from the compiled configuration."""
        unit = self.sources.pou_of(instance)
        if unit is not None and unit.chart is not None and unit.chart.steps:
            return "SFC"
        source = self.sources.source_of(instance)
        if source is None or not _maybe_drawn(source):
            return None  # nothing to parse: no line of the POU opens a drawing
        pou = self._pou(instance)
        return pou.graphic.language if pou is not None and pou.graphic is not None else None

    def drawable(self, instances: list[str]) -> list[str]:
        return [instance for instance in instances if self.kind(instance) is not None]

    def chart(self, instance: str) -> LiveChart | None:
        source = self.sources.source_of(instance)
        pou = self._pou(instance)
        if source is None or pou is None or pou.sfc is None or not pou.sfc.steps:
            return None
        return LiveChart(
            instance=instance,
            pou=pou.name,
            file=source.file,
            layout=chart_layout(pou.sfc, source.lines),
            steps={step.name: f"{instance}.{step.name}" for step in pou.sfc.steps},
            transitions=tuple(
                f"{instance}.{transition_variable(n)}" for n in range(len(pou.sfc.transitions))
            ),
        )

    def graphic(self, instance: str, paths: Collection[str]) -> LiveGraphic | None:
        """The body drawn, with the values the running resource has (`paths`: its
        variables): a value the lowering inlined is in no variable, and is not shown."""
        source = self.sources.source_of(instance)
        pou = self._pou(instance)
        if source is None or pou is None or pou.graphic is None:
            return None
        body = placed(pou.graphic)
        known = {path.upper(): path for path in paths}
        named = _named(instance, body, paths)

        def variable(name: str | None) -> str | None:
            return known.get(f"{instance}.{name}".upper()) if name else None

        carried: dict[tuple[int, str], str] = {}
        for element in body.elements:
            for pin in element.outputs:
                found = _carried(body, element, pin.name, variable, named, 0)
                if found is not None:
                    carried[(element.id, pin.name)] = found
        values: list[DrawnValue] = []
        for element in body.elements:
            values += _labels(element, carried, named)
        return LiveGraphic(
            instance=instance,
            pou=pou.name,
            file=source.file,
            language=pou.graphic.language,
            parts=tuple(draw(body)),
            values=tuple(values),
            carried=carried,
        )

    def _pou(self, instance: str) -> ast.Pou | None:
        source = self.sources.source_of(instance)
        if source is None:
            return None
        if source.name.upper() not in self._parsed:
            self._parsed[source.name.upper()] = _parsed(source)
        return self._parsed[source.name.upper()]


def _parsed(source: PouSource) -> ast.Pou | None:
    """The POU alone, parsed from its own lines: positions count from its first line, as
    `source.lines` does (the configuration compiled, so its text parses)."""
    unit = parse_source(source.file, "\n".join(source.lines))
    return next((pou for pou in unit.pous if pou.name.upper() == source.name.upper()), None)


def _maybe_drawn(source: PouSource) -> bool:
    """Whether a line of the POU is `FBD` or `LD` alone, as a drawn body opens."""
    return any(line.strip().upper() in ("FBD", "LD") for line in source.lines)


_REFERENCE = re.compile(r"[A-Za-z_]\w*(?:\.[A-Za-z_]\w*)*")


def variable_path(instance: str, text: str, known: dict[str, str]) -> str | None:
    """The path of the variable `text` names in a POU of `instance`: the instance's own
    (`Count.total`, `Count.timer.Q`) before a global of the same name, as in ST; None for
    an expression or a constant, which no one variable holds. `known`: the resource's
    paths by their upper case."""
    text = text.strip()
    if not _REFERENCE.fullmatch(text):
        return None
    return known.get(f"{instance}.{text}".upper()) or known.get(text.upper())


def _named(instance: str, body: GraphicBody, paths: Collection[str]) -> dict[int, str]:
    """element id -> the path of the variable an IN, OUT, INOUT, contact or coil names."""
    known = {path.upper(): path for path in paths}
    found: dict[int, str] = {}
    for element in body.elements:
        if element.kind in ("IN", "OUT", "INOUT", "CONTACT", "COIL"):
            path = variable_path(instance, element.text, known)
            if path is not None:
                found[element.id] = path
    return found


_MAX_CONTINUATIONS = 16  # a continuation of a connector fed by a continuation, and so on


def _carried(
    body: GraphicBody,
    element: Element,
    pin: str,
    variable: Callable[[str | None], str | None],
    named: dict[int, str],
    depth: int,
) -> str | None:
    """What an element's output pin puts out: TRUE, or the path of the variable that holds
    it; None when no variable does."""
    if element.kind == "LEFT_RAIL":
        return TRUE
    if element.kind in ("CONTACT", "COIL", "BLOCK"):
        return variable(value_variable(body, element.id, pin))
    if element.kind in ("IN", "INOUT"):
        return named.get(element.id)
    if element.kind == "CONTINUATION" and depth < _MAX_CONTINUATIONS:
        connector = next(
            (
                e
                for e in body.elements
                if e.kind == "CONNECTOR" and e.text.upper() == element.text.upper()
            ),
            None,
        )
        wires = [w for p in connector.inputs for w in p.wires] if connector else []
        source = body.element(wires[0].element) if len(wires) == 1 else None
        if source is not None:
            return _carried(body, source, wires[0].pin, variable, named, depth + 1)
    return None


_LIFT = 4  # a value's label stands this far above its wire


def _labels(
    element: Element, carried: dict[tuple[int, str], str], named: dict[int, str]
) -> list[DrawnValue]:
    """The values drawn at an element: what each output pin puts out, beside it; the
    variable an OUT writes, after its box; the variable of a contact or coil, under it."""
    x, y, w, h = element.at.x, element.at.y, element.size.x, element.size.y
    if element.kind in ("CONTACT", "COIL"):
        path = named.get(element.id)
        inputs, _ = pin_places(element)
        pin_y = inputs[0].y if inputs else y + h / 2
        return [DrawnValue(path, Point(x, pin_y + h / 2 + 12), element.id)] if path else []
    if element.kind == "OUT":
        path = named.get(element.id)
        return [DrawnValue(path, Point(x + w + 4, y + h / 2 + 4), element.id)] if path else []
    if element.kind not in ("BLOCK", "IN", "INOUT"):
        return []
    found = []
    for pin in element.outputs:
        path = carried.get((element.id, pin.name))
        if path is not None and path != TRUE:
            at = output_place(element, pin.name)
            found.append(DrawnValue(path, Point(at.x + 4, at.y - _LIFT), element.id))
    return found
