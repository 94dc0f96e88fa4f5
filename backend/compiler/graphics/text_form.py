"""The text form of a graphical body: one element a line, inside a POU of an ST file.

```
FBD
  2: IN LocalVar0 {at 430 70 size 90 30}
  1: BLOCK ADD (IN1 := 2, IN2 := NOT 3) -> (OUT) {at 560 60 size 70 60 order 1}
  4: OUT LocalVar2 := 1.OUT
END_FBD
```

A line is `ID: KIND[MODIFIERS] text inputs -> (outputs) {layout}`: the inputs are
`:= wires` for an element's one unnamed pin or `(NAME := wires, NAME, wires, ...)`; wires
are `[NOT|R_EDGE|F_EDGE] ID[.PIN] | ID[.PIN] ...`. The layout (a pragma, as ST writes
them) holds what only the drawing needs: `at X Y`, `size W H`, `order N`, `in I X Y` and
`out I X Y` (the place of the I-th input or output pin), `wire I K X Y X Y ...` (the points
of the K-th wire into input pin I). docs/project-format.md describes the form; this module
reads and writes it, and `write_body(read_body(t))` gives `t` back for what it writes.
"""

from __future__ import annotations

import re
from dataclasses import replace

from backend.compiler.codes import Code
from backend.compiler.diagnostics import Diagnostic
from backend.compiler.graphics.model import (
    KINDS,
    MODIFIERS,
    PIN_FLAGS,
    Element,
    GraphicBody,
    Pin,
    Point,
    Wire,
)
from backend.compiler.source import Pos

# kinds with one unnamed output pin unless the line lists others
_ONE_OUTPUT = ("IN", "INOUT", "CONTINUATION", "CONTACT", "COIL", "LEFT_RAIL")
# kinds whose text is followed by `:= wires` into one unnamed input pin
_ONE_INPUT = ("OUT", "INOUT", "CONNECTOR", "JUMP", "RETURN", "CONTACT", "COIL")

_HEAD = re.compile(r"\s*(\d{1,18})\s*:\s*([A-Za-z_]+)\s*(?:\[([A-Za-z_,\s]*)\])?")
_WIRE = re.compile(r"(\d{1,18})(?:\.([A-Za-z_][A-Za-z0-9_]*))?$")
_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*$")
_LAYOUT_WORDS = {"at": 2, "size": 2, "order": 1, "in": 3, "out": 3}
# the largest place, size or order a layout takes: a drawing is drawn and printed from them,
# and infinities or huge numbers would make that endless
MAX_COORDINATE = 1_000_000


class _LineError(Exception):
    def __init__(self, col: int, message: str) -> None:
        super().__init__(message)
        self.col = col
        self.message = message


def read_body(text: str, file: str, line: int, col: int) -> tuple[GraphicBody, list[Diagnostic]]:
    """The body written in `text` (from its `FBD`/`LD` keyword to its `END_FBD`/`END_LD`),
    which starts at `line`:`col` of `file`; with a diagnostic for each line it cannot read
    (that line's element is left out)."""
    lines = text.split("\n")
    language = lines[0].strip().upper()
    elements: list[Element] = []
    diagnostics: list[Diagnostic] = []
    seen: dict[int, int] = {}
    for index, raw in enumerate(lines[1:-1], start=1):
        content = _without_comment(raw.rstrip("\r"))
        if not content.strip():
            continue
        at = line + index
        try:
            element = _element(content)
        except _LineError as exc:
            diagnostics.append(
                Diagnostic.at(Pos(file, at, exc.col + 1), Code.GRAPHIC_SYNTAX, exc.message)
            )
            continue
        if element.id in seen:
            message = f"element {element.id} is written twice (first on line {seen[element.id]})"
            diagnostics.append(
                Diagnostic.at(Pos(file, at, _indent(raw) + 1), Code.GRAPHIC_SYNTAX, message)
            )
            continue
        seen[element.id] = at
        elements.append(replace(element, line=at, col=_indent(raw) + 1))
    return GraphicBody(language, tuple(elements), line, col), diagnostics


def write_body(body: GraphicBody, indent: str = "  ") -> str:
    """The body in its text form, from its keyword to its end keyword (no newline after)."""
    lines = [body.language]
    lines += [indent + element_line(e) for e in body.elements]
    lines.append(f"END_{body.language}")
    return "\n".join(lines)


