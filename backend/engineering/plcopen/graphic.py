"""An FBD or LD body of a PLCopen TC6 file (1.0 to 2.01) into a `GraphicBody`.

Everything TC6 says of an element is kept: its local id, place, size, execution order, pins
with their formal parameters, relative positions, negation, edge and storage, and each
connection with the points it is drawn through, so that the body can be written back
(`graphic_xml.py`). What the model has no place for (an inline expression on a pin, a pin
both negated and edge-triggered, a vendor's element) is refused with the place and the
reason, as is a drawing that breaks the schema: an element without its local id, an id
used twice, a connection to an element that is not there, a position that is no number.
The importer leaves such a POU out and names the place.
"""

from __future__ import annotations

import re
from dataclasses import replace

from backend.compiler.graphics.model import Element, GraphicBody, Pin, Point, Wire
from backend.compiler.graphics.text_form import (
    MAX_COORDINATE,
    element_line,
    read_body,
    write_body,
)
from backend.engineering.plcopen.issues import Where
from backend.engineering.plcopen.xml_tree import Element as Xml
from backend.engineering.plcopen.xml_tree import st_source

IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")
NUMBER = re.compile(r"[+-]?([0-9]+(\.[0-9]*)?|\.[0-9]+)\Z")  # xsd:decimal: no NaN, no 1e9
# a local id or an execution order (CODESYS numbers elements from 10^10 up, per network)
WHOLE = re.compile(r"[0-9]{1,18}\Z")
LARGEST = MAX_COORDINATE  # a coordinate, size or execution order beyond this is no drawing
NOT_PARTS = ("addData", "documentation")
GROUPS = ("inputVariables", "inOutVariables", "outputVariables")  # a block's pins
UNSET = "???"  # CODESYS's expression on a connection point that is not connected
# TC6 element -> the model's kind
KIND_OF = {
    "inVariable": "IN",
    "outVariable": "OUT",
    "inOutVariable": "INOUT",
    "block": "BLOCK",
    "connector": "CONNECTOR",
    "continuation": "CONTINUATION",
    "jump": "JUMP",
    "label": "LABEL",
    "return": "RETURN",
    "comment": "COMMENT",
    "leftPowerRail": "LEFT_RAIL",
    "rightPowerRail": "RIGHT_RAIL",
    "contact": "CONTACT",
    "coil": "COIL",
}
EDGES = {"none": "", "rising": "R_EDGE", "falling": "F_EDGE"}
STORAGE = {"none": "", "set": "SET", "reset": "RESET"}


class DrawingProblem(Exception):
    """The body cannot be read: `where` in the XML, and why."""

    def __init__(self, where: Where, message: str) -> None:
        super().__init__(message)
        self.where = where
        self.message = message


def graphic_body(body: Xml) -> GraphicBody:
    """The <FBD> or <LD> element as a GraphicBody, its elements in the order of the file."""
    elements: list[Element] = []
    seen: dict[int, Xml] = {}
    connections: list[Xml] = []  # each wire's <connection>, in the order they are read
    for item in body.children:
        if item.tag in NOT_PARTS:
            continue
        if item.tag == "vendorElement" and not _pins(item):
            continue  # drawn only for the tool that wrote it (CODESYS's network titles)
        if item.tag not in KIND_OF:
            raise DrawingProblem(
                item.where, f"a <{item.tag}> in an <{body.tag}> body, which padt does not draw"
            )
        element = _element(item, connections)
        if element.id in seen:
            raise DrawingProblem(
                item.where,
                f"localId {element.id} is used twice (also at line {seen[element.id].where.line})",
            )
        seen[element.id] = item
        elements.append(element)
    drawn = GraphicBody(body.tag, tuple(elements))
    _check_wires(drawn, connections)
    _check_text_form(drawn, seen)
    return drawn


def _pins(item: Xml) -> bool:
    """Whether a vendor's element takes part in the logic: it has a connection point."""
    parts = ("connectionPointIn", "connectionPointOut", *GROUPS)
    return any(child.tag in parts for child in item.children)


