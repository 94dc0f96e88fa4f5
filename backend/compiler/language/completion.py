"""Completion: what may be written at the cursor. After `x.` the members of what `x` is
(a structure's members, a function block's inputs, outputs, methods and properties);
after `Color#` the enum's values; after `:` in a var block the types; elsewhere the
variables in scope, the globals, the POUs, types and standard functions (a call with its
parameters as a snippet), in a test file the test functions alike, the keywords and
snippets for statements and POU skeletons.

The text around the cursor is read as it is, parsed or not (the line being typed); the
names come from the last analysis that resolved, plus those the cursor's POU declares in
its text right now."""

from __future__ import annotations

from dataclasses import dataclass

from backend.compiler import builtins
from backend.compiler.ast import key
from backend.compiler.comments import declaration_comment
from backend.compiler.language.analysis import Analysis
from backend.compiler.language.hover import (
    TEST_FUNCTION_HELP,
    interface_lines,
    standard_signature,
    test_signature,
)
from backend.compiler.language.position import (
    Symbol,
    base_before,
    call_around,
    declared_in_text,
    members,
    scope_at,
    variable_symbol,
)
from backend.compiler.language.tokens import KEYWORDS, VAR_KINDS, Lexed, piece_at
from backend.compiler.resolve import PouSymbols, Variable
from backend.compiler.test_functions import TEST_FUNCTIONS, is_test_file
from backend.compiler.types import FbType

ELEMENTARY_TYPES = (
    "BOOL", "BYTE", "WORD", "DWORD", "LWORD", "SINT", "INT", "DINT", "LINT", "USINT", "UINT",
    "UDINT", "ULINT", "REAL", "LREAL", "TIME", "LTIME", "DATE", "TOD", "DT", "LDATE", "LTOD",
    "LDT", "STRING", "WSTRING", "CHAR",
)  # fmt: skip

# (label, detail, body): statement snippets and POU skeletons
SNIPPETS = (
    ("IF", "IF ... THEN ... END_IF", "IF ${1:condition} THEN\n\t${2}\nEND_IF;"),
    ("CASE", "CASE ... OF ... END_CASE", "CASE ${1:selector} OF\n\t${2:1}:\n\t\t${3}\nEND_CASE;"),
    ("FOR", "FOR ... END_FOR", "FOR ${1:i} := ${2:1} TO ${3:10} DO\n\t${4}\nEND_FOR;"),
    ("WHILE", "WHILE ... END_WHILE", "WHILE ${1:condition} DO\n\t${2}\nEND_WHILE;"),
    ("REPEAT", "REPEAT ... END_REPEAT", "REPEAT\n\t${1}\nUNTIL ${2:condition}\nEND_REPEAT;"),
    ("PROGRAM", "PROGRAM skeleton", "PROGRAM ${1:Name}\nVAR\n\t${2}\nEND_VAR\n${3}\nEND_PROGRAM\n"),
    (
        "FUNCTION_BLOCK",
        "FUNCTION_BLOCK skeleton",
        "FUNCTION_BLOCK ${1:Name}\nVAR_INPUT\n\t${2}\nEND_VAR\nVAR_OUTPUT\n\t${3}\nEND_VAR\n"
        "VAR\nEND_VAR\n${4}\nEND_FUNCTION_BLOCK\n",
    ),
    (
        "FUNCTION",
        "FUNCTION skeleton",
        "FUNCTION ${1:Name} : ${2:INT}\nVAR_INPUT\n\t${3}\nEND_VAR\n${1:Name} := ${4};\n"
        "END_FUNCTION\n",
    ),
    (
        "TYPE STRUCT",
        "TYPE ... STRUCT skeleton",
        "TYPE ${1:Name} :\nSTRUCT\n\t${2}\nEND_STRUCT;\nEND_TYPE\n",
    ),
)

# how high a kind of item ranks (lower first) among those that match the prefix alike
_RANK = {
    "parameter": -1,
    "local": 0,
    "member": 0,
    "enum_value": 1,
    "variable": 1,
    "method": 1,
    "property": 1,
    "function": 2,
    "function_block": 2,
    "type": 2,
    "standard": 3,
    "snippet": 4,
    "keyword": 5,
}


# the variables of a function block (and every member of a structure) named from outside
_OUTSIDE = ("VAR_INPUT", "VAR_OUTPUT", "VAR_IN_OUT", "MEMBER", "SYSTEM")