def element_line(element: Element) -> str:
    """One element as its line of the text form."""
    head = f"{element.id}: {element.kind}"
    if element.modifiers:
        head += f"[{', '.join(element.modifiers)}]"
    parts = [head]
    if element.kind == "COMMENT":
        parts.append(_quoted(element.text))
    else:
        if element.text:
            parts.append(element.text)
        if element.instance:
            parts.append(element.instance)
    inputs = _inputs_text(element)
    if inputs:
        parts.append(inputs)
    outputs = _outputs_text(element)
    if outputs:
        parts.append(outputs)
    layout = _layout_text(element)
    if layout:
        parts.append(layout)
    return " ".join(parts)


# ---- reading ------------------------------------------------------------------------------


def _element(content: str) -> Element:
    head = _HEAD.match(content)
    if head is None:
        raise _LineError(_indent(content), "expected an element: `ID: KIND ...`")
    element_id, kind = int(head.group(1)), head.group(2).upper()
    if kind not in KINDS:
        raise _LineError(head.start(2), f"unknown element kind '{head.group(2)}'")
    modifiers = _modifiers(kind, head.group(3), head.start(3) if head.group(3) else 0)
    rest_start = head.end()
    rest = content[rest_start:]
    layout: dict[str, list[list[float]]] = {}
    brace = _top_level(rest, "{")
    if brace >= 0:
        close = rest.rfind("}")
        if close < brace or rest[close + 1 :].strip():
            raise _LineError(rest_start + brace, "a layout `{...}` must close the line")
        layout = _layout(rest[brace + 1 : close], rest_start + brace + 1)
        rest = rest[:brace]
    outputs_text = ""
    arrow = _top_level(rest, "->")
    if arrow >= 0:
        outputs_text = rest[arrow + 2 :].strip()
        rest = rest[:arrow]
    element = Element(element_id, kind, modifiers=modifiers)
    element = _core(element, rest, rest_start)
    outputs = _outputs(outputs_text, rest_start + arrow + 2) if arrow >= 0 else ()
    if not outputs and kind in _ONE_OUTPUT:
        outputs = (Pin(),)
    if arrow < 0 and kind == "BLOCK":  # `-> ()`: a block drawn without outputs
        raise _LineError(rest_start, "a BLOCK lists its outputs: `-> (OUT)`")
    return _placed(replace(element, outputs=outputs), layout, rest_start)


def _modifiers(kind: str, text: str | None, col: int) -> tuple[str, ...]:
    if text is None:
        return ()
    words = tuple(w.strip().upper() for w in text.split(",") if w.strip())
    allowed = MODIFIERS.get(kind, ())
    for word in words:
        if word not in allowed:
            takes = ", ".join(allowed) if allowed else "none"
            raise _LineError(col, f"{kind} takes no modifier {word} (it takes: {takes})")
    return words


def _core(element: Element, text: str, col: int) -> Element:
    """The element's text and inputs, from what stands between its kind and its outputs."""
    kind = element.kind
    if kind == "COMMENT":
        return replace(element, text=_unquoted(text.strip(), col))
    if kind == "BLOCK":
        paren = _top_level(text, "(")
        names = (text[:paren] if paren >= 0 else text).split()
        if not 1 <= len(names) <= 2 or not all(_NAME.match(n) for n in names):
            raise _LineError(col, "a BLOCK names its type and, for an FB, its instance")
        inputs = _pin_list(text[paren:], col + paren) if paren >= 0 else ()
        instance = names[1] if len(names) == 2 else ""
        return replace(element, text=names[0], instance=instance, inputs=inputs)
    if kind == "RIGHT_RAIL":
        stripped = text.strip()
        inputs = _pin_list(stripped, col) if stripped else ()
        return replace(element, inputs=inputs)
    assign = _top_level(text, ":=")
    if kind in _ONE_INPUT and assign >= 0:
        pin = _pin_value("", text[assign + 2 :], col + assign + 2)
        return replace(element, text=text[:assign].strip(), inputs=(pin,))
    if kind in _ONE_INPUT:
        # written without `:=`: its pin is there, unconnected
        return replace(element, text=text.strip(), inputs=(Pin(),))
    if assign >= 0:
        raise _LineError(col + assign, f"{kind} takes no input")
    return replace(element, text=text.strip())


def _pin_list(text: str, col: int) -> tuple[Pin, ...]:
    stripped = text.strip()
    if not (stripped.startswith("(") and stripped.endswith(")")):
        raise _LineError(col, "expected the pins in parentheses: `(NAME := 1, ...)`")
    inner_col = col + text.index("(") + 1
    inner = stripped[1:-1]
    pins: list[Pin] = []
    for offset, entry in _split_top(inner, ","):
        entry_col = inner_col + offset
        if not entry.strip():
            continue
        assign = _top_level(entry, ":=")
        if assign >= 0:
            name = entry[:assign].strip()
            if not _NAME.match(name):
                raise _LineError(entry_col, f"expected a pin name before ':=', not '{name}'")
            pins.append(_pin_value(name, entry[assign + 2 :], entry_col + assign + 2))
        elif entry.strip() == "_":
            pins.append(Pin())
        elif _NAME.match(entry.strip()) and entry.strip().upper() not in PIN_FLAGS:
            pins.append(Pin(entry.strip()))
        else:
            pins.append(_pin_value("", entry, entry_col))
    return tuple(pins)