def _check_text_form(body: GraphicBody, items: dict[int, Xml]) -> None:
    """Each element reads back from its line of the text form as it is: an expression or a
    name that would not (one holding `//`, `{`, `->`, ...) is refused here, not written
    into a file that means something else."""
    read, problems = read_body(write_body(body), "", 1, 1)
    why = {problem.line: problem.message for problem in problems}
    for line, element in enumerate(body.elements, start=2):  # line 1: the keyword
        again = read.element(element.id)
        if again is None or replace(again, line=0, col=0) != element:
            words = f" {element.text!r}" if element.text else ""
            reason = why.get(line, f"`{element_line(element)}` reads back as another element")
            raise DrawingProblem(
                items[element.id].where,
                f"the {element.kind}{words} (localId {element.id}) does not fit a line of the "
                f"text form: {reason}",
            )


def _element(item: Xml, connections: list[Xml]) -> Element:
    kind = KIND_OF[item.tag]
    local = _whole(item, "localId", required=True)
    base = Element(
        id=local,
        kind=kind,
        order=_order(item),
        at=_point(_required(item, "position")),
        size=Point(_number(item, "width"), _number(item, "height")),
    )
    if kind == "IN":
        flag = _output_flag(item, "negated", "edge")
        _no_storage(item, "storage")
        return replace(base, text=_expression(item), outputs=(_pin_out(item, "", flag),))
    if kind == "OUT":
        return replace(
            base,
            text=_expression(item),
            modifiers=_storage(item, "storage"),
            inputs=(_pin_in(item, connections, "", _flag(item, "negated", "edge")),),
        )
    if kind == "INOUT":
        _no_storage(item, "storageOut")
        return replace(
            base,
            text=_expression(item),
            modifiers=_storage(item, "storageIn"),
            inputs=(_pin_in(item, connections, "", _flag(item, "negatedIn", "edgeIn")),),
            outputs=(_pin_out(item, "", _output_flag(item, "negatedOut", "edgeOut")),),
        )
    if kind == "BLOCK":
        inputs, outputs = _block_pins(item, connections)
        instance = item.attrs.get("instanceName", "").strip()
        return replace(
            base,
            text=_identifier(item, "typeName"),
            instance=_identifier(item, "instanceName") if instance else "",
            inputs=inputs,
            outputs=outputs,
        )
    if kind in ("CONNECTOR", "CONTINUATION"):
        name = _identifier(item, "name")
        if kind == "CONNECTOR":
            return replace(base, text=name, inputs=(_pin_in(item, connections, "", ""),))
        return replace(base, text=name, outputs=(_pin_out(item, "", ""),))
    if kind == "JUMP":
        text = _identifier(item, "label")
        return replace(base, text=text, inputs=(_pin_in(item, connections, "", ""),))
    if kind == "LABEL":
        return replace(base, text=_identifier(item, "label"))
    if kind == "RETURN":
        return replace(base, inputs=(_pin_in(item, connections, "", ""),))
    if kind == "COMMENT":
        return replace(base, text=st_source(_required(item, "content")))
    if kind == "LEFT_RAIL":
        pins = tuple(_out(point, "") for point in item.all("connectionPointOut"))
        return replace(base, outputs=pins)
    if kind == "RIGHT_RAIL":
        pins = tuple(_in(p, connections, "", "") for p in item.all("connectionPointIn"))
        return replace(base, inputs=pins)
    return replace(  # CONTACT, COIL
        base,
        text=_variable(item),
        modifiers=_ld_modifiers(item, kind),
        inputs=(_pin_in(item, connections, "", ""),),
        outputs=(_pin_out(item, "", ""),),
    )