@dataclass(frozen=True)
class CompletionItem:
    label: str
    # variable, function, function_block, method, property, type, keyword, snippet, member,
    # enum_value
    kind: str
    detail: str  # a type, a signature in one line
    insert_text: str
    snippet: bool  # insert_text holds ${n} placeholders
    documentation: str = ""


@dataclass(frozen=True)
class _Ranked:
    rank: int
    item: CompletionItem


def complete(analysis: Analysis, file: str, line: int, col: int) -> list[CompletionItem]:
    """What may be written at line:col of `file`, those starting with the word typed so
    far first (case-insensitively), most relevant first, then by label."""
    text = analysis.texts.get(file)
    if text is None:
        return []
    # only the declaration being typed in is read: a keystroke relexes no more
    lexed, lines_before = piece_at(text, line)
    line -= lines_before
    piece = lexed.text
    offset = lexed.offset(line, col)
    if not 0 <= offset <= len(piece) or col < 1 or _in_comment_or_string(lexed, line, col, offset):
        return []
    start = offset
    while start > 0 and (piece[start - 1].isalnum() or piece[start - 1] == "_"):
        start -= 1
    prefix = piece[start:offset]
    before = lexed.index_at(line, col - len(prefix)) - 1
    previous = lexed.tokens[before].text if before >= 0 else ""
    if previous == ".":
        base = base_before(analysis, file, lexed, before, lines_before)
        inside = _through_self(lexed, before)  # THIS^. sees the block's own variables
        found = (
            [_member_item(m) for m in members(analysis, base) if inside or _seen_from_outside(m)]
            if base is not None
            else []
        )
    elif previous == "#" and before >= 1:
        found = _enum_items(analysis, lexed.tokens[before - 1].text)
    elif previous == ":" and lexed.innermost(line, col, VAR_KINDS | {"STRUCT"}):
        found = _type_items(analysis)
    else:
        found = _general_items(analysis, file, lexed, line, col)  # lines of the piece
        if previous in ("(", ","):  # an argument begins: the callee's parameters first
            callee = call_around(analysis, file, lexed, before + 1, lines_before)
            found += _parameter_items(callee) if callee is not None else []
    return _ordered(found, prefix)


def _in_comment_or_string(lexed: Lexed, line: int, col: int, offset: int) -> bool:
    if any(comment.holds(offset) for comment in lexed.comments):
        return True
    index = lexed.index_at(line, col) - 1
    token = lexed.tokens[index] if index >= 0 else None
    if token is None or token.kind != "string":
        return False
    unclosed = len(token.text) < 2 or token.text[-1] != token.text[0]
    return token.offset < offset < token.end or (offset == token.end and unclosed)


def _ordered(found: list[_Ranked], prefix: str) -> list[CompletionItem]:
    wanted = key(prefix)
    seen: set[tuple[str, str]] = set()
    result = []
    matching = [r for r in found if key(r.item.label).startswith(wanted)]
    for ranked in sorted(matching, key=lambda r: (r.rank, key(r.item.label), r.item.label)):
        identity = (key(ranked.item.label), ranked.item.kind)
        if identity not in seen:
            seen.add(identity)
            result.append(ranked.item)
    return result


def _member_item(symbol: Symbol) -> _Ranked:
    type_name = symbol.type.name if symbol.type is not None else ""
    if symbol.kind == "method" and symbol.block is not None:
        insert, snippet = _call_snippet(symbol.name, symbol.block.parameters)
        documentation = "\n".join(interface_lines(symbol.block))
        item = CompletionItem(symbol.name, "method", type_name, insert, snippet, documentation)
        return _Ranked(_RANK["member"], item)
    kind = symbol.kind if symbol.kind in ("property", "enum_value") else "member"
    detail = f"{symbol.detail} : {type_name}" if symbol.kind == "variable" else type_name
    return _Ranked(_RANK["member"], CompletionItem(symbol.name, kind, detail, symbol.name, False))


def _through_self(lexed: Lexed, dot: int) -> bool:
    """Whether the `.` at token `dot` follows `THIS^` or `SUPER^`."""
    if dot < 2 or lexed.tokens[dot - 1].text != "^":
        return False
    return lexed.tokens[dot - 2].upper in ("THIS", "SUPER")


def _seen_from_outside(symbol: Symbol) -> bool:
    """A member an engineer names through an instance: not a function block's own VAR."""
    return symbol.kind != "variable" or symbol.detail in _OUTSIDE