def _pin_value(name: str, text: str, col: int) -> Pin:
    words = text.split()
    flag = ""
    if words and words[0].upper() in PIN_FLAGS:
        flag = words[0].upper()
        text = text[text.upper().index(flag) + len(flag) :]
    wires: list[Wire] = []
    for offset, part in _split_top(text, "|"):
        match = _WIRE.match(part.strip())
        if match is None:
            if not part.strip() and not wires and offset == 0 and "|" not in text:
                break  # `NAME :=` with nothing after it: unconnected
            at = col + offset + _indent(part)
            raise _LineError(at, f"expected a wire `ID` or `ID.PIN`, not '{part.strip()}'")
        wires.append(Wire(int(match.group(1)), match.group(2) or ""))
    return Pin(name, tuple(wires), flag)


def _outputs(text: str, col: int) -> tuple[Pin, ...]:
    stripped = text.strip()
    if not (stripped.startswith("(") and stripped.endswith(")")):
        raise _LineError(col, "expected the outputs in parentheses: `-> (OUT, Q)`")
    if not stripped[1:-1].strip():
        return ()
    pins: list[Pin] = []
    for offset, entry in _split_top(stripped[1:-1], ","):
        words = entry.split()
        negated = bool(words) and words[0].upper() == "NOT"
        names = words[1:] if negated else words
        if len(names) != 1 or not _NAME.match(names[0]):
            raise _LineError(col + offset, f"expected an output pin name, not '{entry.strip()}'")
        name = "" if names[0] == "_" else names[0]
        pins.append(Pin(name, flag="NOT" if negated else ""))
    return tuple(pins)


def _layout(text: str, col: int) -> dict[str, list[list[float]]]:
    """The layout's words, each with its lists of numbers (`in` and `out` and `wire` may
    come many times)."""
    result: dict[str, list[list[float]]] = {}
    word = ""
    for token in text.split():
        lowered = token.lower()
        if lowered in _LAYOUT_WORDS or lowered == "wire":
            word = lowered
            result.setdefault(word, []).append([])
            continue
        if not word:
            raise _LineError(col, f"unknown layout word '{token}'")
        try:
            number = float(token)
        except ValueError:
            raise _LineError(col, f"expected a number after '{word}', not '{token}'") from None
        if not abs(number) <= MAX_COORDINATE:  # NaN too
            message = f"a place or size is a number within ±{MAX_COORDINATE:,}, not '{token}'"
            raise _LineError(col, message)
        result[word][-1].append(number)
    for name, groups in result.items():
        size = _LAYOUT_WORDS.get(name)
        for numbers in groups:
            wrong = (size is not None and len(numbers) != size) or (
                size is None and (len(numbers) < 2 or len(numbers) % 2)
            )
            if wrong:
                raise _LineError(col, f"wrong count of numbers after '{name}'")
    return result


def _placed(element: Element, layout: dict[str, list[list[float]]], col: int) -> Element:
    inputs = list(element.inputs)
    outputs = list(element.outputs)
    for numbers in layout.get("in", []):
        index = int(numbers[0])
        if not 0 <= index < len(inputs):
            raise _LineError(col, f"layout names input pin {index}; the element has {len(inputs)}")
        inputs[index] = replace(inputs[index], at=Point(numbers[1], numbers[2]))
    for numbers in layout.get("out", []):
        index = int(numbers[0])
        if not 0 <= index < len(outputs):
            raise _LineError(
                col, f"layout names output pin {index}; the element has {len(outputs)}"
            )
        outputs[index] = replace(outputs[index], at=Point(numbers[1], numbers[2]))
    for numbers in layout.get("wire", []):
        pin, wire = int(numbers[0]), int(numbers[1])
        if not 0 <= pin < len(inputs) or not 0 <= wire < len(inputs[pin].wires):
            raise _LineError(
                col, f"layout names wire {wire} of input pin {pin}, which is not there"
            )
        points = tuple(Point(x, y) for x, y in zip(numbers[2::2], numbers[3::2], strict=True))
        wires = list(inputs[pin].wires)
        wires[wire] = replace(wires[wire], points=points)
        inputs[pin] = replace(inputs[pin], wires=tuple(wires))
    at = layout.get("at", [[0, 0]])[-1]
    size = layout.get("size", [[0, 0]])[-1]
    order = int(layout.get("order", [[0]])[-1][0])
    return replace(
        element,
        inputs=tuple(inputs),
        outputs=tuple(outputs),
        at=Point(at[0], at[1]),
        size=Point(size[0], size[1]),
        order=order,
    )


