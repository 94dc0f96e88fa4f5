"""Hover: what the name under the cursor is, as an engineer wants it at a glance: its
declaration (type, block, initial value), where it is declared, and the comment written
with it; a POU's or method's interface; a standard function's parameters; in a test file
what a test function does. The live value when online is the adapters' to add."""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

from backend.compiler import builtins
from backend.compiler.ast import key
from backend.compiler.comments import declaration_comment
from backend.compiler.language.analysis import Analysis
from backend.compiler.language.position import (
    Location,
    Range,
    Symbol,
    current_declaration,
    symbol_at,
)
from backend.compiler.language.tokens import Lexed, piece_at
from backend.compiler.resolve import PouSymbols
from backend.compiler.source import Pos, stdlib_sources
from backend.compiler.test_functions import TEST_FUNCTIONS
from backend.compiler.types import ElementaryType

# what each test function does (docs/testing.md), shown where a hover shows a comment
TEST_FUNCTION_HELP = {
    "ASSERT_TRUE": "The test fails unless CONDITION is TRUE.",
    "ASSERT_FALSE": "The test fails unless CONDITION is FALSE.",
    "ASSERT_EQUAL": "The test fails unless EXPECTED and ACTUAL, of the same type, are equal "
    "(arrays element by element, structures member by member).",
    "ASSERT_NOT_EQUAL": "The test fails when EXPECTED and ACTUAL, of the same type, are equal.",
    "ASSERT_NEAR": "The test fails unless ABS(EXPECTED - ACTUAL) <= TOLERANCE (a NaN never "
    "passes).",
    "FAIL": "The test fails here with MESSAGE.",
    "RUN_CYCLES": "Runs N cycles of the resource, virtual time moving on by its cycle time each.",
    "RUN_FOR": "Runs as many cycles of the resource as T of virtual time takes.",
    "RUN_UNTIL": "Runs cycles until CONDITION is TRUE after one; the test fails when T of "
    "virtual time passes first.",
    "TEST_CYCLES": "The cycles this test has run so far.",
    "FORCE": "Forces a program's or a global variable to VALUE until RELEASE or the end of "
    "the test.",
    "RELEASE": "Ends the force of VARIABLE.",
    "REPLAY": "Runs the cycles of the recording FILE (its path in the project folder), each "
    "cycle given what it took from outside in the recorded run.",
}


@dataclass(frozen=True)
class Hover:
    range: Range  # the identifier hovered
    kind: str  # the symbol's kind (position.Symbol.kind)
    signature: str  # the declaration as ST reads it, one or more lines
    declared: Location | None  # None for the standard and the test functions
    owner: str  # the POU, structure or enum it belongs to; "" at the top
    # the comment on or above the declaration's line, what a test function does; "" if none
    comment: str

    @property
    def markdown(self) -> str:
        parts = [f"```st\n{self.signature}\n```"]
        if self.comment:
            parts.append(self.comment)
        if self.declared is not None:
            place = f"{self.declared.file}:{self.declared.range.line}"
            parts.append(
                f"Declared in {self.owner} ({place})" if self.owner else f"Declared at {place}"
            )
        return "\n\n".join(parts)


def hover(analysis: Analysis, file: str, line: int, col: int) -> Hover | None:
    located = symbol_at(analysis, file, line, col)
    if located is None:
        return None
    symbol = located.symbol
    declared = None
    comment = ""
    pos = current_declaration(analysis, symbol)
    if symbol.kind == "test_function":
        comment = TEST_FUNCTION_HELP.get(symbol.name, "")
    elif pos is not None:
        end = pos.col + len(symbol.name)
        declared = Location(pos.file, Range(pos.line, pos.col, pos.line, end))
        comment = declaration_comment(_text(analysis, pos.file), pos)
    return Hover(
        located.range, symbol.kind, signature(analysis, symbol), declared, symbol.owner, comment
    )


def signature(analysis: Analysis, symbol: Symbol) -> str:
    """The declaration of `symbol` as ST reads it."""
    type_name = symbol.type.name if symbol.type is not None else ""
    match symbol.kind:
        case "variable":
            variable = symbol.variable
            located = f" AT {variable.location}" if variable and variable.location else ""
            head = f"{symbol.detail} {symbol.name}{located} : {type_name}"
            initial = _initial_value(analysis, current_declaration(analysis, symbol))
            return f"{head} := {initial}" if initial else head
        case "pou" | "method":
            block = symbol.block
            name = f"{symbol.owner}.{symbol.name}" if symbol.owner else symbol.name
            head = f"{symbol.detail} {name}" + (f" : {type_name}" if type_name else "")
            return "\n".join([head, *interface_lines(block)]) if block else head
        case "property":
            return f"PROPERTY {symbol.owner}.{symbol.name} : {type_name}"
        case "type":
            return _type_signature(analysis, symbol)
        case "enum_value":
            info = analysis.resolved.enums.get(key(symbol.owner))
            value = info.values[key(symbol.name)][1] if info else ""
            return f"{symbol.owner}#{symbol.name} (= {value})"
        case "interface":
            return f"INTERFACE {symbol.name}"
        case "standard_function":
            return standard_signature(symbol.name)
        case "test_function":
            return test_signature(symbol.name)
        case _:
            return f"{symbol.name} : {symbol.detail}"


