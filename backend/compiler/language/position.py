"""What is at file:line:col: the identifier there and the symbol it names in its POU or
method (a variable, global, POU, method, property, type, enum value, a member through a
dotted chain, a parameter named in a call, a standard function), with where that symbol is
declared. Hover, definition, references and rename all start here.

The identifier and its context come from the text (tokens.py), so a file being typed,
which does not parse, still answers; what a name means comes from the analysis (its
symbol tables), looked up in the scope the cursor is in, as the compiler looks it up."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import NamedTuple

from backend.compiler import ast, builtins
from backend.compiler.ast import key
from backend.compiler.language.analysis import Analysis
from backend.compiler.language.tokens import (
    VAR_KINDS,
    Lexed,
    Token,
    declarations,
    piece_at,
    pieces,
)
from backend.compiler.resolve import (
    PARAMETER_KINDS,
    PouSymbols,
    PropertyInfo,
    Variable,
    visible,
)
from backend.compiler.source import Pos
from backend.compiler.test_functions import test_function
from backend.compiler.types import (
    ArrayType,
    EnumType,
    FbType,
    InterfaceType,
    OpenArrayType,
    RefType,
    StructType,
    Type,
    elementary,
    value_type,
)
from runtime.contract.system_variables import NAMESPACE

STANDARD_FILE_PREFIX = "stdlib/"
_MAX_CHAIN = 64  # members followed in one dotted chain (hostile text may hold thousands)
_SCOPES = frozenset({"PROGRAM", "FUNCTION_BLOCK", "FUNCTION", "INTERFACE", "METHOD", "PROPERTY"})
_ACCESSORS = frozenset({"GET", "SET"})
_DECLARING = frozenset({"PROGRAM", "FUNCTION_BLOCK", "FUNCTION", "METHOD"})
# the keywords a declared name follows (past its modifiers, which `_declares` does not see)
_NAMING_KEYWORDS = _DECLARING | {"PROPERTY", "INTERFACE", "TYPE"}
_POU_KINDS = ("PROGRAM", "FUNCTION_BLOCK", "FUNCTION")
# a member of a function block seen from outside its instances
_HIDDEN_MEMBERS = ("VAR_TEMP", "VAR_GLOBAL", "RETURN")


class Range(NamedTuple):
    """1-based lines and columns in characters; the end is exclusive."""

    line: int
    col: int
    end_line: int
    end_col: int


@dataclass(frozen=True)
class Location:
    file: str
    range: Range


@dataclass(frozen=True)
class Symbol:
    # variable, pou, method, property, type, enum_value, interface, standard_function,
    # test_function (of a test file, docs/testing.md)
    kind: str
    name: str  # as declared
    declared: Pos | None  # the declaration's name; None for a standard function
    owner: str  # the POU (`Tank`, `Tank.Fill`), struct or enum it belongs to; "" at the top
    detail: str  # a variable's block (VAR_INPUT, VAR_GLOBAL, MEMBER...), a POU's kind...
    type: Type | None = field(default=None, compare=False)
    variable: Variable | None = field(default=None, compare=False)
    block: PouSymbols | None = field(default=None, compare=False)  # a POU's or method's

    @property
    def identity(self) -> tuple[str, Pos | None, str]:
        """The same symbol wherever it is named: declared in one place."""
        return (self.kind, self.declared, key(self.name))

    @property
    def standard(self) -> bool:
        """Part of the standard library (no source of the project's)."""
        return self.declared is None or self.declared.file.startswith(STANDARD_FILE_PREFIX)


@dataclass(frozen=True)
class Located:
    symbol: Symbol
    range: Range  # the identifier under the cursor


def symbol_at(analysis: Analysis, file: str, line: int, col: int) -> Located | None:
    """The symbol named by the identifier at (or just before) line:col of `file`."""
    text = analysis.texts.get(file)
    if text is None:
        return None
    lexed, before = piece_at(text, line)
    index = lexed.name_at(line - before, col)
    if index < 0:
        return None
    symbol = token_symbol(analysis, file, lexed, index, before)
    if symbol is None:
        return None
    return Located(symbol, token_range(lexed.tokens[index], before))


def token_range(token: Token, line_offset: int = 0) -> Range:
    """The range of a token of a text lexed from line `line_offset` + 1 of its file."""
    line = token.line + line_offset
    return Range(line, token.col, line, token.end_col)


def scope_at(analysis: Analysis, lexed: Lexed, line: int, col: int) -> PouSymbols | None:
    """The POU, method or property accessor whose code line:col stands in, as the last
    analysis resolved it; None outside any (globals, types)."""
    resolved = analysis.resolved
    scope: PouSymbols | None = None
    methods: dict[str, PouSymbols] = {}
    properties: dict[str, PropertyInfo] = {}
    prop: PropertyInfo | None = None
    for span in lexed.innermost(line, col, _SCOPES | _ACCESSORS):
        name = key(span.name)
        if span.kind in _POU_KINDS:
            scope = resolved.pous.get(name)
            methods = scope.methods if scope is not None else {}
            properties = scope.properties if scope is not None else {}
        elif span.kind == "INTERFACE":
            interface = resolved.interfaces.get(name)
            methods = interface.methods if interface is not None else {}
            properties = interface.properties if interface is not None else {}
        elif span.kind == "METHOD":
            scope = methods.get(name, scope)
        elif span.kind == "PROPERTY":
            prop = properties.get(name)
        elif prop is not None:  # GET or SET
            scope = (prop.getter if span.kind == "GET" else prop.setter) or scope
    return scope


@dataclass(frozen=True)
class _Place:
    """An identifier being resolved: the text around it and the scope it stands in."""

    analysis: Analysis
    file: str
    lexed: Lexed
    scope: PouSymbols | None
    line_offset: int  # the lines of the file before the lexed text


def token_symbol(
    analysis: Analysis, file: str, lexed: Lexed, index: int, line_offset: int = 0
) -> Symbol | None:
    """The symbol the name token `index` of `file` means, or None (an unknown name, a
    keyword, a literal)."""
    token = lexed.tokens[index]
    if not token.is_name():
        return None
    scope = scope_at(analysis, lexed, token.line, token.col)
    return _token_symbol(_Place(analysis, file, lexed, scope, line_offset), index, 0)


def _token_symbol(place: _Place, index: int, depth: int) -> Symbol | None:
    tokens = place.lexed.tokens
    token = tokens[index]
    before = tokens[index - 1].text if index > 0 else ""
    after = tokens[index + 1].text if index + 1 < len(tokens) else ""
    if before == "." and index >= 2:
        base = _expression_base(place, index - 2, depth + 1)
        return member(place.analysis, base, token.text) if base is not None else None
    if before == "#" and index >= 2:  # `Color#Red`
        return _enum_value(place.analysis, tokens[index - 2].text, token.text)
    declared = _declared_in_type(place, index)
    if declared is not None:
        return declared
    if after in (":=", "=>"):
        call = _open_call(place.lexed, index)
        if call is not None:
            return _parameter(place, call, token.text, depth)
        if call is None and _in_parentheses(place.lexed, index):
            return None  # a structure's member in an initial value `(x := 1)`
    if place.scope is None:  # a POU the analysis does not know (yet): its text declares
        here = _declared_here(place, token)
        if here is not None:
            return here
    found = lookup(place.analysis, place.scope, token.text, place.file)
    return found or _declared_here(place, token)


def lookup(
    analysis: Analysis, scope: PouSymbols | None, name: str, file: str = ""
) -> Symbol | None:
    """What a plain name means in `scope` (None: outside every POU) of `file`, as the
    compiler looks it up: a variable of the scope (its block's, in a method), a global, a
    method or property of the block, a POU, a type, an interface, an enum value, a test
    function (in a test file), a standard function."""
    resolved = analysis.resolved
    name_key = key(name)
    variable = (
        visible(resolved, scope, name)
        if scope is not None
        else resolved.globals_by_key.get(name_key)
    )
    if variable is not None:
        if variable.kind == "RETURN" and scope is not None:
            return _result_owner(analysis, scope)
        return variable_symbol(variable, _variable_owner(scope, variable))
    block = _block(scope)
    if block is not None:
        if name_key in block.methods:
            return method_symbol(block.methods[name_key], block.name)
        if name_key in block.properties:
            return property_symbol(block.properties[name_key], block.name)
    if name_key in resolved.pous:
        return pou_symbol(analysis, resolved.pous[name_key])
    index = _index(analysis)
    if name_key in index.types:
        return type_symbol(analysis, index.types[name_key])
    if name_key in resolved.interfaces:
        decl = resolved.interfaces[name_key].decl
        return Symbol(
            "interface", decl.name, name_pos(analysis, decl.pos, decl.name), "", "INTERFACE"
        )
    found = resolved.enum_values_named(name)
    if found:
        return _enum_value(analysis, found[0][0].type.name, name)
    if name_key == key(NAMESPACE) and resolved.system:
        return Symbol("namespace", NAMESPACE, None, "", "system variables")
    test = test_function(name, file)
    if test is not None:
        return Symbol("test_function", test.name, None, "", "FUNCTION")
    standard = builtins.lookup(name)
    if standard is not None and not name.startswith("_"):
        return Symbol("standard_function", standard.name, None, "", "FUNCTION")
    basic = elementary(name)
    if basic is not None:
        return Symbol("type", basic.name, None, "", "elementary", basic)
    return None


def declared_in_text(place_lexed: Lexed, line: int, col: int) -> list[tuple[Token, str, str]]:
    """The variables the POU (or method) at line:col declares in its text as it is now:
    each name's token, its block (VAR_INPUT...) and the text of its type. What the last
    analysis cannot know of a POU that does not parse while it is typed."""
    lexed = place_lexed
    holders = lexed.innermost(line, col, _DECLARING)
    if not holders:
        return []
    holder = lexed.spans.index(holders[-1])
    return [
        (lexed.tokens[name], span.kind, type_text)
        for index, span in enumerate(lexed.spans)
        if span.kind in VAR_KINDS and span.parent == holder
        for name, type_text in declarations(lexed, index)
    ]


def type_from_text(analysis: Analysis, text: str) -> Type | None:
    """The type a declaration's type text names (`TON`, `ARRAY[1..3] OF Point`,
    `REF_TO Motor`), as far as its members matter."""
    words = text.replace("[", " [ ").split()
    if not words:
        return None
    upper = [w.upper() for w in words]
    if upper[0] == "ARRAY" and "OF" in upper:
        element = type_from_text(analysis, " ".join(words[upper.index("OF") + 1 :]))
        return ArrayType(element, ()) if element is not None else None
    if upper[0] in ("REF_TO", "POINTER", "REFERENCE"):
        rest = words[2:] if upper[0] != "REF_TO" else words[1:]
        target = type_from_text(analysis, " ".join(rest))
        return RefType(target, implicit=upper[0] == "REFERENCE") if target is not None else None
    resolved = analysis.resolved
    name = upper[0]
    if name in resolved.pous and resolved.pous[name].kind == "FUNCTION_BLOCK":
        return FbType(resolved.pous[name].name)
    if name in resolved.structs:
        return StructType(resolved.structs[name].name)
    if name in resolved.enums:
        return resolved.enums[name].type
    if name in resolved.interfaces:
        return InterfaceType(resolved.interfaces[name].name)
    return elementary(name.split("[")[0])


def _declared_here(place: _Place, token: Token) -> Symbol | None:
    """A variable of the POU around `token` that only its current text declares."""
    for name, block, type_text in declared_in_text(place.lexed, token.line, token.col):
        if name.upper == token.upper:
            holders = place.lexed.innermost(token.line, token.col, _DECLARING)
            owner = holders[-1].name if holders else ""
            declared = Pos(place.file, name.line + place.line_offset, name.col)
            found = type_from_text(place.analysis, type_text)
            return Symbol("variable", name.text, declared, owner, block, found)
    return None


def members(analysis: Analysis, base: Type | Symbol) -> list[Symbol]:
    """What may follow `base.`: a structure's members, a function block's inputs,
    outputs, variables, methods and properties (an interface's methods and properties),
    an enum's values (`Color.Red`), the system variables (`SYS.`)."""
    resolved = analysis.resolved
    if isinstance(base, Symbol):
        if base.kind == "namespace":
            return [variable_symbol(v, NAMESPACE) for _, v in sorted(resolved.system.items())]
        if base.kind == "type" and isinstance(base.type, EnumType):
            enum = resolved.enums.get(key(base.name))
            names = [spelling for spelling, _ in enum.values.values()] if enum else []
            values = [_enum_value(analysis, base.name, n) for n in names]
            return [value for value in values if value is not None]
        return []
    base = value_type(base)
    if isinstance(base, StructType) and key(base.name) in resolved.structs:
        info = resolved.structs[key(base.name)]
        return [variable_symbol(v, info.name) for v in info.members]
    if isinstance(base, FbType) and key(base.name) in resolved.pous:
        block = resolved.pous[key(base.name)]
        found = [
            variable_symbol(v, block.name)
            for v in block.variables
            if v.kind not in _HIDDEN_MEMBERS and v.kind != "STEP"
        ]
        found += [method_symbol(m, block.name) for _, m in sorted(block.methods.items())]
        found += [property_symbol(p, block.name) for _, p in sorted(block.properties.items())]
        return found
    if isinstance(base, InterfaceType) and key(base.name) in resolved.interfaces:
        interface = resolved.interfaces[key(base.name)]
        return [
            *(method_symbol(m, interface.name) for _, m in sorted(interface.methods.items())),
            *(property_symbol(p, interface.name) for _, p in sorted(interface.properties.items())),
        ]
    return []


def member(analysis: Analysis, base: Type | Symbol, name: str) -> Symbol | None:
    return next((m for m in members(analysis, base) if key(m.name) == key(name)), None)


def variable_symbol(variable: Variable, owner: str) -> Symbol:
    owner = "" if variable.kind == "VAR_GLOBAL" else owner
    return Symbol(
        "variable", variable.name, variable.pos, owner, variable.kind, variable.type, variable
    )


def method_symbol(method: PouSymbols, owner: str) -> Symbol:
    return Symbol(
        "method", method.name, method.pou.pos, owner, "METHOD", method.return_type, None, method
    )


def property_symbol(prop: PropertyInfo, owner: str) -> Symbol:
    return Symbol("property", prop.name, prop.pos, owner, "PROPERTY", prop.type)


def pou_symbol(analysis: Analysis, pou: PouSymbols) -> Symbol:
    declared = name_pos(analysis, pou.pou.pos, pou.name)
    return Symbol("pou", pou.name, declared, "", pou.kind, pou.return_type, None, pou)


def type_symbol(analysis: Analysis, decl: ast.TypeDecl) -> Symbol:
    resolved = analysis.resolved
    found: Type | None = None
    detail = "alias"
    if key(decl.name) in resolved.structs:
        found, detail = StructType(resolved.structs[key(decl.name)].name), "STRUCT"
    elif key(decl.name) in resolved.enums:
        found, detail = resolved.enums[key(decl.name)].type, "enum"
    return Symbol("type", decl.name, decl.pos, "", detail, found)


def name_pos(analysis: Analysis, pos: Pos, name: str) -> Pos:
    """Where the name of a declaration that starts at `pos` with a keyword stands (a POU's
    pos is its keyword's); `pos` itself when the file is not the project's."""
    text = analysis.texts.get(pos.file)
    if text is None:
        return pos
    lexed, before = piece_at(text, pos.line)
    start = lexed.index_at(pos.line - before, pos.col)
    for token in lexed.tokens[start : start + 8]:
        if token.kind == "ident" and token.upper == key(name):
            return Pos(pos.file, token.line + before, token.col)
    return pos


def current_declaration(analysis: Analysis, symbol: Symbol) -> Pos | None:
    """Where the symbol's declaration stands in the text as it is now. The analysis may
    be older than the text (the last one that resolved, while a line is typed): when the
    name is no longer at its place, the declaration of that name nearest to it."""
    pos = symbol.declared
    text = analysis.texts.get(pos.file) if pos is not None else None
    if pos is None or text is None:
        return pos
    lexed, before = piece_at(text, pos.line)
    index = lexed.index_at(pos.line - before, pos.col)
    token = lexed.tokens[index] if index < len(lexed.tokens) else None
    wanted = key(symbol.name)
    if token is not None and (token.line + before, token.col, token.upper) == (
        pos.line,
        pos.col,
        wanted,
    ):
        return pos
    candidates = [
        (abs(found.line + offset - pos.line), found.line + offset, found.col)
        for piece, offset in pieces(text)
        for number, found in enumerate(piece.tokens)
        if found.upper == wanted and _declares(piece, number)
    ]
    if not candidates:
        return pos
    _, line, col = min(candidates)
    return Pos(pos.file, line, col)


def _declares(lexed: Lexed, index: int) -> bool:
    """Whether the name token `index` is declared there: `name :`, `name,` at a statement's
    start, or the name after PROGRAM, METHOD, TYPE...."""
    tokens = lexed.tokens
    after = tokens[index + 1].text if index + 1 < len(tokens) else ""
    before = tokens[index - 1] if index > 0 else None
    if before is not None and before.upper in _NAMING_KEYWORDS:
        return True
    return after in (":", ",") and (
        before is None or before.text in (";", ",") or before.upper in VAR_KINDS
    )


def _block(scope: PouSymbols | None) -> PouSymbols | None:
    """The PROGRAM or FUNCTION_BLOCK whose methods and properties a scope sees."""
    if scope is None:
        return None
    if scope.outer is not None:
        return scope.outer
    return scope if scope.kind in ("PROGRAM", "FUNCTION_BLOCK") else None


def _variable_owner(scope: PouSymbols | None, variable: Variable) -> str:
    if scope is None:
        return ""
    if scope.outer is not None:
        if scope.by_key.get(key(variable.name)) is variable:
            return f"{scope.outer.name}.{scope.name}"
        return scope.outer.name
    return scope.name


def _result_owner(analysis: Analysis, scope: PouSymbols) -> Symbol:
    """A function's, method's or property getter's name in its own body: its result,
    which is named (and renamed) with it."""
    outer = scope.outer
    if outer is not None:
        for name, prop in outer.properties.items():
            if prop.getter is scope or (key(scope.name) == name and scope.method is None):
                return property_symbol(prop, outer.name)
        return method_symbol(scope, outer.name)
    if scope.kind == "METHOD":  # an interface's prototype
        return method_symbol(scope, scope.declared_in)
    return pou_symbol(analysis, scope)


def _enum_value(analysis: Analysis, type_name: str, value: str) -> Symbol | None:
    info = analysis.resolved.enums.get(key(type_name))
    if info is None or key(value) not in info.values:
        return None
    spelling = info.values[key(value)][0]
    declared = _index(analysis).enum_values.get((key(type_name), key(value)))
    return Symbol("enum_value", spelling, declared, info.type.name, "enum value", info.type)


def _declared_in_type(place: _Place, index: int) -> Symbol | None:
    """A structure's member or an enum's value where its TYPE declares it."""
    tokens = place.lexed.tokens
    token = tokens[index]
    spans = place.lexed.innermost(token.line, token.col, frozenset({"TYPE", "STRUCT"}))
    if not spans:
        return None
    resolved = place.analysis.resolved
    innermost = spans[-1]
    after = tokens[index + 1].text if index + 1 < len(tokens) else ""
    if innermost.kind == "STRUCT" and after in (":", ","):
        info = resolved.structs.get(key(innermost.name))
        found = info.by_key.get(key(token.text)) if info is not None else None
        return variable_symbol(found, info.name) if found is not None and info else None
    opening = _open_parenthesis(place.lexed, index)
    if innermost.kind == "TYPE" and opening >= 2 and tokens[opening - 1].text == ":":
        return _enum_value(place.analysis, tokens[opening - 2].text, token.text)
    return None


def base_before(
    analysis: Analysis, file: str, lexed: Lexed, dot: int, line_offset: int = 0
) -> Type | Symbol | None:
    """What the expression before the `.` that is token `dot` is, as the base of a member
    (see `members`), or None when that is not known."""
    token = lexed.tokens[dot]
    scope = scope_at(analysis, lexed, token.line, token.col)
    return _expression_base(_Place(analysis, file, lexed, scope, line_offset), dot - 1, 0)


def _expression_base(place: _Place, index: int, depth: int) -> Type | Symbol | None:
    """What the expression that ends with token `index` is, as the base of a member:
    its type, or an enum type or `SYS` (whose members are named after a dot)."""
    if depth > _MAX_CHAIN or index < 0:
        return None
    tokens = place.lexed.tokens
    token = tokens[index]
    if token.text == "^":
        base = _expression_base(place, index - 1, depth + 1)
        if isinstance(base, RefType):
            return base.target
        if isinstance(base, Symbol) and base.kind == "self":
            return base.type
        return None
    if token.text == "]":
        opening = _matching(place.lexed, index, "[", "]")
        base = _expression_base(place, opening - 1, depth + 1) if opening > 0 else None
        if isinstance(base, Type) and isinstance(value_type(base), ArrayType | OpenArrayType):
            element = value_type(base)
            assert isinstance(element, ArrayType | OpenArrayType)
            return element.element
        return None
    if token.text == ")":
        opening = _matching(place.lexed, index, "(", ")")
        if opening < 1 or not tokens[opening - 1].is_name():
            return None
        called = _token_symbol(place, opening - 1, depth + 1)
        if (
            called is not None
            and called.kind in ("method", "pou")
            and called.detail != "FUNCTION_BLOCK"
        ):
            return called.type
        return None
    if token.kind != "ident":
        return None
    if token.upper in ("THIS", "SUPER"):
        block = _block(place.scope)
        if block is None:
            return None
        target = (
            block if token.upper == "THIS" else place.analysis.resolved.pous.get(block.base or "")
        )
        if target is None:
            return None
        return Symbol("self", token.upper, None, "", "", FbType(target.name))
    symbol = _token_symbol(place, index, depth + 1)
    if symbol is None:
        return None
    if symbol.kind in ("type", "namespace"):
        return symbol
    return symbol.type


def _parameter(place: _Place, call: int, name: str, depth: int) -> Symbol | None:
    """The parameter `name` of what the call whose `(` is token `call` calls."""
    callee = _callee(place, call, depth)
    found = callee.by_key.get(key(name)) if callee is not None else None
    if callee is None or found is None or found.kind not in PARAMETER_KINDS:
        return None
    owner = callee.name if callee.outer is None else f"{callee.outer.name}.{callee.name}"
    return variable_symbol(found, owner)


def call_around(
    analysis: Analysis, file: str, lexed: Lexed, index: int, line_offset: int = 0
) -> PouSymbols | None:
    """The function, function block or method whose argument list token `index` (or the
    end of the text) stands in, if that is known."""
    call = _open_call(lexed, index)
    if call is None:
        return None
    token = lexed.tokens[call]
    scope = scope_at(analysis, lexed, token.line, token.col)
    return _callee(_Place(analysis, file, lexed, scope, line_offset), call, 0)


def _callee(place: _Place, call: int, depth: int) -> PouSymbols | None:
    """What the call whose `(` is token `call` calls: a POU, a method, the block of an
    instance."""
    tokens = place.lexed.tokens
    if call < 1:
        return None
    if tokens[call - 1].is_name():
        called = _token_symbol(place, call - 1, depth + 1)
        if called is not None and called.block is not None:
            return called.block
        if called is not None and isinstance(called.type, FbType):
            return place.analysis.resolved.pous.get(key(called.type.name))
        return None
    base = _expression_base(place, call - 1, depth + 1)
    if isinstance(base, FbType):
        return place.analysis.resolved.pous.get(key(base.name))
    return None


def _open_parenthesis(lexed: Lexed, index: int) -> int:
    """The index of the `(` or `[` not closed before token `index` in its statement; -1."""
    depth = 0
    tokens = lexed.tokens
    for i in range(index - 1, max(index - 400, -1), -1):
        text = tokens[i].text
        if text in (")", "]"):
            depth += 1
        elif text in ("(", "["):
            if depth == 0:
                return i
            depth -= 1
        elif text == ";" or tokens[i].upper in ("THEN", "DO", "ELSE", "OF", "REPEAT"):
            return -1
    return -1


def _open_call(lexed: Lexed, index: int) -> int | None:
    """The index of the `(` of the call whose argument list token `index` stands in."""
    opening = _open_parenthesis(lexed, index)
    if opening < 1 or lexed.tokens[opening].text != "(":
        return None
    before = lexed.tokens[opening - 1]
    return opening if before.is_name() or before.text == "]" else None


def _in_parentheses(lexed: Lexed, index: int) -> bool:
    return _open_parenthesis(lexed, index) >= 0


def _matching(lexed: Lexed, index: int, opening: str, closing: str) -> int:
    """The index of the `opening` that the `closing` at `index` closes; -1."""
    depth = 0
    for i in range(index, max(index - 400, -1), -1):
        text = lexed.tokens[i].text
        if text == closing:
            depth += 1
        elif text == opening:
            depth -= 1
            if depth == 0:
                return i
    return -1


@dataclass(frozen=True)
class _Index:
    """Declarations the symbol tables keep no place of: types by key, and where each
    enum value is declared."""

    types: dict[str, ast.TypeDecl]
    enum_values: dict[tuple[str, str], Pos]


_indexed: list[tuple[Analysis, _Index]] = []  # the last analysis asked about, and its index


def _index(analysis: Analysis) -> _Index:
    if _indexed and _indexed[0][0] is analysis:
        return _indexed[0][1]
    types: dict[str, ast.TypeDecl] = {}
    enum_values: dict[tuple[str, str], Pos] = {}
    for unit in analysis.units:
        for decl in unit.types:
            types.setdefault(key(decl.name), decl)
            if isinstance(decl.spec, ast.EnumSpec):
                for value, _, pos in decl.spec.values:
                    enum_values.setdefault((key(decl.name), key(value)), pos)
    index = _Index(types, enum_values)
    _indexed[:] = [(analysis, index)]
    return index