def _parameter_items(callee: PouSymbols) -> list[_Ranked]:
    """`IN := ` for each input and in-out, `Q => ` for each output of what is called."""
    found = []
    for number, parameter in enumerate(callee.parameters):  # in the order declared
        arrow = "=>" if parameter.kind == "VAR_OUTPUT" else ":="
        detail = f"{parameter.kind} : {parameter.type.name}"
        insert = f"{parameter.name} {arrow} "
        item = CompletionItem(f"{parameter.name} {arrow}", "variable", detail, insert, False)
        found.append(_Ranked(_RANK["parameter"] - len(callee.parameters) + number, item))
    return found


def _enum_items(analysis: Analysis, type_name: str) -> list[_Ranked]:
    info = analysis.resolved.enums.get(key(type_name))
    if info is None:
        return []
    return [
        _Ranked(
            _RANK["enum_value"],
            CompletionItem(name, "enum_value", f"{info.type.name} = {value}", name, False),
        )
        for name, value in info.values.values()
    ]


def _type_items(analysis: Analysis) -> list[_Ranked]:
    resolved = analysis.resolved
    found = [
        _Ranked(_RANK["standard"], CompletionItem(name, "type", "elementary type", name, False))
        for name in ELEMENTARY_TYPES
    ]
    for name in ("ARRAY", "REF_TO", "POINTER TO", "REFERENCE TO"):
        found.append(_Ranked(_RANK["keyword"], CompletionItem(name, "keyword", "", name, False)))
    for _, pou in sorted(resolved.pous.items()):
        if pou.kind == "FUNCTION_BLOCK":
            rank = (
                _RANK["function_block"]
                if key(pou.name) in analysis.user_pous
                else _RANK["standard"]
            )
            documentation = "\n".join(interface_lines(pou))
            item = CompletionItem(
                pou.name, "function_block", "FUNCTION_BLOCK", pou.name, False, documentation
            )
            found.append(_Ranked(rank, item))
    for name in [*resolved.structs, *resolved.enums, *resolved.interfaces]:
        spelling = _type_name(analysis, name)
        found.append(
            _Ranked(_RANK["type"], CompletionItem(spelling, "type", "type", spelling, False))
        )
    return found


def _type_name(analysis: Analysis, name: str) -> str:
    resolved = analysis.resolved
    if name in resolved.structs:
        return resolved.structs[name].name
    if name in resolved.enums:
        return resolved.enums[name].type.name
    return resolved.interfaces[name].name


def _general_items(
    analysis: Analysis, file: str, lexed: Lexed, line: int, col: int
) -> list[_Ranked]:
    resolved = analysis.resolved
    scope = scope_at(analysis, lexed, line, col)
    text = analysis.texts[file]
    found: list[_Ranked] = []
    own: set[str] = set()
    for variable in _scope_variables(scope):
        own.add(key(variable.name))
        comment = declaration_comment(text, variable.pos) if variable.pos.file == file else ""
        found += _variable_items(analysis, variable, _RANK["local"], comment)
    for declared, kind, type_text in declared_in_text(lexed, line, col):
        if declared.upper not in own:  # declared while the file does not parse yet
            detail = f"{kind} : {type_text}"
            item = CompletionItem(declared.text, "variable", detail, declared.text, False)
            found.append(_Ranked(_RANK["local"], item))
    for variable in resolved.globals:
        if key(variable.name) not in own:
            found += _variable_items(analysis, variable, _RANK["variable"], "")
    block = scope.outer if scope is not None and scope.outer is not None else scope
    if block is not None and block.kind in ("PROGRAM", "FUNCTION_BLOCK"):
        for _, method in sorted(block.methods.items()):
            insert, snippet = _call_snippet(method.name, method.parameters)
            detail = method.return_type.name if method.return_type is not None else "METHOD"
            found.append(
                _Ranked(
                    _RANK["method"], CompletionItem(method.name, "method", detail, insert, snippet)
                )
            )
        for _, prop in sorted(block.properties.items()):
            found.append(
                _Ranked(
                    _RANK["property"],
                    CompletionItem(prop.name, "property", prop.type.name, prop.name, False),
                )
            )
    found += _pou_items(analysis)
    for name in sorted(resolved.structs) + sorted(resolved.enums):
        spelling = _type_name(analysis, name)
        found.append(
            _Ranked(_RANK["type"], CompletionItem(spelling, "type", "type", spelling, False))
        )
    for _, info in sorted(resolved.enums.items()):
        for spelling, value in info.values.values():
            detail = f"{info.type.name}#{spelling} = {value}"
            found.append(
                _Ranked(
                    _RANK["enum_value"],
                    CompletionItem(spelling, "enum_value", detail, spelling, False),
                )
            )
    for name in builtins.names():
        standard = builtins.lookup(name)
        params = standard.params if standard is not None else None
        names = params if params is not None else ("IN1", "IN2")
        item = CompletionItem(
            name,
            "function",
            "standard function",
            _placeholders(name, names),
            True,
            standard_signature(name),
        )
        found.append(_Ranked(_RANK["standard"], item))
    if is_test_file(file):
        for name, function in TEST_FUNCTIONS.items():
            documentation = "\n\n".join(
                part for part in (test_signature(name), TEST_FUNCTION_HELP.get(name, "")) if part
            )
            item = CompletionItem(
                name,
                "function",
                "test function",
                _placeholders(name, function.params),
                True,
                documentation,
            )
            found.append(_Ranked(_RANK["standard"], item))
    for label, detail, body in SNIPPETS:
        found.append(
            _Ranked(_RANK["snippet"], CompletionItem(label, "snippet", detail, body, True))
        )
    for word in sorted(KEYWORDS):
        found.append(
            _Ranked(_RANK["keyword"], CompletionItem(word, "keyword", "keyword", word, False))
        )
    return found