# ---- writing ------------------------------------------------------------------------------


def _inputs_text(element: Element) -> str:
    if not element.inputs:
        return ""
    if element.kind in _ONE_INPUT and len(element.inputs) == 1 and not element.inputs[0].name:
        pin = element.inputs[0]
        return f":= {_wires_text(pin)}" if pin.wires else ""
    entries = []
    for pin in element.inputs:
        wires = _wires_text(pin)
        if pin.name and wires:
            entries.append(f"{pin.name} := {wires}")
        else:
            entries.append(pin.name or wires or "_")  # `_`: an unnamed pin, unconnected
    return f"({', '.join(entries)})"


def _wires_text(pin: Pin) -> str:
    wires = " | ".join(f"{w.element}.{w.pin}" if w.pin else str(w.element) for w in pin.wires)
    return f"{pin.flag} {wires}" if pin.flag and wires else wires


def _outputs_text(element: Element) -> str:
    outputs = element.outputs
    if element.kind in _ONE_OUTPUT and len(outputs) == 1 and replace(outputs[0], at=None) == Pin():
        return ""
    if not outputs:
        return "-> ()" if element.kind == "BLOCK" else ""
    names = [f"NOT {p.name or '_'}" if p.flag == "NOT" else p.name or "_" for p in outputs]
    return f"-> ({', '.join(names)})"


def _layout_text(element: Element) -> str:
    words: list[str] = []
    if element.at != Point(0, 0) or element.size != Point(0, 0):
        words += ["at", _num(element.at.x), _num(element.at.y)]
        words += ["size", _num(element.size.x), _num(element.size.y)]
    if element.order:
        words += ["order", str(element.order)]
    for word, pins in (("in", element.inputs), ("out", element.outputs)):
        for index, pin in enumerate(pins):
            if pin.at is not None:
                words += [word, str(index), _num(pin.at.x), _num(pin.at.y)]
    for index, pin in enumerate(element.inputs):
        for number, wire in enumerate(pin.wires):
            if wire.points:
                words += ["wire", str(index), str(number)]
                words += [_num(v) for p in wire.points for v in (p.x, p.y)]
    return "{" + " ".join(words) + "}" if words else ""


def _num(value: float) -> str:
    return str(int(value)) if value == int(value) else repr(value)


def _quoted(text: str) -> str:
    escaped = text.replace("$", "$$").replace("'", "$'").replace("\n", "$N").replace("\r", "$R")
    return f"'{escaped}'"


_ESCAPES = {"$$": "$", "$'": "'", "$N": "\n", "$R": "\r", "$n": "\n", "$r": "\r"}


def _unquoted(text: str, col: int) -> str:
    if len(text) < 2 or not (text.startswith("'") and text.endswith("'")):
        raise _LineError(col, "a COMMENT's words are quoted: `'text'`")
    return re.sub(r"\$.", lambda m: _ESCAPES.get(m.group(0), m.group(0)), text[1:-1])


# ---- scanning -----------------------------------------------------------------------------


def _top_level(text: str, token: str) -> int:
    """The first place of `token` outside strings and parentheses (a `(` counts at depth 0)."""
    depth = 0
    quote = ""
    i = 0
    while i < len(text):
        char = text[i]
        if quote:
            if char == "$":
                i += 2
                continue
            if char == quote:
                quote = ""
        elif char in "'\"":
            quote = char
        elif depth == 0 and text.startswith(token, i):
            return i
        elif char in "([":
            depth += 1
        elif char in ")]":
            depth -= 1
        i += 1
    return -1


def _split_top(text: str, separator: str) -> list[tuple[int, str]]:
    """`text` cut at each `separator` outside strings and parentheses, with the offsets."""
    parts: list[tuple[int, str]] = []
    start = 0
    while True:
        found = _top_level(text[start:], separator)
        if found < 0:
            parts.append((start, text[start:]))
            return parts
        parts.append((start, text[start : start + found]))
        start += found + len(separator)


def _without_comment(line: str) -> str:
    """The line without a `//` comment or a whole-line `(* *)` comment."""
    stripped = line.strip()
    if stripped.startswith("(*") and stripped.endswith("*)"):
        return ""
    cut = _top_level(line, "//")
    return line if cut < 0 else line[:cut]


def _indent(text: str) -> int:
    return len(text) - len(text.lstrip())
