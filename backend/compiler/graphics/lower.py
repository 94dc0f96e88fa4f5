"""A drawing lowered to Structured Text: the statements that do what its elements do, in
their execution order, each on a line of its own that says which element it comes from;
and the hidden variables that hold what the drawing keeps between its elements.

What the lowering guarantees (the live views and docs/language.md rely on it):
- an output pin P of a FUNCTION block with id N and type T is the variable
  `_TMP_<T>N_<P>` when its type can be told from the drawing (the declared type of a
  variable wired into it, a conversion's target, BOOL for a comparison, a FUNCTION's type);
  else the call is written where its output is used (and the value is not observable);
- an FB instance is called once, and its outputs are read as `instance.P`;
- a block with EN wired runs only when EN is TRUE; its ENO is `_TMP_<T>N_ENO` (FALSE when
  it did not run);
- the power flow out of an LD contact or coil with id N is the BOOL `_TMP_LD<N>`;
  a rising or falling contact or coil keeps the last value it saw in `_TMP_LD<N>_M`;
- an edge on an input pin (R_EDGE, F_EDGE) is sensed into `_TMP_E<N>_<P>` (`_TMP_E<N>` for
  an element's one pin), with its last value in `..._M`;
- jumps run the drawing as segments from label to label (`_TMP_JUMP`);
- in a drawn ACTION the names start `_TMP_<ACTION>_` (`_TMP_FILL_LD5`).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field, replace

from backend.compiler.codes import Code
from backend.compiler.diagnostics import Diagnostic
from backend.compiler.graphics.model import LD_KINDS, Element, GraphicBody, Pin, Wire
from backend.compiler.graphics.order import evaluation_order
from backend.compiler.source import Pos
from backend.compiler.types import ELEMENTARY

# standard FUNCTIONs whose result has the type of their first typed input
_SAME_TYPE = frozenset((
    "ADD", "SUB", "MUL", "DIV", "MOD", "MAX", "MIN", "LIMIT", "SEL", "MUX", "MOVE", "ABS", "NEG",
    "AND", "OR", "XOR", "NOT", "SHL", "SHR", "ROL", "ROR", "EXPT", "SQRT", "LN", "LOG", "EXP",
    "SIN", "COS", "TAN", "ASIN", "ACOS", "ATAN",
))  # fmt: skip
_COMPARISONS = frozenset(("GT", "GE", "EQ", "LE", "LT", "NE"))
_CONVERSION = re.compile(r"^(?:[A-Z]+_)?TO_([A-Z]+)$")
_ELEMENTARY = frozenset(ELEMENTARY)
_TYPED_LITERAL = re.compile(r"^([A-Za-z_]+)#")
_IDENTIFIER = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")
_ENABLE = "EN"
# how deep values are written into each other (continuations, FUNCTIONs without a type):
# a bound on the text a crafted drawing can make the lowering write
MAX_INLINE_DEPTH = 32
MAX_INLINE_TEXT = 16_384
_ENABLE_OUT = "ENO"


@dataclass(frozen=True)
class Context:
    """What the POU around the drawing declares: its variables with their types' text
    (upper-case names), and the result types of the FUNCTIONs its file declares."""

    variables: dict[str, str]
    functions: dict[str, str] = field(default_factory=dict)


@dataclass(frozen=True)
class Line:
    """One line of the lowered body: ST text and the element it comes from (None: the
    body's own framing, such as the jump dispatcher)."""

    text: str
    element: Element | None


@dataclass
class Lowered:
    lines: list[Line] = field(default_factory=list)
    temporaries: dict[str, str] = field(default_factory=dict)  # name -> ST type
    diagnostics: list[Diagnostic] = field(default_factory=list)


def value_variable(
    body: GraphicBody, element_id: int, pin: str = "", action: str = ""
) -> str | None:
    """The variable of the POU instance that holds the value an element puts out on `pin`
    (see the module's guarantees; `action`: the action the body is of); None where the
    value is the element's own expression (read `Element.text`), a constant (a left rail)
    or nowhere."""
    element = body.element(element_id)
    tmp = _hidden_prefix(action)
    if element is None:
        return None
    if element.kind in ("CONTACT", "COIL"):
        return f"{tmp}LD{element.id}"
    if element.kind != "BLOCK":
        return None
    if pin.upper() == _ENABLE_OUT:
        return _temporary(tmp, element, _ENABLE_OUT)
    if element.instance:
        return f"{element.instance}.{pin}"
    return _temporary(tmp, element, pin or _result_pin(element))


def _hidden_prefix(action: str) -> str:
    """How the names of a body's hidden variables start: an action's have its name, so that
    they differ from the POU body's and the other actions'."""
    return f"_TMP_{action.upper()}_" if action else "_TMP_"


def temporaries_block(lowered: Lowered) -> str:
    """The declarations of the hidden variables, as one ST `VAR` block on one line."""
    names = " ".join(f"{n} : {t};" for n, t in lowered.temporaries.items())
    return f"VAR {names} END_VAR"


def lower(body: GraphicBody, file: str, context: Context, action: str = "") -> Lowered:
    """The statements of `body` (of the POU, or of its action `action`), in execution
    order, with its hidden variables."""
    return _Lowering(body, file, context, _hidden_prefix(action)).run()


# kinds that act on what is wired into them, and without a wire do nothing
_ACTS_ON_ITS_WIRE = ("OUT", "INOUT", "JUMP", "RETURN", "CONNECTOR", "COIL")


_EDGES = ("R_EDGE", "F_EDGE")


def _edge(tmp: str, element: Element, pin: Pin) -> str:
    """The variable holding the sensed edge of an input pin."""
    return f"{tmp}E{element.id}_{pin.name}".upper() if pin.name else f"{tmp}E{element.id}"


def _place(element: Element) -> tuple[int, float, float, int]:
    """Where an element stands on the sheet, for what comes before a label: its execution
    order, its height, its left, then its line in the file."""
    return (element.order, element.at.y, element.at.x, element.line)


def _wired(element: Element) -> bool:
    return bool(element.inputs and element.inputs[0].wires)


def _temporary(tmp: str, element: Element, pin: str) -> str:
    return f"{tmp}{element.text}{element.id}_{pin}".upper()


def _result_pin(element: Element) -> str:
    outputs = [p.name for p in element.outputs if p.name.upper() != _ENABLE_OUT]
    return outputs[0] if outputs else "OUT"


class _Lowering:
    """One lowering: the expressions and types found so far (they refer to each other)."""

    def __init__(self, body: GraphicBody, file: str, context: Context, tmp: str) -> None:
        self.body = body
        self.tmp = tmp  # how the hidden variables' names start
        self.file = file
        self.context = context
        self.by_id = {e.id: e for e in body.elements}
        self.connectors = {
            e.text.upper(): e for e in body.elements if e.kind == "CONNECTOR" and e.text
        }
        self.out = Lowered()
        self.types: dict[int, str | None] = {}  # FUNCTION blocks' result types
        self.inline: dict[int, str] = {}  # calls of untyped FUNCTIONs, as written
        self.expanding: set[int] = set()  # those being written: one met again is a loop
        self.prefix = ""  # edge sensing to put before the next statement
        self.feedback: set[tuple[int, int]] = set()
        self.evaluated: set[int] = set()

    # ---- the whole body ----------------------------------------------------------------

    def run(self) -> Lowered:
        self._check_elements()
        if any(d.severity == "error" for d in self.out.diagnostics):
            return self.out
        self._type_functions()
        labels = sorted((e for e in self.body.elements if e.kind == "LABEL"), key=_place)
        segments = self._segments(labels)
        jumps = any(e.kind == "JUMP" for e in self.body.elements)
        if not jumps:
            for segment in segments:
                self._segment_lines(segment, None, -1)
            return self.out
        self.out.temporaries[f"{self.tmp}JUMP"] = "INT"
        self.out.lines.append(Line(f"{self.tmp}JUMP := 0;", None))
        jump = f"{self.tmp}JUMP"
        self.out.lines.append(Line(f"WHILE {jump} >= 0 DO CASE {jump} OF", None))
        label_index = {e.text.upper(): i + 1 for i, e in enumerate(labels)}
        for index, segment in enumerate(segments):
            following = index + 1 if index + 1 < len(segments) else -1
            self.out.lines.append(Line(f"{index}:", None))
            self._segment_lines(segment, label_index, following)
        self.out.lines.append(Line(f"ELSE {jump} := -1; END_CASE; END_WHILE;", None))
        return self.out

    def _segments(self, labels: list[Element]) -> list[list[Element]]:
        """The elements from each label to the next, by their places (the first segment:
        those before every label); a drawing without labels is one segment."""
        segments: list[list[Element]] = [[] for _ in range(len(labels) + 1)]
        for element in self.body.elements:
            if element.kind == "LABEL":
                continue
            index = sum(1 for label in labels if _place(label) < _place(element))
            segments[index].append(element)
        return segments

    def _segment_lines(
        self, elements: list[Element], labels: dict[str, int] | None, following: int
    ) -> None:
        nodes = [e for e in elements if self._has_statement(e)]
        ordered, feedback = evaluation_order(nodes, self._depends_on)
        self.feedback |= feedback
        closing = 0
        for element in ordered:
            if element.kind == "JUMP" and labels is not None:
                target = labels.get(element.text.upper())
                if target is None:
                    self._error(element, Code.GRAPHIC_LABEL, f"no label '{element.text}'")
                    continue
                condition = self._pin_value(element, element.inputs[0])
                self._emit(element, f"IF {condition} THEN {self.tmp}JUMP := {target}; ELSE")
                closing += 1
                continue
            self._element_lines(element)
        if labels is not None:
            ends = " END_IF;" * closing
            self.out.lines.append(Line(f"{self.tmp}JUMP := {following};{ends}", None))

    def _has_statement(self, element: Element) -> bool:
        if element.kind in _ACTS_ON_ITS_WIRE and not _wired(element):
            return False  # left out, with a warning (W0901)
        if element.kind in ("OUT", "INOUT", "JUMP", "RETURN", "CONTACT", "COIL"):
            return True
        if element.kind != "BLOCK":
            return False
        # a FUNCTION whose value can be kept is evaluated where the order says; one whose
        # type is unknown is written into the expressions that use it
        return bool(element.instance) or self._result_type(element) is not None

    def _depends_on(self, element: Element) -> set[int]:
        """The elements with a statement that `element` takes a value from."""
        found: set[int] = set()
        seen: set[int] = set()
        stack = [w.element for p in element.inputs for w in p.wires]
        while stack:
            source_id = stack.pop()
            if source_id in seen:
                continue
            seen.add(source_id)
            source = self.by_id.get(source_id)
            if source is None:
                continue
            if self._has_statement(source):
                found.add(source_id)
            elif source.kind == "CONTINUATION":
                connector = self.connectors.get(source.text.upper())
                if connector is not None:
                    stack += [w.element for p in connector.inputs for w in p.wires]
            else:
                stack += [w.element for p in source.inputs for w in p.wires]
        return found

    # ---- one element -------------------------------------------------------------------

    def _element_lines(self, element: Element) -> None:
        kind = element.kind
        self._edges(element)
        if kind in ("OUT", "INOUT"):
            value = self._pin_value(element, element.inputs[0])
            self._store(element, element.text, value, self._gate(element.inputs[0]))
        elif kind == "RETURN":
            self._emit(
                element, f"IF {self._pin_value(element, element.inputs[0])} THEN RETURN; END_IF;"
            )
        elif kind == "CONTACT":
            self._contact(element)
        elif kind == "COIL":
            self._coil(element)
        elif kind == "BLOCK":
            self._block(element)
        self.evaluated.add(element.id)

    def _store(self, element: Element, target: str, value: str, gate: str | None) -> None:
        if "SET" in element.modifiers:
            text = f"IF {value} THEN {target} := TRUE; END_IF;"
        elif "RESET" in element.modifiers:
            text = f"IF {value} THEN {target} := FALSE; END_IF;"
        else:
            text = f"{target} := {value};"
        self._emit(element, text if gate is None else f"IF {gate} THEN {text} END_IF;")

    def _gate(self, pin: Pin) -> str | None:
        """The ENO of the block a variable's one wire comes from, when that block has EN
        wired: the variable is written only in a cycle the block ran (as Beremiz does)."""
        if len(pin.wires) != 1:
            return None
        source = self.by_id[pin.wires[0].element]
        enable = source.input(_ENABLE) if source.kind == "BLOCK" else None
        if enable is None or not enable.wires or pin.wires[0].pin.upper() == _ENABLE_OUT:
            return None
        return _temporary(self.tmp, source, _ENABLE_OUT)

    def _contact(self, element: Element) -> None:
        power = self._pin_value(element, element.inputs[0]) if element.inputs else "TRUE"
        flow = f"{self.tmp}LD{element.id}"
        self._temporary(flow, "BOOL")
        variable = element.text
        if "NEGATED" in element.modifiers:
            self._emit(element, f"{flow} := {power} AND NOT {variable};")
        elif "RISING" in element.modifiers or "FALLING" in element.modifiers:
            memory = self._temporary(f"{flow}_M", "BOOL")
            edge = (
                f"{variable} AND NOT {memory}"
                if "RISING" in element.modifiers
                else f"NOT {variable} AND {memory}"
            )
            self._emit(element, f"{flow} := {power} AND ({edge}); {memory} := {variable};")
        else:
            self._emit(element, f"{flow} := {power} AND {variable};")

    def _coil(self, element: Element) -> None:
        power = self._pin_value(element, element.inputs[0]) if element.inputs else "FALSE"
        flow = self._temporary(f"{self.tmp}LD{element.id}", "BOOL")
        variable = element.text
        modifiers = element.modifiers
        text = f"{flow} := {power};"
        if "NEGATED" in modifiers:
            text += f" {variable} := NOT {flow};"
        elif "SET" in modifiers:
            text += f" IF {flow} THEN {variable} := TRUE; END_IF;"
        elif "RESET" in modifiers:
            text += f" IF {flow} THEN {variable} := FALSE; END_IF;"
        elif "RISING" in modifiers or "FALLING" in modifiers:
            memory = self._temporary(f"{flow}_M", "BOOL")
            edge = (
                f"{flow} AND NOT {memory}" if "RISING" in modifiers else f"NOT {flow} AND {memory}"
            )
            text += f" {variable} := {edge}; {memory} := {flow};"
        else:
            text += f" {variable} := {flow};"
        self._emit(element, text)

    def _block(self, element: Element) -> None:
        arguments = self._arguments(element)
        enable = element.input(_ENABLE)
        enabled = enable is not None and enable.wires
        if element.instance:
            call = f"{element.instance}({', '.join(arguments)});"
        else:
            result = self._temporary(
                _temporary(self.tmp, element, _result_pin(element)),
                self._result_type(element) or "",
            )
            call = f"{result} := {element.text}({', '.join(arguments)});"
        if enabled and enable is not None:
            eno = self._temporary(_temporary(self.tmp, element, _ENABLE_OUT), "BOOL")
            condition = self._pin_value(element, enable)
            call = f"IF {condition} THEN {call} {eno} := TRUE; ELSE {eno} := FALSE; END_IF;"
        self._emit(element, call)

    def _arguments(self, element: Element) -> list[str]:
        arguments = []
        for pin in element.inputs:
            if pin.name.upper() in (_ENABLE, "") or not pin.wires:
                continue
            arguments.append(f"{pin.name} := {self._pin_value(element, pin)}")
        return arguments

    def _edges(self, element: Element) -> None:
        """The statements that sense the edges of an element's edge-triggered inputs, put
        before the next statement written (`_emit`)."""
        for pin in element.inputs:
            if pin.flag not in _EDGES or not pin.wires:
                continue
            value = self._pin_value(element, replace(pin, flag=""))
            edge = self._temporary(_edge(self.tmp, element, pin), "BOOL")
            memory = self._temporary(f"{edge}_M", "BOOL")
            sensed = (
                f"{value} AND NOT {memory}" if pin.flag == "R_EDGE" else f"NOT {value} AND {memory}"
            )
            self.prefix += f"{edge} := {sensed}; {memory} := {value}; "

    # ---- values ------------------------------------------------------------------------

    def _pin_value(self, consumer: Element, pin: Pin, depth: int = 0) -> str:
        if pin.flag in _EDGES and pin.wires:
            return _edge(self.tmp, consumer, pin)  # sensed before the statement (`_edges`)
        values = [self._wire_value(consumer, w, depth) for w in pin.wires]
        if not values:
            return "FALSE"
        value = values[0] if len(values) == 1 else "(" + " OR ".join(values) + ")"
        return f"NOT ({value})" if pin.flag == "NOT" else value

    def _wire_value(self, consumer: Element, wire: Wire, depth: int) -> str:
        source = self.by_id[wire.element]
        value = self._output_value(consumer, source, wire.pin, depth)
        pin = next((p for p in source.outputs if p.name.upper() == wire.pin.upper()), None)
        return f"NOT ({value})" if pin is not None and pin.flag == "NOT" else value

    def _output_value(self, consumer: Element, source: Element, pin: str, depth: int) -> str:
        kind = source.kind
        if kind in ("IN", "INOUT"):
            return source.text if _IDENTIFIER.match(source.text) else f"({source.text})"
        if kind == "LEFT_RAIL":
            return "TRUE"
        if kind in ("CONTACT", "COIL"):
            return f"{self.tmp}LD{source.id}"
        if kind == "BLOCK" and pin.upper() == _ENABLE_OUT:
            enable = source.input(_ENABLE)
            return _temporary(self.tmp, source, _ENABLE_OUT) if enable and enable.wires else "TRUE"
        if kind == "BLOCK" and source.instance:
            return f"{source.instance}.{pin}"
        if kind == "BLOCK" and self._result_type(source) is not None:
            return _temporary(self.tmp, source, pin or _result_pin(source))
        # a value written where it is used: a continuation's, or an untyped FUNCTION's
        if depth >= MAX_INLINE_DEPTH:
            message = (
                f"element {source.id} is reached through more than {MAX_INLINE_DEPTH} "
                "continuations or FUNCTIONs whose type the drawing cannot tell: a loop, or "
                "a chain to cut with a variable"
            )
            self._error(consumer, Code.EXPRESSION_DEPTH, message)
            return "FALSE"
        if kind == "CONTINUATION":
            connector = self.connectors[source.text.upper()]
            return self._pin_value(connector, connector.inputs[0], depth + 1)
        if (consumer.id, source.id) in self.feedback or source.id in self.expanding:
            self._error(consumer, Code.GRAPHIC_FEEDBACK, self._feedback_message(source))
            return "FALSE"
        if source.id not in self.inline:
            self.expanding.add(source.id)
            self._edges(source)
            arguments = [
                f"{p.name} := {self._pin_value(source, p, depth + 1)}"
                for p in source.inputs
                if p.name.upper() not in (_ENABLE, "") and p.wires
            ]
            self.expanding.discard(source.id)
            self.inline[source.id] = f"{source.text}({', '.join(arguments)})"
        call = self.inline[source.id]
        if len(call) > MAX_INLINE_TEXT:
            message = (
                f"the call of {source.text} (element {source.id}), written where its value is "
                f"used, is longer than {MAX_INLINE_TEXT:,} characters: cut the chain with a "
                "variable"
            )
            self._error(consumer, Code.EXPRESSION_DEPTH, message)
            return "FALSE"
        return call

    def _feedback_message(self, source: Element) -> str:
        return (
            f"the output of {source.text} (element {source.id}) feeds back into its own "
            "inputs: write it into a variable and read that variable back"
        )

    def _result_type(self, element: Element) -> str | None:
        """The type of a FUNCTION block's result, when the drawing tells it."""
        return self.types.get(element.id)

    def _type_functions(self) -> None:
        """The result types of the FUNCTION blocks, each found after those feeding it (in
        the order of the data flow, so no chain of blocks nests a call)."""
        blocks = [e for e in self.body.elements if e.kind == "BLOCK" and not e.instance]
        ordered, _ = evaluation_order(blocks, self._feeding_blocks)
        for block in ordered:
            self.types[block.id] = self._typed(block)

    def _feeding_blocks(self, element: Element) -> set[int]:
        found: set[int] = set()
        stack = [w for p in element.inputs for w in p.wires]
        seen: set[int] = set()
        while stack:
            wire = stack.pop()
            source = self.by_id.get(wire.element)
            if source is None or source.id in seen:
                continue
            seen.add(source.id)
            if source.kind == "BLOCK":
                found.add(source.id)
            elif source.kind == "CONTINUATION" and source.text.upper() in self.connectors:
                stack += self.connectors[source.text.upper()].inputs[0].wires
        return found

    def _typed(self, element: Element) -> str | None:
        name = element.text.upper()
        conversion = _CONVERSION.match(name)
        if name in self.context.functions:
            return self.context.functions[name] or None
        if name in _COMPARISONS:
            return "BOOL"
        if conversion is not None and conversion.group(1) in _ELEMENTARY:
            return conversion.group(1)
        if name not in _SAME_TYPE:
            return None
        pins = [p for p in element.inputs if p.name.upper() not in (_ENABLE, "G", "K")]
        if name == "LIMIT":
            pins = [p for p in pins if p.name.upper() == "IN"] + pins
        for pin in pins:
            for wire in pin.wires:
                found = self._source_type(wire)
                if found is not None:
                    return found
        return None

    def _source_type(self, wire: Wire) -> str | None:
        """The type of what comes along `wire`, when known already."""
        for _ in range(MAX_INLINE_DEPTH):
            source = self.by_id.get(wire.element)
            if source is None:
                return None
            if source.kind != "CONTINUATION":
                break
            connector = self.connectors.get(source.text.upper())
            if connector is None or not connector.inputs or not connector.inputs[0].wires:
                return None
            wire = connector.inputs[0].wires[0]
        else:
            return None
        if source.kind in ("IN", "INOUT"):
            literal = _TYPED_LITERAL.match(source.text.strip())
            if literal is not None and literal.group(1).upper() in _ELEMENTARY:
                return literal.group(1).upper()
            declared = self.context.variables.get(source.text.strip().upper(), "")
            return declared if declared.upper() in _ELEMENTARY else None
        if source.kind in ("LEFT_RAIL", "CONTACT", "COIL"):
            return "BOOL"
        if source.kind == "BLOCK" and not source.instance:
            if wire.pin.upper() == _ENABLE_OUT:
                return "BOOL"
            if wire.pin and wire.pin.upper() != _result_pin(source).upper():
                return None
            return self.types.get(source.id)
        return None

    # ---- checks and output -------------------------------------------------------------

    def _check_elements(self) -> None:
        language = self.body.language
        for element in self.body.elements:
            if language == "FBD" and element.kind in LD_KINDS:
                self._error(
                    element, Code.GRAPHIC_KIND, f"{element.kind} belongs in an LD body, not FBD"
                )
            for pin in element.inputs:
                for wire in pin.wires:
                    self._check_wire(element, wire)
            if element.kind in _ACTS_ON_ITS_WIRE and not _wired(element):
                what = f"{element.kind} {element.text}".strip()
                self._error(
                    element,
                    Code.GRAPHIC_UNCONNECTED,
                    f"{what} (element {element.id}) has no wire into it: it is left out",
                )
            if element.kind == "CONTINUATION" and element.text.upper() not in self.connectors:
                self._error(
                    element,
                    Code.GRAPHIC_LABEL,
                    f"no connector '{element.text}' for this continuation",
                )
            if element.kind == "BLOCK" and not _IDENTIFIER.match(element.text):
                self._error(element, Code.GRAPHIC_SYNTAX, f"'{element.text}' is not a block type")
        seen: dict[str, Element] = {}
        for element in self.body.elements:
            if element.kind in ("LABEL", "CONNECTOR"):
                name = f"{element.kind} {element.text.upper()}"
                if name in seen:
                    self._error(
                        element,
                        Code.GRAPHIC_LABEL,
                        f"{element.kind.lower()} '{element.text}' is given twice",
                    )
                seen[name] = element

    def _check_wire(self, consumer: Element, wire: Wire) -> None:
        source = self.by_id.get(wire.element)
        if source is None:
            self._error(
                consumer,
                Code.GRAPHIC_WIRE,
                f"a wire comes from element {wire.element}, which is not in the drawing",
            )
            return
        if not source.outputs:
            self._error(
                consumer,
                Code.GRAPHIC_WIRE,
                f"a wire comes from element {wire.element} ({source.kind}), which has no output",
            )
            return
        names = [p.name.upper() for p in source.outputs]
        if wire.pin and wire.pin.upper() not in names and wire.pin.upper() != _ENABLE_OUT:
            self._error(
                consumer,
                Code.GRAPHIC_WIRE,
                f"a wire comes from output '{wire.pin}' of element {wire.element}, "
                "which has no such output",
            )

    def _temporary(self, name: str, type_text: str) -> str:
        if name.upper() in self.context.variables:
            self.out.diagnostics.append(
                Diagnostic.at(
                    Pos(self.file, self.body.line, self.body.col),
                    Code.GRAPHIC_NAME,
                    f"the variable '{name}' is declared, and the drawing needs that name itself",
                )
            )
        if type_text:
            self.out.temporaries.setdefault(name, type_text)
        return name

    def _emit(self, element: Element, text: str) -> None:
        self.out.lines.append(Line(self.prefix + text, element))
        self.prefix = ""

    def _error(self, element: Element, code: Code, message: str) -> None:
        self.out.diagnostics.append(
            Diagnostic.at(Pos(self.file, element.line, element.col), code, message)
        )