def _scope_variables(scope: PouSymbols | None) -> list[Variable]:
    """The variables code in `scope` names without a dot: its own, then its block's (in a
    method); not the result of a function (named like the function)."""
    if scope is None:
        return []
    found = [v for v in scope.variables if v.kind not in ("VAR_GLOBAL",)]
    if scope.outer is not None:
        found += [v for v in scope.outer.variables if v.kind != "VAR_GLOBAL"]
    return found


def _variable_items(
    analysis: Analysis, variable: Variable, rank: int, comment: str
) -> list[_Ranked]:
    symbol = variable_symbol(variable, "")
    detail = f"{symbol.detail} : {variable.type.name}"
    items = [
        _Ranked(
            rank, CompletionItem(variable.name, "variable", detail, variable.name, False, comment)
        )
    ]
    if isinstance(variable.type, FbType):  # `t1(IN := , PT := )`: the instance called
        block = analysis.resolved.pous.get(key(variable.type.name))
        if block is not None:
            insert, snippet = _call_snippet(variable.name, block.parameters)
            label = f"{variable.name}(...)"
            documentation = "\n".join(interface_lines(block))
            items.append(
                _Ranked(
                    rank,
                    CompletionItem(
                        label, "snippet", f"call of {block.name}", insert, snippet, documentation
                    ),
                )
            )
    return items


def _pou_items(analysis: Analysis) -> list[_Ranked]:
    found = []
    for name, pou in sorted(analysis.resolved.pous.items()):
        if pou.kind not in ("FUNCTION", "FUNCTION_BLOCK"):
            continue
        user = name in analysis.user_pous
        kind = "function" if pou.kind == "FUNCTION" else "function_block"
        rank = _RANK[kind] if user else _RANK["standard"]
        insert, snippet = _call_snippet(pou.name, pou.parameters)
        detail = pou.kind if user else f"standard {pou.kind}"
        documentation = "\n".join(interface_lines(pou))
        found.append(
            _Ranked(rank, CompletionItem(pou.name, kind, detail, insert, snippet, documentation))
        )
    return found


def _placeholders(name: str, params: tuple[str, ...]) -> str:
    """`LIMIT(${1:MN}, ${2:IN}, ${3:MX})`: a call, each parameter a placeholder named after it."""
    body = ", ".join(f"${{{n}:{p}}}" for n, p in enumerate(params, 1))
    return f"{name}({body})"


def _call_snippet(name: str, parameters: list[Variable]) -> tuple[str, bool]:
    """`TON(IN := ${1}, PT := ${2})`: a call with its inputs named, the cursor in the first."""
    inputs = [p.name for p in parameters if p.kind in ("VAR_INPUT", "VAR_IN_OUT")]
    body = ", ".join(f"{p} := ${{{n}}}" for n, p in enumerate(inputs, 1))
    return f"{name}({body})", True
