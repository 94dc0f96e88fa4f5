"""A `GraphicBody` written as the <FBD> or <LD> body element of PLCopen TC6 2.01: the
inverse of `graphic.py`, so that a drawing imported and kept in its text form goes back to
the tools it came from with every element, pin, place and wire point it had."""

from __future__ import annotations

from xml.sax.saxutils import escape, quoteattr

from backend.compiler.graphics.model import Element, GraphicBody, Pin, Point

TC6 = "http://www.plcopen.org/xml/tc6_0201"
XHTML = "http://www.w3.org/1999/xhtml"
INDENT = "  "
TAG_OF = {
    "IN": "inVariable",
    "OUT": "outVariable",
    "INOUT": "inOutVariable",
    "BLOCK": "block",
    "CONNECTOR": "connector",
    "CONTINUATION": "continuation",
    "JUMP": "jump",
    "LABEL": "label",
    "RETURN": "return",
    "COMMENT": "comment",
    "LEFT_RAIL": "leftPowerRail",
    "RIGHT_RAIL": "rightPowerRail",
    "CONTACT": "contact",
    "COIL": "coil",
}
EDGE_OF = {"R_EDGE": "rising", "F_EDGE": "falling"}


def body_xml(body: GraphicBody) -> str:
    """The body element, with the TC6 and XHTML namespaces declared on it (a document that
    declares them already may take it as it is)."""
    lines = [f"<{body.language} xmlns={quoteattr(TC6)} xmlns:xhtml={quoteattr(XHTML)}>"]
    for element in body.elements:
        lines += [INDENT + line for line in element_xml(element)]
    lines.append(f"</{body.language}>")
    return "\n".join(lines) + "\n"


def element_xml(element: Element) -> list[str]:
    tag = TAG_OF[element.kind]
    attrs = {"localId": str(element.id)}
    if element.order:
        attrs["executionOrderId"] = str(element.order)
    attrs["height"] = _num(element.size.y)
    attrs["width"] = _num(element.size.x)
    inside = [_point("position", element.at)]
    kind = element.kind
    if kind in ("IN", "OUT", "INOUT"):
        _simple_flags(element, attrs)
        inside += _points(element)
        inside.append(f"<expression>{escape(element.text)}</expression>")
    elif kind == "BLOCK":
        attrs["typeName"] = element.text
        if element.instance:
            attrs["instanceName"] = element.instance
        inside += _block_pins(element)
    elif kind in ("CONNECTOR", "CONTINUATION"):
        attrs["name"] = element.text
        inside += _points(element)
    elif kind in ("JUMP", "LABEL"):
        attrs["label"] = element.text
        inside += _points(element)
    elif kind == "RETURN":
        inside += _points(element)
    elif kind == "COMMENT":
        inside.append(f"<content><xhtml:p>{escape(element.text)}</xhtml:p></content>")
    elif kind == "LEFT_RAIL":
        inside += [line for pin in element.outputs for line in _out(pin, rail=True)]
    elif kind == "RIGHT_RAIL":
        inside += [line for pin in element.inputs for line in _in(pin)]
    else:  # CONTACT, COIL
        _ld_flags(element, attrs)
        inside += _points(element)
        inside.append(f"<variable>{escape(element.text)}</variable>")
    head = f"<{tag}" + "".join(f" {k}={quoteattr(v)}" for k, v in attrs.items()) + ">"
    return [head, *(INDENT + line for line in inside), f"</{tag}>"]


def _simple_flags(element: Element, attrs: dict[str, str]) -> None:
    """negated, edge and storage of an in-, out- or in-out variable (In/Out for the last)."""
    storage = element.modifiers[0].lower() if element.modifiers else "none"
    if element.kind == "INOUT":
        _pin_flags(element.inputs[0], attrs, "In")
        attrs["storageIn"] = storage
        _pin_flags(element.outputs[0], attrs, "Out")
        return
    pin = element.outputs[0] if element.kind == "IN" else element.inputs[0]
    _pin_flags(pin, attrs, "")
    if element.kind == "OUT":
        attrs["storage"] = storage


def _pin_flags(pin: Pin, attrs: dict[str, str], suffix: str) -> None:
    attrs[f"negated{suffix}"] = "true" if pin.flag == "NOT" else "false"
    attrs[f"edge{suffix}"] = EDGE_OF.get(pin.flag, "none")


def _ld_flags(element: Element, attrs: dict[str, str]) -> None:
    modifiers = set(element.modifiers)
    attrs["negated"] = "true" if "NEGATED" in modifiers else "false"
    attrs["edge"] = (
        "rising" if "RISING" in modifiers else "falling" if "FALLING" in modifiers else "none"
    )
    if element.kind == "COIL":
        attrs["storage"] = (
            "set" if "SET" in modifiers else "reset" if "RESET" in modifiers else "none"
        )


def _points(element: Element) -> list[str]:
    """The connection points of an element with one unnamed input and/or output."""
    lines = [line for pin in element.inputs for line in _in(pin)]
    return lines + [line for pin in element.outputs for line in _out(pin)]


def _block_pins(block: Element) -> list[str]:
    """inputVariables, inOutVariables, outputVariables: a pin of the same name among the
    inputs and the outputs is an in-out variable."""
    outputs = {pin.name.upper(): pin for pin in block.outputs}
    in_out = {pin.name.upper() for pin in block.inputs} & set(outputs)
    groups = (
        ("inputVariables", [p for p in block.inputs if p.name.upper() not in in_out]),
        ("inOutVariables", [p for p in block.inputs if p.name.upper() in in_out]),
        ("outputVariables", [p for p in block.outputs if p.name.upper() not in in_out]),
    )
    lines = []
    for group, pins in groups:
        if not pins:
            lines.append(f"<{group}/>")
            continue
        lines.append(f"<{group}>")
        for pin in pins:
            attrs = {"formalParameter": pin.name}
            _pin_flags(pin, attrs, "")
            head = "<variable" + "".join(f" {k}={quoteattr(v)}" for k, v in attrs.items()) + ">"
            inside = _in(pin) if group != "outputVariables" else []
            if group != "inputVariables":
                inside += _out(outputs[pin.name.upper()])
            lines += [
                INDENT + head,
                *(INDENT * 2 + line for line in inside),
                INDENT + "</variable>",
            ]
        lines.append(f"</{group}>")
    return lines


def _in(pin: Pin) -> list[str]:
    inside = [_point("relPosition", pin.at)] if pin.at is not None else []
    for wire in pin.wires:
        attrs = f" refLocalId={quoteattr(str(wire.element))}"
        if wire.pin:
            attrs += f" formalParameter={quoteattr(wire.pin)}"
        if not wire.points:
            inside.append(f"<connection{attrs}/>")
            continue
        inside.append(f"<connection{attrs}>")
        inside += [INDENT + _point("position", point) for point in wire.points]
        inside.append("</connection>")
    return ["<connectionPointIn>", *(INDENT + line for line in inside), "</connectionPointIn>"]


def _out(pin: Pin, rail: bool = False) -> list[str]:
    head = '<connectionPointOut formalParameter="">' if rail else "<connectionPointOut>"
    if pin.at is None:
        return [head.replace(">", "/>")]
    return [head, INDENT + _point("relPosition", pin.at), "</connectionPointOut>"]


def _point(tag: str, point: Point) -> str:
    return f'<{tag} x="{_num(point.x)}" y="{_num(point.y)}"/>'


def _num(value: float) -> str:
    return str(int(value)) if value == int(value) else repr(value)
