"""The outline of a file: its POUs with their var blocks' variables, methods and
properties, its types with their members, its global lists, nested, each with its range
and the range of its name. Read from the text as it is, so a file that does not parse
right now keeps its outline."""

from __future__ import annotations

from dataclasses import dataclass

from backend.compiler.language.analysis import Analysis
from backend.compiler.language.position import Range, token_range
from backend.compiler.language.tokens import VAR_KINDS, Lexed, declarations, lex

# the blocks shown, and the kind an outline names them by
_KINDS = {
    "PROGRAM": "program",
    "FUNCTION_BLOCK": "function_block",
    "FUNCTION": "function",
    "INTERFACE": "interface",
    "METHOD": "method",
    "PROPERTY": "property",
    "CONFIGURATION": "configuration",
    "RESOURCE": "resource",
    "STRUCT": "struct",
}


@dataclass(frozen=True)
class Symbol:
    name: str
    kind: str  # program, function_block, function, interface, method, property, struct,
    # type, variable, global_list, configuration, resource
    detail: str  # a variable's block and type, a type's first word
    range: Range  # the whole declaration
    selection_range: Range  # its name
    children: tuple[Symbol, ...] = ()


def outline(analysis: Analysis, file: str) -> list[Symbol]:
    """The symbols `file` declares, in the order they stand."""
    text = analysis.texts.get(file)
    if text is None:
        return []
    lexed = lex(text)
    return _children(lexed, -1)


def _children(lexed: Lexed, parent: int) -> list[Symbol]:
    found: list[Symbol] = []
    for index, span in enumerate(lexed.spans):
        if span.parent != parent:
            continue
        whole = Range(*span.start, *span.end)
        if span.kind in VAR_KINDS:
            variables = _variables(lexed, index, span.kind)
            if parent < 0 or lexed.spans[parent].kind in ("CONFIGURATION", "RESOURCE"):
                found.append(Symbol(span.kind, "global_list", "", whole, whole, tuple(variables)))
            else:
                found += variables
        elif span.kind == "TYPE":
            found += _types(lexed, index)
        elif span.kind in _KINDS and span.name_token >= 0:
            name = lexed.tokens[span.name_token]
            children = tuple(_children(lexed, index))
            found.append(
                Symbol(name.text, _KINDS[span.kind], span.kind, whole, token_range(name), children)
            )
        elif span.kind in ("GET", "SET"):
            found += _children(lexed, index)
    return found


def _variables(lexed: Lexed, span: int, block: str) -> list[Symbol]:
    found = []
    for name, type_text in declarations(lexed, span):
        token = lexed.tokens[name]
        where = token_range(token)
        detail = f"{block} : {type_text}" if block else type_text
        found.append(Symbol(token.text, "variable", detail, where, where))
    return found


def _types(lexed: Lexed, span: int) -> list[Symbol]:
    """The types one TYPE ... END_TYPE declares; a STRUCT with its members."""
    structs = {
        lexed.spans[i].name_token: i
        for i, s in enumerate(lexed.spans)
        if s.parent == span and s.kind == "STRUCT"
    }
    found = []
    for name, type_text in declarations(lexed, span):
        token = lexed.tokens[name]
        where = token_range(token)
        if name in structs:
            inner = lexed.spans[structs[name]]
            members = tuple(_variables(lexed, structs[name], ""))
            whole = Range(token.line, token.col, *inner.end)
            found.append(Symbol(token.text, "struct", "STRUCT", whole, where, members))
        else:
            found.append(Symbol(token.text, "type", type_text, where, where))
    return found