def interface_lines(block: PouSymbols) -> list[str]:
    """A POU's or method's parameters, one per line: `  VAR_INPUT IN : BOOL`."""
    return [f"  {v.kind} {v.name} : {v.type.name}" for v in block.parameters]


def standard_signature(name: str) -> str:
    """`LIMIT(MN, IN, MX)`; a function of any number of inputs `MAX(IN1, IN2, ...)`."""
    found = builtins.lookup(name)
    if found is None:
        return name
    params = ", ".join(found.params) if found.params is not None else "IN1, IN2, ..."
    return f"{found.name}({params}) (standard function)"


def test_signature(name: str) -> str:
    """`ASSERT_EQUAL(EXPECTED, ACTUAL [, MESSAGE]) (test function)`; with the type of the
    value of one that gives one."""
    found = TEST_FUNCTIONS.get(key(name))
    if found is None:
        return name
    params = ", ".join(found.params[: found.required])
    optional = "".join(f" [, {p}]" for p in found.params[found.required :])
    gives = f" : {found.gives.name}" if found.gives is not None else ""
    return f"{found.name}({params}{optional}){gives} (test function)"


def _initial_value(analysis: Analysis, pos: Pos | None) -> str:
    """The text after `:=` of the declaration at `pos`, up to its `;`."""
    found = _lexed_at(analysis, pos)
    if found is None:
        return ""
    lexed, start = found
    depth = 0
    begin = -1
    for index in range(start, min(start + 400, len(lexed.tokens))):
        token = lexed.tokens[index]
        if token.text in ("(", "["):
            depth += 1
        elif token.text in (")", "]"):
            depth -= 1
        elif token.text == ":=" and depth == 0 and begin < 0:
            begin = index + 1
        elif token.text in (";", "END_VAR", "END_STRUCT") and depth <= 0:
            if begin < 0 or begin >= index:
                return ""
            first, last = lexed.tokens[begin], lexed.tokens[index - 1]
            return " ".join(lexed.text[first.offset : last.end].split())
    return ""


def _type_signature(analysis: Analysis, symbol: Symbol) -> str:
    resolved = analysis.resolved
    if isinstance(symbol.type, ElementaryType) and symbol.detail == "elementary":
        return _elementary(symbol.type)
    if key(symbol.name) in resolved.structs:
        info = resolved.structs[key(symbol.name)]
        fields = [f"  {m.name} : {m.type.name};" for m in info.members]
        return "\n".join([f"TYPE {symbol.name} : STRUCT", *fields, "END_STRUCT"])
    if key(symbol.name) in resolved.enums:
        values = resolved.enums[key(symbol.name)].values.values()
        listed = ", ".join(f"{name} := {value}" for name, value in values)
        return f"TYPE {symbol.name} : ({listed})"
    declared = _declared_text(analysis, current_declaration(analysis, symbol))
    return f"TYPE {symbol.name} : {declared}" if declared else f"TYPE {symbol.name}"


def _elementary(basic: ElementaryType) -> str:
    """`INT: 16-bit signed integer, -32768..32767`."""
    if basic.is_integer:
        kind = (
            "bit string"
            if basic.category == "bits"
            else "signed integer"
            if basic.signed
            else "unsigned integer"
        )
        return f"{basic.name}: {basic.bits}-bit {kind}, {basic.min}..{basic.max}"
    described = {
        "bool": "TRUE or FALSE",
        "real": f"{basic.bits}-bit floating point",
        "time": "a duration (T#1h2m3s4ms)",
        "date": "a date, time of day or both",
        "string": f"characters, at most {basic.max_length} unless [n] says how many",
    }
    return f"{basic.name}: {described.get(basic.category, basic.category)}"


def _declared_text(analysis: Analysis, pos: Pos | None) -> str:
    """The text after the `:` of the type declaration at `pos`, up to its `;`."""
    found = _lexed_at(analysis, pos)
    if found is None:
        return ""
    lexed, start = found
    tokens = lexed.tokens[start : start + 200]
    colon = next((i for i, t in enumerate(tokens) if t.text == ":"), -1)
    end = next((i for i, t in enumerate(tokens) if t.text == ";"), -1)
    if colon < 0 or end <= colon + 1:
        return ""
    return " ".join(lexed.text[tokens[colon + 1].offset : tokens[end - 1].end].split())


def _lexed_at(analysis: Analysis, pos: Pos | None) -> tuple[Lexed, int] | None:
    """The lexed piece of the file around `pos` and the index of the token at `pos`."""
    if pos is None:
        return None
    text = _text(analysis, pos.file)
    if text is None:
        return None
    lexed, before = piece_at(text, pos.line)
    return lexed, lexed.index_at(pos.line - before, pos.col)


def _text(analysis: Analysis, file: str) -> str | None:
    """A file's text: the project's as the editor has it, or the standard library's."""
    if file in analysis.texts:
        return analysis.texts[file]
    return _standard_texts().get(file)


@cache
def _standard_texts() -> dict[str, str]:
    return {source.name: source.text for source in stdlib_sources()}
