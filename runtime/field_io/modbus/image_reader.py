"""The values of the served points after a cycle, read fast enough for 1,000 points."""

from __future__ import annotations

import operator
from typing import Any

from runtime.contract.modbus import Point
from runtime.variables import Variables


def is_output(point: Point) -> bool:
    return point.location.upper().startswith("%Q")


class ImageReader:
    """The values of the served points after a cycle, in the store's order (outputs
    first): outputs from the output image (safe in STOP), the others from the globals,
    each group with one C-level getter call, not a Python loop over 1,000 points."""

    def __init__(self, points: tuple[Point, ...], variables: Variables) -> None:
        self._variables = variables
        self._points = points
        outputs = [p.variable for p in points if is_output(p)]
        others = [p for p in points if not is_output(p)]
        self._outputs = operator.itemgetter(*outputs) if outputs else None
        self._single_output = len(outputs) == 1
        bound = [variables.find(p.variable) for p in others]
        simple = all(b is not None and b.program is None and len(b.path.attrs) == 1 for b in bound)
        attrs = [str(b.path.attrs[0]) for b in bound if b is not None] if simple else []
        self._others = operator.attrgetter(*attrs) if attrs else None
        self._single_other = len(attrs) == 1
        self._bound = bound
        self._other_points = others

    def values(self, outputs: dict[str, Any], globals_: Any) -> tuple[Any, ...]:
        head = self._output_values(outputs)
        if self._others is not None:
            tail = self._others(globals_)
            return (*head, *((tail,) if self._single_other else tail))
        read = self._variables.read
        return (*head, *(
            read(b) if b is not None else p.safe_value
            for p, b in zip(self._other_points, self._bound, strict=True)
        ))  # fmt: skip

    def _output_values(self, outputs: dict[str, Any]) -> tuple[Any, ...]:
        if self._outputs is None:
            return ()
        try:
            found = self._outputs(outputs)
        except KeyError:  # no output image yet
            served = (p for p in self._points if is_output(p))
            return tuple(outputs.get(p.variable, p.safe_value) for p in served)
        return (found,) if self._single_output else tuple(found)
