"""A graphical body as data: the elements of an FBD or LD drawing and the wires between them,
with everything PLCopen TC6 XML says of them (so that an import can be written back), and
where each element is written in its ST file (so that diagnostics and the debugger point
at it).

The vocabulary follows TC6: an element has a local id, input pins that take wires from
other elements' output pins, and a place on the sheet. Semantics live elsewhere
(`order.py`, `lower.py`); this module only says what a drawing is.
"""

from __future__ import annotations

from dataclasses import dataclass

# the kinds of element, by language; an LD body may hold FBD elements (TC6 allows it)
FBD_KINDS = (
    "IN",  # inVariable: a variable or expression read
    "OUT",  # outVariable: a variable written
    "INOUT",  # inOutVariable: written, then read on
    "BLOCK",  # a FUNCTION, or an FB instance (`instance` set)
    "CONNECTOR",  # connector: the value wired into it travels to continuations by name
    "CONTINUATION",  # continuation: the value of the connector of its name
    "JUMP",  # jump to a label when its input is TRUE
    "LABEL",  # a label that jumps go to
    "RETURN",  # return from the POU when its input is TRUE
    "COMMENT",  # a comment on the sheet
)
LD_KINDS = ("LEFT_RAIL", "RIGHT_RAIL", "CONTACT", "COIL")
KINDS = FBD_KINDS + LD_KINDS

# modifiers an element kind takes (written `KIND[MOD]`)
MODIFIERS: dict[str, tuple[str, ...]] = {
    "CONTACT": ("NEGATED", "RISING", "FALLING"),
    "COIL": ("NEGATED", "SET", "RESET", "RISING", "FALLING"),
    "OUT": ("SET", "RESET"),  # TC6 `storage` of an outVariable
    "INOUT": ("SET", "RESET"),
}

# how an input pin treats what is wired into it (TC6 `negated`, `edge`)
PIN_FLAGS = ("NOT", "R_EDGE", "F_EDGE")


@dataclass(frozen=True)
class Point:
    x: float
    y: float


@dataclass(frozen=True)
class Wire:
    """One wire into an input pin: from `element`'s output pin `pin` ("" for an element's
    only output, or any pin of a left rail), with the points TC6 draws it through."""

    element: int
    pin: str = ""
    points: tuple[Point, ...] = ()


@dataclass(frozen=True)
class Pin:
    """A connection point. An input pin takes wires (several: wired OR, as in LD); `flag`
    is NOT, R_EDGE, F_EDGE or "". `name` is the formal parameter of a block, "" for an
    element's only pin (a rail's pins are all "")."""

    name: str = ""
    wires: tuple[Wire, ...] = ()
    flag: str = ""
    at: Point | None = None  # relative to the element, as TC6 gives it


@dataclass(frozen=True)
class Element:
    """One element of the drawing. `text` is what the element names: the ST expression of an
    IN, OUT or INOUT; the type of a BLOCK; the name of a CONNECTOR, CONTINUATION, JUMP or
    LABEL; the variable of a CONTACT or COIL; the words of a COMMENT."""

    id: int
    kind: str
    text: str = ""
    instance: str = ""  # a BLOCK that is an FB instance: the instance's name
    modifiers: tuple[str, ...] = ()
    inputs: tuple[Pin, ...] = ()
    outputs: tuple[Pin, ...] = ()
    order: int = 0  # TC6 executionOrderId; 0: none given
    at: Point = Point(0, 0)
    size: Point = Point(0, 0)
    line: int = 0  # where the element is written in its file (1-based; 0: not written)
    col: int = 0

    def input(self, name: str = "") -> Pin | None:
        return next((p for p in self.inputs if p.name.upper() == name.upper()), None)


@dataclass(frozen=True)
class GraphicBody:
    """The body of a POU drawn in `language` (FBD or LD)."""

    language: str
    elements: tuple[Element, ...]
    line: int = 0  # the line of the body's first keyword in its file
    col: int = 0

    def element(self, element_id: int) -> Element | None:
        return next((e for e in self.elements if e.id == element_id), None)