def _block_pins(block: Xml, connections: list[Xml]) -> tuple[tuple[Pin, ...], tuple[Pin, ...]]:
    """The inputs (inputVariables, then inOutVariables) and outputs (inOutVariables, then
    outputVariables) of a block: an in-out variable is a pin of each, of the same name."""
    inputs: list[Pin] = []
    outputs: list[Pin] = []
    names: dict[str, int] = {}
    for group in GROUPS:
        holder = block.child(group)
        for variable in holder.all("variable") if holder is not None else []:
            name = variable.attrs.get("formalParameter")
            if name is None or not IDENTIFIER.match(name):
                raise DrawingProblem(
                    variable.where, f"a pin of block {block.attrs.get('localId')} without a name"
                )
            if name.upper() in names:
                raise DrawingProblem(
                    variable.where,
                    f"block {block.attrs.get('localId')} has two pins {name} (also at line "
                    f"{names[name.upper()]})",
                )
            names[name.upper()] = variable.where.line
            _no_storage(variable, "storage")
            flag = (_output_flag if group == "outputVariables" else _flag)(
                variable, "negated", "edge"
            )
            if group != "outputVariables":
                inputs.append(_pin_in(variable, connections, name, flag))
            if group != "inputVariables":
                # an in-out pin's negation and edge belong to its input
                outputs.append(_pin_out(variable, name, "" if group == "inOutVariables" else flag))
    return tuple(inputs), tuple(outputs)


def _pin_in(item: Xml, connections: list[Xml], name: str, flag: str) -> Pin:
    """The input pin of an element (TC6 lets an unconnected pin leave out its point)."""
    point = item.child("connectionPointIn")
    return _in(point, connections, name, flag) if point is not None else Pin(name, (), flag)


def _pin_out(item: Xml, name: str, flag: str) -> Pin:
    point = item.child("connectionPointOut")
    return _out(point, name, flag) if point is not None else Pin(name, (), flag)


def _in(point: Xml, connections: list[Xml], name: str, flag: str) -> Pin:
    _no_expression(point)
    wires = []
    for connection in point.all("connection"):
        source = _whole(connection, "refLocalId", required=True)
        pin = connection.attrs.get("formalParameter", "")
        points = tuple(_point(p) for p in connection.all("position"))
        wires.append(Wire(source, pin, points))
        connections.append(connection)
    return Pin(name, tuple(wires), flag, _relative(point))


def _out(point: Xml, name: str, flag: str = "") -> Pin:
    _no_expression(point)
    return Pin(name, (), flag, _relative(point))


def _no_expression(point: Xml) -> None:
    """TC6 lets a connection point hold an expression instead of connections; padt wires
    pins only. CODESYS's `???` (nothing there) is taken for what it says."""
    expression = point.child("expression")
    if expression is not None and expression.text().strip() not in ("", UNSET):
        raise DrawingProblem(
            expression.where, "an expression on a connection point (padt wires pins only)"
        )


def _relative(point: Xml) -> Point | None:
    relative = point.child("relPosition")
    return _point(relative) if relative is not None else None


def _check_wires(body: GraphicBody, connections: list[Xml]) -> None:
    """Each connection leads from an element of the body (and a block's output pin)."""
    wires = [(e, w) for e in body.elements for pin in e.inputs for w in pin.wires]
    for (element, wire), connection in zip(wires, connections, strict=True):
        source = body.element(wire.element)
        if source is None:
            problem = f"localId {wire.element}, which is no element of the body"
        elif source.kind == "BLOCK" and not any(
            p.name.upper() == wire.pin.upper() for p in source.outputs
        ):
            problem = (
                f"output {wire.pin or '(none)'} of block {source.id} ({source.text}), "
                "which has no such output"
            )
        elif not source.outputs:
            problem = f"element {source.id}, which has no output"
        else:
            continue
        raise DrawingProblem(connection.where, f"element {element.id} is connected to {problem}")


# ---- attributes -------------------------------------------------------------------------


def _required(item: Xml, tag: str) -> Xml:
    found = item.child(tag)
    if found is None:
        raise DrawingProblem(item.where, f"<{item.tag}> without <{tag}>")
    return found


def _whole(item: Xml, attribute: str, required: bool = False) -> int:
    text = item.attrs.get(attribute)
    if text is None:
        if required:
            raise DrawingProblem(item.where, f"<{item.tag}> without its {attribute}")
        return 0
    if not WHOLE.match(text.strip()):
        raise DrawingProblem(item.where, f"<{item.tag}> {attribute} {text!r} is no whole number")
    return int(text)


def _order(item: Xml) -> int:
    order = _whole(item, "executionOrderId")
    if abs(order) > LARGEST:
        raise DrawingProblem(item.where, f"<{item.tag}> executionOrderId {order} is no order")
    return order


def _number(item: Xml, attribute: str, required: bool = False) -> float:
    text = item.attrs.get(attribute)
    if text is None:
        if required:
            raise DrawingProblem(item.where, f"<{item.tag}> without its {attribute}")
        return 0.0
    if not NUMBER.match(text.strip()) or abs(float(text)) > LARGEST:
        raise DrawingProblem(item.where, f"<{item.tag}> {attribute} {text!r} is no coordinate")
    return float(text)


def _point(item: Xml) -> Point:
    return Point(_number(item, "x", required=True), _number(item, "y", required=True))


def _identifier(item: Xml, attribute: str) -> str:
    name = item.attrs.get(attribute, "").strip()
    if not IDENTIFIER.match(name):
        raise DrawingProblem(item.where, f"<{item.tag}> {attribute} {name!r} is no IEC identifier")
    return name


def _text(item: Xml, tag: str) -> str:
    """The text of an <expression> or <variable>: one line of ST."""
    text = _required(item, tag).text().strip()
    if not text:
        raise DrawingProblem(item.where, f"<{item.tag}> with an empty <{tag}>")
    if "\n" in text or "\r" in text:
        raise DrawingProblem(item.where, f"<{item.tag}> with an <{tag}> that spans lines")
    return text


def _expression(item: Xml) -> str:
    return _text(item, "expression")


def _variable(item: Xml) -> str:
    return _text(item, "variable")


def _true(item: Xml, attribute: str) -> bool:
    value = item.attrs.get(attribute, "false").strip().lower()
    if value not in ("true", "false", "1", "0"):
        raise DrawingProblem(item.where, f"<{item.tag}> {attribute} {value!r} is no boolean")
    return value in ("true", "1")


def _edge(item: Xml, attribute: str) -> str:
    value = item.attrs.get(attribute, "none").strip()
    if value not in EDGES:
        raise DrawingProblem(
            item.where, f"<{item.tag}> {attribute} {value!r} is none, rising or falling"
        )
    return EDGES[value]


def _flag(item: Xml, negated: str, edge: str) -> str:
    """A pin's flag: NOT, R_EDGE, F_EDGE or "" (one at most: IEC draws one)."""
    not_ = _true(item, negated)
    triggered = _edge(item, edge)
    if not_ and triggered:
        raise DrawingProblem(
            item.where, f"<{item.tag}> both negated and {triggered} (a pin takes one of them)"
        )
    return "NOT" if not_ else triggered


def _output_flag(item: Xml, negated: str, edge: str) -> str:
    """An output pin's flag: NOT or "" (an edge is detected where a value comes in)."""
    flag = _flag(item, negated, edge)
    if flag not in ("", "NOT"):
        raise DrawingProblem(
            item.where, f"<{item.tag}> {edge} on an output (padt detects edges on inputs)"
        )
    return flag


def _storage(item: Xml, attribute: str) -> tuple[str, ...]:
    value = item.attrs.get(attribute, "none").strip()
    if value not in STORAGE:
        raise DrawingProblem(
            item.where, f"<{item.tag}> {attribute} {value!r} is none, set or reset"
        )
    return (STORAGE[value],) if STORAGE[value] else ()


def _no_storage(item: Xml, attribute: str) -> None:
    """A storage where IEC has none (an input, a block's pin): refused, not dropped."""
    if _storage(item, attribute):
        raise DrawingProblem(
            item.where,
            f"<{item.tag}> {attribute} {item.attrs[attribute]!r}: only an output "
            "variable or a coil sets or resets",
        )


def _ld_modifiers(item: Xml, kind: str) -> tuple[str, ...]:
    """CONTACT: NEGATED, RISING or FALLING; COIL: those, SET or RESET (one at most)."""
    found = ["NEGATED"] if _true(item, "negated") else []
    found += {"R_EDGE": ["RISING"], "F_EDGE": ["FALLING"], "": []}[_edge(item, "edge")]
    if kind == "COIL":
        found += list(_storage(item, "storage"))
    else:
        _no_storage(item, "storage")
    if len(found) > 1:
        raise DrawingProblem(
            item.where,
            f"a {kind.lower()} both {' and '.join(m.lower() for m in found)} (IEC draws one)",
        )
    return tuple(found)
