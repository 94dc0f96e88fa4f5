"""Stage 1, parse: ST source text -> `ast.SourceUnit`, or diagnostics.

A lark LALR(1) parser with the contextual lexer (fast, and deterministic); the tree it
builds is turned into typed AST dataclasses right away so that no later stage sees lark.
"""

from __future__ import annotations

import datetime
import functools
import re
import threading
from collections.abc import Sequence
from dataclasses import dataclass, replace
from importlib import resources
from typing import Any

from lark import Lark, Token, Transformer, Tree, v_args
from lark.exceptions import (
    UnexpectedCharacters,
    UnexpectedEOF,
    UnexpectedInput,
    UnexpectedToken,
    VisitError,
)

from backend.compiler import ast
from backend.compiler.codes import Code
from backend.compiler.diagnostics import CompileError, Diagnostic
from backend.compiler.graphics.context import context_of
from backend.compiler.graphics.lower import Context, Lowered, lower, temporaries_block
from backend.compiler.graphics.model import GraphicBody
from backend.compiler.graphics.text_form import read_body
from backend.compiler.limits import (
    MAX_BRANCH_DEPTH,
    MAX_COMMENT_NESTING,
    MAX_DATA_DEPTH,
    MAX_EXPRESSION_DEPTH,
    MAX_LOOP_DEPTH,
    MAX_NUMBER_LITERAL,
    MAX_PROJECT_TOKENS,
    MAX_STATEMENT_DEPTH,
    MAX_STRING_LITERAL,
)
from backend.compiler.source import Pos
from runtime.contract.values import parse_time_literal


@functools.cache
def _parser() -> Lark:
    grammar = resources.files("backend.compiler").joinpath("grammar.lark").read_text()
    grammar = grammar.replace("NESTED_COMMENT_PATTERN", nested_comment(MAX_COMMENT_NESTING))
    # cache=True keeps the built LALR tables in the temp folder: `padt` starts in a fraction;
    # the pragma callback reports skipped pragmas (lark drops ignored tokens otherwise)
    return Lark(
        grammar,
        parser="lalr",
        lexer="contextual",
        propagate_positions=True,
        cache=True,
        lexer_callbacks={"PRAGMA": _PRAGMAS.append},
    )


def nested_comment(depth: int) -> str:
    """A regular expression for `(* ... *)` holding comments nested up to `depth` levels.
    Each level reads runs of other characters, a `(` or `*` that opens or closes nothing,
    or a comment one level down; the possessive repeats keep no backtracking state, so
    memory stays constant however long the comment."""
    pattern = r"\(\*(?:[^(*]++|\((?!\*)|\*(?!\)))*+\*\)"
    for _ in range(depth):
        pattern = rf"\(\*(?:[^(*]++|\((?!\*)|\*(?!\))|{pattern})*+\*\)"
    return pattern


# Pragmas seen by the lexer during the current parse (the parser is built once, so its
# callback needs a module-level list; a parse resets and reads it, holding _LEXING, since
# the language services parse from several threads).
_PRAGMAS: list[Token] = []
_LEXING = threading.Lock()


_EPOCH = datetime.datetime(1970, 1, 1)
_DATE_KINDS = {
    "D": "DATE", "DATE": "DATE", "LD": "LDATE", "LDATE": "LDATE",
    "DT": "DT", "DATE_AND_TIME": "DT", "LDT": "LDT", "LDATE_AND_TIME": "LDT",
    "TOD": "TOD", "TIME_OF_DAY": "TOD", "LTOD": "LTOD", "LTIME_OF_DAY": "LTOD",
}  # fmt: skip
# TIME_TO_STRING and friends print these prefixes
DATE_PREFIXES = {"DATE": "D#", "LDATE": "LDATE#", "TOD": "TOD#", "LTOD": "LTOD#", "DT": "DT#",
                 "LDT": "LDT#"}  # fmt: skip


def parse_date_literal(text: str) -> tuple[str, int]:
    """`D#2024-01-31`, `TOD#12:00:00.5`, `DT#2024-01-31-12:00:00` -> (type, ns since epoch or
    since midnight)."""
    prefix, _, body = text.partition("#")
    kind = _DATE_KINDS[prefix.upper()]
    if kind in ("TOD", "LTOD"):
        return kind, _clock_ns(body)
    parts = body.split("-")
    day = datetime.datetime(int(parts[0]), int(parts[1]), int(parts[2]))
    ns = (day - _EPOCH) // datetime.timedelta(microseconds=1) * 1000
    if len(parts) > 3:
        ns += _clock_ns(parts[3])
    return kind, ns


def _clock_ns(text: str) -> int:
    """`12:30:05.25` -> nanoseconds since midnight; digits below 1 ns are cut off."""
    hours, minutes, *rest = text.split(":")
    whole, _, fraction = (rest[0] if rest else "0").partition(".")
    seconds = (int(hours) * 60 + int(minutes)) * 60 + int(whole)
    return seconds * 1_000_000_000 + int((fraction + "000000000")[:9])


def parse_int_literal(text: str) -> int:
    text = text.replace("_", "")
    if "#" in text:
        base, _, digits = text.partition("#")
        if not digits:
            raise ValueError(f"no digits after '{base}#'")
        return int(digits, int(base))
    return int(text)


class BadEscape(ValueError):
    """A `$` escape that IEC 61131-3 does not define."""


def decode_string_literal(text: str, wide: bool = False) -> str:
    """Decode the `$` escapes of an ST string literal (without the quotes): `$N`, `$$`,
    `$'`, ... and `$hh` (STRING) or `$hhhh` (WSTRING) character codes."""
    digits = 4 if wide else 2
    out: list[str] = []
    i = 0
    escapes = {"N": "\n", "L": "\n", "R": "\r", "T": "\t", "P": "\f", "$": "$", "'": "'"}
    while i < len(text):
        ch = text[i]
        if ch == "$" and i + 1 < len(text):
            nxt = text[i + 1]
            if nxt.upper() in escapes:
                out.append(escapes[nxt.upper()])
                i += 2
                continue
            if nxt == '"' and wide:
                out.append('"')
                i += 2
                continue
            hex_digits = text[i + 1 : i + 1 + digits]
            if re.fullmatch(f"[0-9A-Fa-f]{{{digits}}}", hex_digits):
                out.append(chr(int(hex_digits, 16)))
                i += 1 + digits
                continue
            raise BadEscape(f"invalid escape '${nxt}' in string literal")
        if ch == "$":
            raise BadEscape("a string literal cannot end with '$'")
        out.append(_source_char(ch, wide))
        i += 1
    return "".join(out)


def _source_char(ch: str, wide: bool) -> str:
    """A character written in the (UTF-8) source: a STRING holds its UTF-8 bytes, one
    character per byte; a WSTRING its UTF-16 code units."""
    if ord(ch) < 128:
        return ch
    if wide:
        units = ch.encode("utf-16-le", "surrogatepass")
        return "".join(
            chr(int.from_bytes(units[i : i + 2], "little")) for i in range(0, len(units), 2)
        )
    return ch.encode("utf-8").decode("latin-1")


# The longest literal of each kind, as written (strings between their quotes), and what a
# longer one is read as. CPython refuses integers of more than 4,300 digits.
_LITERAL_LIMITS = {
    "INTEGER": (MAX_NUMBER_LITERAL, "0"),
    "BASED_INTEGER": (MAX_NUMBER_LITERAL, "2#0"),
    "REAL_NUMBER": (MAX_NUMBER_LITERAL, "0.0"),
    "TIME_LITERAL": (MAX_NUMBER_LITERAL, "T#0s"),
    "DATE_LITERAL": (MAX_NUMBER_LITERAL, "D#1970-01-01"),
    "STRING_LITERAL": (MAX_STRING_LITERAL, "''"),
    "WSTRING_LITERAL": (MAX_STRING_LITERAL, '""'),
}


def _children(tree: Tree[Any]) -> list[Any]:
    """A transformed node's children: AST nodes by now, which lark's types cannot know."""
    return list(tree.children)


@dataclass(frozen=True)
class _ActionsBlock:
    """`ACTIONS [pou] ... END_ACTIONS`: actions declared after the POU they belong to."""

    owner: str | None  # None: the POU right before the block
    actions: tuple[ast.Action, ...]
    pos: Pos


def _with_actions_blocks(items: list[Any]) -> tuple[list[Any], list[Diagnostic]]:
    """The file's items with each ACTIONS block's actions moved into the PROGRAM or
    FUNCTION_BLOCK of the same file that it names (or that comes right before it)."""
    result: list[Any] = []
    errors: list[Diagnostic] = []
    for item in items:
        if isinstance(item, ast.Method | ast.Property):
            errors.extend(_attach_member(result, item))
            continue
        if not isinstance(item, _ActionsBlock):
            result.append(item)
            continue
        pous = [(i, p) for i, p in enumerate(result) if isinstance(p, ast.Pou)]
        if item.owner is None:
            owner = pous[-1:] if result and isinstance(result[-1], ast.Pou) else []
        else:
            owner = [(i, p) for i, p in pous if ast.key(p.name) == ast.key(item.owner)]
        if not owner or owner[0][1].kind == "FUNCTION":
            named = f" of '{item.owner}'" if item.owner else ""
            message = f"these ACTIONS{named} follow no PROGRAM or FUNCTION_BLOCK of this file"
            errors.append(Diagnostic.at(item.pos, Code.ACTIONS_OWNER, message))
            continue
        index, pou = owner[0]
        sfc = pou.sfc or ast.Sfc((), (), ())
        result[index] = replace(pou, sfc=replace(sfc, actions=sfc.actions + item.actions))
    return result, errors


@dataclass(frozen=True)
class _Clause:
    """`EXTENDS A, B` or `IMPLEMENTS I1, I2` of a declaration."""

    keyword: str
    names: tuple[str, ...]


def _attach_member(result: list[Any], member: ast.Method | ast.Property) -> list[Diagnostic]:
    """A METHOD or PROPERTY after END_FUNCTION_BLOCK, END_PROGRAM or END_INTERFACE (the
    text form of TwinCAT): a member of the last block or interface before it."""
    owners = [
        i
        for i, item in enumerate(result)
        if isinstance(item, ast.Interface)
        or (isinstance(item, ast.Pou) and item.kind != "FUNCTION")
    ]
    if not owners:
        kind = "method" if isinstance(member, ast.Method) else "property"
        message = f"{kind} '{member.name}' follows no FUNCTION_BLOCK, PROGRAM or INTERFACE"
        return [Diagnostic.at(member.pos, Code.MEMBER_OWNER, message)]
    owner = result[owners[-1]]
    if isinstance(member, ast.Method):
        result[owners[-1]] = replace(owner, methods=(*owner.methods, member))
    else:
        result[owners[-1]] = replace(owner, properties=(*owner.properties, member))
    return []


class _ToAst(Transformer[Token, Any]):
    """Bottom-up conversion of the lark tree into AST nodes."""

    def __init__(self, file: str, line_offset: int = 0) -> None:
        super().__init__()
        self.file = file
        self.line_offset = line_offset  # lines of the file before the text parsed
        self.errors: list[Diagnostic] = []
        self.addresses: list[tuple[str, Pos]] = []
        self.warnings: list[Diagnostic] = []  # the dialect extensions met (W08xx)

    def _pos(self, item: Any) -> Pos:
        if isinstance(item, Token):
            return Pos(self.file, (item.line or 0) + self.line_offset, item.column or 0)
        return Pos(self.file, item.meta.line + self.line_offset, item.meta.column)

    def _declared(self, name: Token) -> str:
        """A name being declared. IEC 61131-3 forbids two underscores in a row and one at
        the end; padt needs both free: generated code names its own things with `__`, and
        a Python keyword used as a name becomes the name with `_` appended."""
        text = str(name)
        if "__" in text or text.endswith("_"):
            message = f"'{text}': an identifier has no two underscores in a row, none at its end"
            self.errors.append(Diagnostic.at(self._pos(name), Code.IDENTIFIER, message))
        return text

    # ---- literals
    def _literal(self, token: Token) -> Token:
        """A literal token as written; one too long is reported and read as a harmless
        stand-in, so that the rest of the file is still checked."""
        limit, stand_in = _LITERAL_LIMITS[token.type]
        quoted = token.type in ("STRING_LITERAL", "WSTRING_LITERAL")
        length = len(token) - 2 if quoted else len(token)
        if length <= limit:
            return token
        message = f"literal of {length:,} characters; at most {limit:,}"
        self.errors.append(Diagnostic.at(self._pos(token), Code.LITERAL_LENGTH, message))
        return Token.new_borrow_pos(token.type, stand_in, token)

    # lark passes every token of these terminals through `_literal` before the rules see it
    INTEGER = BASED_INTEGER = REAL_NUMBER = TIME_LITERAL = DATE_LITERAL = _literal
    STRING_LITERAL = WSTRING_LITERAL = _literal

    def _integer(self, token: Token) -> int:
        value = parse_int_literal(str(token))
        try:
            float(value)  # REAL#n and n in REAL arithmetic become floats
        except OverflowError:
            raise ValueError("a number beyond the range of LREAL") from None
        return value

    def int_literal(self, items: list[Token]) -> ast.IntLiteral:
        token = items[0]
        based = token.type == "BASED_INTEGER"
        return ast.IntLiteral(self._integer(token), self._pos(token), based=based)

    def real_literal(self, items: list[Token]) -> ast.RealLiteral:
        text = str(items[0]).replace("_", "")
        return ast.RealLiteral(float(text), text, self._pos(items[0]))

    def bool_literal(self, items: list[Token]) -> ast.BoolLiteral:
        return ast.BoolLiteral(str(items[0]).upper() == "TRUE", self._pos(items[0]))

    def time_literal(self, items: list[Token]) -> ast.TimeLiteral:
        ns, long = parse_time_literal(str(items[0]))
        if not -(1 << 63) <= ns < 1 << 63:
            raise ValueError("a duration beyond the 64-bit range of LTIME")
        return ast.TimeLiteral(ns, "LTIME" if long else "TIME", self._pos(items[0]))

    def date_literal(self, items: list[Token]) -> ast.TimeLiteral:
        type_name, ns = parse_date_literal(str(items[0]))
        return ast.TimeLiteral(ns, type_name, self._pos(items[0]))

    def _decode(self, token: Token, wide: bool) -> str:
        try:
            return decode_string_literal(str(token)[1:-1], wide)
        except BadEscape as exc:
            self.errors.append(Diagnostic.at(self._pos(token), Code.STRING_ESCAPE, str(exc)))
            return ""

    def string_literal(self, items: list[Token]) -> ast.StringLiteral:
        return ast.StringLiteral(self._decode(items[0], False), False, self._pos(items[0]))

    def wstring_literal(self, items: list[Token]) -> ast.StringLiteral:
        return ast.StringLiteral(self._decode(items[0], True), True, self._pos(items[0]))

    def typed_literal(self, items: list[Token]) -> ast.Expr:
        prefix, *rest = items
        type_name = str(prefix)[:-1].upper()
        pos = self._pos(prefix)
        negative = len(rest) == 2
        token = rest[-1]
        if token.type in ("INTEGER", "BASED_INTEGER"):
            value = self._integer(token)
            based = token.type == "BASED_INTEGER"
            return ast.IntLiteral(-value if negative else value, pos, type_name, based)
        if token.type == "REAL_NUMBER":
            text = str(token).replace("_", "")
            value_f = float(text)
            return ast.RealLiteral(-value_f if negative else value_f, text, pos, type_name)
        if token.type == "BOOL_LITERAL":
            return ast.BoolLiteral(str(token).upper() == "TRUE", pos, type_name)
        wide = type_name == "WSTRING"
        return ast.StringLiteral(self._decode(token, wide), wide, pos, type_name)

    def enum_literal(self, items: list[Token]) -> ast.EnumLiteral:
        prefix, value = items
        return ast.EnumLiteral(str(prefix)[:-1], str(value), self._pos(prefix))

    def null_literal(self, items: list[Token]) -> ast.NullLiteral:
        return ast.NullLiteral(self._pos(items[0]))

    # ---- expressions
    def name_ref(self, items: list[Token]) -> ast.NameRef:
        return ast.NameRef(str(items[0]), self._pos(items[0]))

    def member_ref(self, items: list[Any]) -> ast.MemberRef:
        base, member = items
        return ast.MemberRef(base, str(member), base.pos)

    def index_ref(self, items: list[Any]) -> ast.IndexRef:
        base, *indices = items
        return ast.IndexRef(base, tuple(indices), base.pos)

    def bit_ref(self, items: list[Any]) -> ast.BitRef:
        base, part = items
        text = str(part).upper()
        if text.startswith("%"):
            width = {"X": 1, "B": 8, "W": 16, "D": 32}[text[1]]
            return ast.BitRef(base, int(text[2:]), base.pos, width)
        return ast.BitRef(base, int(text), base.pos)

    def direct_ref(self, items: list[Token]) -> ast.NameRef:
        """`%IX0.1` in code names the variable located there (resolve declares one where
        no declaration does): a name like any other, spelled as the address."""
        address, pos = str(items[0]).upper(), self._pos(items[0])
        if address.endswith("*"):
            message = f"{address} is a partly specified location: it only locates a declaration"
            self.errors.append(Diagnostic.at(pos, Code.SYNTAX, message))
        self.addresses.append((address, pos))
        return ast.NameRef(address, pos)

    def deref(self, items: list[Any]) -> ast.Deref:
        return ast.Deref(items[0], items[0].pos)

    def binary(self, items: list[Any]) -> ast.Binary:
        left, op, right = items
        return ast.Binary(str(op).upper(), left, right, self._pos(op))

    def unary(self, items: list[Any]) -> ast.Unary:
        op, operand = items
        return ast.Unary(str(op).upper(), operand, self._pos(op))

    def named_input(self, items: list[Any]) -> ast.Argument:
        name, value = items
        return ast.Argument(str(name), value, False, self._pos(name))

    def named_output(self, items: list[Any]) -> ast.Argument:
        name, _arrow, *target = items
        return ast.Argument(str(name), target[0] if target else None, True, self._pos(name))

    def negated_output(self, items: list[Any]) -> ast.Argument:
        _not, name, _arrow, target = items
        return ast.Argument(str(name), target, True, self._pos(name), negated=True)

    def positional_arg(self, items: list[Any]) -> ast.Argument:
        return ast.Argument(None, items[0], False, items[0].pos)

    def _arguments(self, items: list[Any]) -> tuple[ast.Argument, ...]:
        """The arguments of a call, without the trailing comma of CODESYS (reported)."""
        for item in items:
            if isinstance(item, Token) and item.type == "COMMA":
                message = "a comma after the last argument is CODESYS/TwinCAT, not IEC 61131-3"
                self.warnings.append(Diagnostic.at(self._pos(item), Code.TRAILING_COMMA, message))
        return tuple(a for a in items if isinstance(a, ast.Argument))

    def call(self, items: list[Any]) -> ast.Call:
        name, *args = items
        return ast.Call(str(name), self._arguments(args), self._pos(name))

    def keyword_call(self, items: list[Any]) -> ast.Call:
        keyword, *args = items
        name = str(keyword).rstrip("( \t\r\n")
        return ast.Call(name, self._arguments(args), self._pos(keyword))

    def method_call(self, items: list[Any]) -> ast.Call:
        receiver, name, *args = items
        return ast.Call(str(name), self._arguments(args), self._pos(name), receiver=receiver)

    def instance_call(self, items: list[Any]) -> ast.Call:
        instance, *args = items
        name = ast.spelling(instance)
        return ast.Call(name, self._arguments(args), instance.pos, instance=instance)

    def trailing_comma(self, items: list[Token]) -> Token:
        return items[0]

    # ---- initializers
    @v_args(tree=True)
    def array_initializer(self, tree: Tree[Any]) -> ast.ArrayInit:
        items: list[tuple[ast.Expr | None, Any]] = []
        for child in _children(tree):
            if child is None:
                continue
            if isinstance(child, tuple) and child and child[0] == "REPEAT":
                items.append((child[1], child[2]))
            else:
                items.append((None, child))
        return ast.ArrayInit(tuple(items), self._pos(tree))

    def repeated_init(self, items: list[Any]) -> tuple[str, ast.Expr, Any]:
        count, *values = [i for i in items if i is not None]
        if len(values) == 1:
            return ("REPEAT", count, values[0])
        # `n(a, b)` repeats a group: an array initializer of its own, flattened later
        return ("REPEAT", count, ast.ArrayInit(tuple((None, v) for v in values), count.pos))

    @v_args(tree=True)
    def struct_initializer(self, tree: Tree[Any]) -> ast.StructInit:
        return ast.StructInit(tuple(_children(tree)), self._pos(tree))

    def member_init(self, items: list[Any]) -> tuple[str, Any]:
        return (str(items[0]), items[1])

    # ---- statements
    @v_args(tree=True)
    def assignment(self, tree: Tree[Any]) -> ast.Assign:
        target, value = _children(tree)
        return ast.Assign(target, value, self._pos(tree))

    @v_args(tree=True)
    def set_reset_assignment(self, tree: Tree[Any]) -> ast.If:
        """CODESYS `x S= c;` is `IF c THEN x := TRUE; END_IF`, `x R= c;` the same with
        FALSE: written so, every later stage checks and runs it as IEC code."""
        target, operator, condition = _children(tree)
        setting = str(operator).upper().startswith("S")
        pos = self._pos(tree)
        message = f"'{str(operator).upper()}' is CODESYS/TwinCAT, not IEC 61131-3"
        self.warnings.append(Diagnostic.at(pos, Code.SET_RESET_ASSIGNMENT, message))
        store = ast.Assign(target, ast.BoolLiteral(setting, self._pos(operator)), pos)
        return ast.If(((condition, (store,)),), (), pos)

    @v_args(tree=True)
    def ref_assignment(self, tree: Tree[Any]) -> ast.Assign:
        """CODESYS `r REF= x;`: r (a REFERENCE TO) refers to x from now on; held as the
        assignment of REF(x) to the reference itself. `r REF= 0;` makes r refer to nothing
        (NULL); another number is REF of a number, which the checks refuse."""
        target, _operator, referenced = _children(tree)
        pos = self._pos(tree)
        if isinstance(referenced, Token):
            number = ast.IntLiteral(int(referenced.replace("_", "")), self._pos(referenced))
            if number.value == 0:
                return ast.Assign(target, ast.NullLiteral(number.pos), pos, bind=True)
            referenced = number
        argument = ast.Argument(None, referenced, False, referenced.pos)
        return ast.Assign(target, ast.Call("REF", (argument,), referenced.pos), pos, bind=True)

    def call_statement(self, items: list[Any]) -> ast.CallStatement | ast.ExprStatement:
        expr = items[0]
        if isinstance(expr, ast.Call):
            return ast.CallStatement(expr, expr.pos)
        return ast.ExprStatement(expr, _start(expr))

    def statement_list(self, items: list[Any]) -> tuple[ast.Statement, ...]:
        return tuple(s for s in items if s is not None)

    def empty_statement(self, items: list[Any]) -> None:
        return None

    @v_args(tree=True)
    def continue_statement(self, tree: Tree[Any]) -> ast.Continue:
        return ast.Continue(self._pos(tree))

    @v_args(tree=True)
    def case_statement(self, tree: Tree[Any]) -> ast.Case:
        selector, *parts = _children(tree)
        orelse: tuple[ast.Statement, ...] = ()
        branches: list[tuple[tuple[Any, ...], list[ast.Statement]]] = []
        for part in parts:
            if isinstance(part, tuple) and part and part[0] == "ELSE":
                orelse = part[1]
            elif isinstance(part, tuple) and part and part[0] == "LABELS":
                branches.append((part[1], []))
            elif part is not None and branches:
                branches[-1][1].append(part)
        grouped = tuple((labels, tuple(body)) for labels, body in branches)
        return ast.Case(selector, grouped, orelse, self._pos(tree))

    def case_labels(self, items: list[Any]) -> tuple[str, tuple[Any, ...]]:
        return ("LABELS", tuple(items))

    def case_range(self, items: list[Any]) -> ast.CaseRange:
        low, high = items
        return ast.CaseRange(low, high, low.pos)

    @v_args(tree=True)
    def return_statement(self, tree: Tree[Any]) -> ast.Return:
        return ast.Return(self._pos(tree))

    @v_args(tree=True)
    def exit_statement(self, tree: Tree[Any]) -> ast.Exit:
        return ast.Exit(self._pos(tree))

    @v_args(tree=True)
    def if_statement(self, tree: Tree[Any]) -> ast.If:
        cond, body, *rest = _children(tree)
        branches = [(cond, body)]
        orelse: tuple[ast.Statement, ...] = ()
        for clause in rest:
            if isinstance(clause, tuple) and clause and clause[0] == "ELSIF":
                branches.append((clause[1], clause[2]))
            elif isinstance(clause, tuple) and clause and clause[0] == "ELSE":
                orelse = clause[1]
        return ast.If(tuple(branches), orelse, self._pos(tree))

    def elsif_clause(self, items: list[Any]) -> tuple[str, ast.Expr, tuple[ast.Statement, ...]]:
        return ("ELSIF", items[0], items[1])

    def else_clause(self, items: list[Any]) -> tuple[str, tuple[ast.Statement, ...]]:
        return ("ELSE", items[0])

    @v_args(tree=True)
    def while_statement(self, tree: Tree[Any]) -> ast.While:
        cond, body = _children(tree)
        return ast.While(cond, body, self._pos(tree))

    @v_args(tree=True)
    def repeat_statement(self, tree: Tree[Any]) -> ast.Repeat:
        body, until = _children(tree)
        return ast.Repeat(body, until, self._pos(tree))

    @v_args(tree=True)
    def for_statement(self, tree: Tree[Any]) -> ast.For:
        children = _children(tree)
        name, start, stop = children[0], children[1], children[2]
        body = children[-1]
        step = children[3] if len(children) == 5 else None
        return ast.For(str(name), start, stop, step, body, self._pos(tree))

    # ---- declarations
    def named_type(self, items: list[Token]) -> ast.NamedType:
        # `Tc2_System.T_MaxString` keeps its qualifier: qualified_names resolves it
        return ast.NamedType(".".join(str(i) for i in items), self._pos(items[0]))

    def type_name(self, items: list[Token]) -> str:
        return ".".join(str(i) for i in items)

    def string_type(self, items: list[Any]) -> ast.StringType:
        kw = items[0]
        length = items[1] if len(items) > 1 else None
        return ast.StringType(str(kw).upper() == "WSTRING", length, self._pos(kw))

    @v_args(tree=True)
    def array_type(self, tree: Tree[Any]) -> ast.ArrayType:
        *ranges, element = _children(tree)
        return ast.ArrayType(tuple(ranges), element, self._pos(tree))

    def array_range(self, items: list[Any]) -> tuple[ast.Expr, ast.Expr]:
        return (items[0], items[1])

    def open_range(self, items: list[Any]) -> None:
        return None

    def variadic_type(self, items: list[Token]) -> ast.VariadicType:
        return ast.VariadicType(self._pos(items[0]))

    def ref_type(self, items: list[Any]) -> ast.RefType:
        pointer, implicit = items[0].type == "POINTER_TO", items[0].type == "REFERENCE_TO"
        return ast.RefType(items[1], self._pos(items[0]), pointer, implicit)

    @v_args(tree=True)
    def enum_spec(self, tree: Tree[Any]) -> ast.EnumSpec:
        children = _children(tree)
        base = None
        # the base type may stand before `(` (rusty, CODESYS 3) or after `)` (CODESYS 2)
        names = [c for c in children if isinstance(c, Token)]
        if names:
            base = str(names[0])
        values = tuple(c for c in children if isinstance(c, tuple))
        return ast.EnumSpec(base, values, self._pos(tree))

    def enum_value(self, items: list[Any]) -> tuple[str, ast.Expr | None, Pos]:
        return (self._declared(items[0]), items[1] if len(items) > 1 else None, self._pos(items[0]))

    @v_args(tree=True)
    def struct_spec(self, tree: Tree[Any]) -> ast.StructSpec:
        members = tuple(d for group in _children(tree) for d in group)
        return ast.StructSpec(members, self._pos(tree))

    def struct_member(self, items: list[Any]) -> list[ast.VarDecl]:
        declared = self.var_decl(items)
        if declared[0].location is not None:
            # a relative location lays the member out in the structure's memory; padt's
            # structures are no memory image
            message = (
                f"'{declared[0].name}' AT {declared[0].location}: padt does not lay "
                "structure members out at locations; declare the member without AT"
            )
            self.errors.append(Diagnostic.at(declared[0].pos, Code.STRUCT_LOCATION, message))
        return declared

    def subrange_spec(self, items: list[Any]) -> ast.SubrangeSpec:
        base, low, high = items
        return ast.SubrangeSpec(str(base), low, high, self._pos(base))

    def type_decl(self, items: list[Any]) -> ast.TypeDecl:
        name, spec, *init = items
        return ast.TypeDecl(self._declared(name), spec, init[0] if init else None, self._pos(name))

    def type_block(self, items: list[Any]) -> list[ast.TypeDecl]:
        specifiers = [i for i in items if isinstance(i, Token)]
        decls = [i for i in items if isinstance(i, ast.TypeDecl)]
        if specifiers:
            self._pou_specifiers("TYPE", decls[0].name, specifiers)
        return decls

    def location(self, items: list[Token]) -> str:
        return str(items[0]).upper()

    def var_qualifier(self, items: list[Token]) -> str:
        return str(items[0]).upper()

    def var_decl(self, items: list[Any]) -> list[ast.VarDecl]:
        names = [i for i in items if isinstance(i, Token) and i.type == "NAME"]
        edges = [str(i).upper() for i in items if isinstance(i, Token) and i.type == "EDGE"]
        rest = [i for i in items if not isinstance(i, Token)]
        location = next((r for r in rest if isinstance(r, str)), None)
        typed = [r for r in rest if not isinstance(r, str)]
        type_ref = typed[0]
        init = typed[1] if len(typed) > 1 else None
        edge = edges[0] if edges else None
        return [
            ast.VarDecl(self._declared(n), type_ref, init, location, self._pos(n), edge)
            for n in names
        ]

    @v_args(meta=True)
    def unnamed_located(self, meta: Any, items: list[Any]) -> list[ast.VarDecl]:
        """`AT %IX1.1 : BOOL;`: the variable is named by its address."""
        location, type_ref, *init = items
        pos = Pos(self.file, meta.line + self.line_offset, meta.column)
        return [ast.VarDecl(location, type_ref, init[0] if init else None, location, pos)]

    def _block(self, kind: str, pos: Pos, items: list[Any]) -> ast.VarBlock:
        qualifiers = tuple(i for i in items if isinstance(i, str))
        decls = tuple(d for group in items if isinstance(group, list) for d in group)
        return ast.VarBlock(kind, qualifiers, decls, pos)

    def var_block(self, items: list[Any]) -> ast.VarBlock:
        kind = items[0]
        return self._block(str(kind).upper(), self._pos(kind), items[1:])

    @v_args(tree=True)
    def global_var_block(self, tree: Tree[Any]) -> ast.VarBlock:
        return self._block("VAR_GLOBAL", self._pos(tree), _children(tree))

    def _pou(self, kind: str, tree: Tree[Any]) -> ast.Pou:
        children = _children(tree)
        specifiers = [c for c in children if isinstance(c, Token) and c.type != "NAME"]
        name, *rest = [c for c in children if not (isinstance(c, Token) and c.type != "NAME")]
        modifiers = self._pou_specifiers(kind, str(name), specifiers)
        return_type = None
        if kind == "FUNCTION" and rest and not isinstance(rest[0], ast.VarBlock | tuple | _Clause):
            return_type, *rest = rest
        blocks = tuple(r for r in rest if isinstance(r, ast.VarBlock))
        graphic = next((r for r in rest if isinstance(r, GraphicBody)), None)
        body = next((r for r in rest if isinstance(r, tuple)), ())
        elements = [r for r in rest if isinstance(r, ast.Step | ast.Transition | ast.Action)]
        sfc = None
        if elements:
            sfc = ast.Sfc(
                tuple(e for e in elements if isinstance(e, ast.Step)),
                tuple(e for e in elements if isinstance(e, ast.Transition)),
                tuple(e for e in elements if isinstance(e, ast.Action)),
            )
        clauses = {c.keyword: c.names for c in rest if isinstance(c, _Clause)}
        return ast.Pou(
            kind, self._declared(name), return_type, blocks, body, self._pos(tree), sfc,
            methods=tuple(r for r in rest if isinstance(r, ast.Method)),
            properties=tuple(r for r in rest if isinstance(r, ast.Property)),
            extends=clauses.get("EXTENDS", ()),
            implements=clauses.get("IMPLEMENTS", ()),
            modifiers=modifiers,
            graphic=graphic,
        )  # fmt: skip

    def graphic_body(self, items: list[Token]) -> GraphicBody:
        pos = self._pos(items[0])
        body, problems = read_body(str(items[0]), self.file, pos.line, pos.col)
        self.errors += problems
        return body

    def _pou_specifiers(self, kind: str, name: str, specifiers: list[Token]) -> tuple[str, ...]:
        """The modifiers (ABSTRACT, FINAL) of a POU, an interface or a data type; its access
        specifiers are CODESYS/TwinCAT (PUBLIC, W0809) or mean PUBLIC in a project that is
        one namespace (INTERNAL, N0802); what does not apply to its kind is an error."""
        words = [str(s).upper() for s in specifiers]
        allowed = {"PUBLIC", "INTERNAL"} | (
            {"ABSTRACT", "FINAL"} if kind == "FUNCTION_BLOCK" else set()
        )
        what = "a data type" if kind == "TYPE" else f"a {kind}"
        accesses = {w for w in words if w in ("PUBLIC", "INTERNAL", "PRIVATE", "PROTECTED")}
        if len(set(words)) < len(words) or len(accesses) > 1 or {"ABSTRACT", "FINAL"} <= set(words):
            message = (
                f"'{name}' is declared {' '.join(words)}: a specifier twice, two access "
                "specifiers, or ABSTRACT with FINAL"
            )
            self.errors.append(Diagnostic.at(self._pos(specifiers[0]), Code.SPECIFIER, message))
        for token, word in zip(specifiers, words, strict=True):
            pos = self._pos(token)
            if word not in allowed:
                message = f"{word} does not apply to {what} ('{name}')"
                self.errors.append(Diagnostic.at(pos, Code.SPECIFIER, message))
            elif word == "PUBLIC":
                message = (
                    f"PUBLIC on {what} is CODESYS/TwinCAT; in IEC 61131-3 '{name}' is public "
                    "without it"
                )
                self.warnings.append(Diagnostic.at(pos, Code.PUBLIC_POU, message))
            elif word == "INTERNAL":
                message = (
                    f"INTERNAL: padt has no namespaces, a project is one, so '{name}' is "
                    "visible everywhere, as if PUBLIC"
                )
                self.warnings.append(Diagnostic.at(pos, Code.INTERNAL_POU, message))
        return tuple(w for w in words if w in ("ABSTRACT", "FINAL"))

    # ---- object orientation
    def extends_clause(self, items: list[Token]) -> _Clause:
        return _Clause("EXTENDS", tuple(str(i) for i in items))

    def implements_clause(self, items: list[Token]) -> _Clause:
        return _Clause("IMPLEMENTS", tuple(str(i) for i in items))

    def oop_specifier(self, items: list[Token]) -> Token:
        return items[0]

    @staticmethod
    def _specifiers(items: list[Any]) -> tuple[str | None, tuple[str, ...], list[Any]]:
        """(access, modifiers, the rest) of a method's or property's children."""
        access = [
            str(i).upper() for i in items if isinstance(i, Token) and i.type == "ACCESS_SPECIFIER"
        ]
        modifiers = tuple(
            str(i).upper() for i in items if isinstance(i, Token) and i.type == "OOP_MODIFIER"
        )
        rest = [
            i
            for i in items
            if not (isinstance(i, Token) and i.type in ("ACCESS_SPECIFIER", "OOP_MODIFIER"))
        ]
        return (access[0] if access else None), modifiers, rest

    def method_decl(self, items: list[Any]) -> ast.Method:
        _keyword, *items = items
        access, modifiers, (name, *rest) = self._specifiers(items)
        return_type = None
        if rest and not isinstance(rest[0], ast.VarBlock | tuple):
            return_type, *rest = rest
        blocks = tuple(r for r in rest if isinstance(r, ast.VarBlock))
        body = next(r for r in rest if isinstance(r, tuple))
        return ast.Method(
            self._declared(name), access, modifiers, return_type, blocks, body, self._pos(name)
        )

    def property_accessor(self, items: list[Any]) -> ast.Accessor:
        keyword, *rest = items
        blocks = tuple(r for r in rest if isinstance(r, ast.VarBlock))
        body = next(r for r in rest if isinstance(r, tuple))
        return ast.Accessor(str(keyword).upper(), blocks, body, self._pos(keyword))

    def property_decl(self, items: list[Any]) -> ast.Property:
        _keyword, *items = items
        access, modifiers, (name, type_ref, *rest) = self._specifiers(items)
        accessors = tuple(r for r in rest if isinstance(r, ast.Accessor))
        return ast.Property(
            self._declared(name), access, modifiers, type_ref, accessors, self._pos(name)
        )

    def interface_decl(self, items: list[Any]) -> ast.Interface:
        specifiers = [i for i in items if isinstance(i, Token) and i.type != "NAME"]
        name, *rest = [i for i in items if not (isinstance(i, Token) and i.type != "NAME")]
        self._pou_specifiers("INTERFACE", str(name), specifiers)
        clauses = {c.keyword: c.names for c in rest if isinstance(c, _Clause)}
        return ast.Interface(
            self._declared(name),
            clauses.get("EXTENDS", ()),
            tuple(r for r in rest if isinstance(r, ast.Method)),
            tuple(r for r in rest if isinstance(r, ast.Property)),
            self._pos(name),
        )

    @v_args(tree=True)
    def assignment_attempt(self, tree: Tree[Any]) -> ast.Assign:
        target, _op, value = _children(tree)
        return ast.Assign(target, value, self._pos(tree), attempt=True)

    def deref_call(self, items: list[Any]) -> ast.Call:
        """`SUPER^()`, `r^(...)`: a call named `^` on the dereferenced receiver."""
        receiver, *args = items
        deref = ast.Deref(receiver, receiver.pos)
        return ast.Call("^", self._arguments(args), receiver.pos, receiver=deref)

    # ---- SFC
    def step_decl(self, items: list[Any]) -> ast.Step:
        keyword, name, *associations = items
        initial = str(keyword).upper() == "INITIAL_STEP"
        return ast.Step(self._declared(name), initial, tuple(associations), self._pos(name))

    def action_association(self, items: list[Any]) -> ast.ActionAssociation:
        name, *rest = items
        qualifier, duration = "N", None
        if rest and isinstance(rest[0], tuple):
            qualifier, duration = rest[0]
        return ast.ActionAssociation(str(name), qualifier, duration, self._pos(name))

    def action_qualifier(self, items: list[Any]) -> tuple[str, ast.Expr | None]:
        qualifier = str(items[0]).upper()
        if len(items) == 1:
            return (qualifier, None)
        token = items[1]
        if token.type == "TIME_LITERAL":
            return (qualifier, self.time_literal([token]))
        return (qualifier, ast.NameRef(str(token), self._pos(token)))

    def step_names(self, items: list[Token]) -> tuple[str, ...]:
        return tuple(str(i) for i in items)

    def transition_decl(self, items: list[Any]) -> ast.Transition:
        keyword, *rest = items
        name = None
        priority = None
        if rest and isinstance(rest[0], Token) and rest[0].type == "NAME":
            name = str(rest.pop(0))
        if rest and isinstance(rest[0], Token) and rest[0].type == "INTEGER":
            priority = int(str(rest.pop(0)))
        sources, targets, condition = rest
        return ast.Transition(name, priority, sources, targets, condition, self._pos(keyword))

    def action_decl(self, items: list[Any]) -> ast.Action:
        _keyword, name, body = items
        return self._action(name, body)

    def actions_item(self, items: list[Any]) -> ast.Action:
        name, body = items
        return self._action(name, body)

    def _action(self, name: Token, body: tuple[ast.Statement, ...] | GraphicBody) -> ast.Action:
        if isinstance(body, GraphicBody):
            return ast.Action(self._declared(name), (), self._pos(name), graphic=body)
        return ast.Action(self._declared(name), body, self._pos(name))

    def actions_block(self, items: list[Any]) -> _ActionsBlock:
        keyword, *rest = items
        owner = str(rest.pop(0)) if rest and isinstance(rest[0], Token) else None
        return _ActionsBlock(owner, tuple(rest), self._pos(keyword))

    @v_args(tree=True)
    def program_decl(self, tree: Tree[Any]) -> ast.Pou:
        return self._pou("PROGRAM", tree)

    @v_args(tree=True)
    def program_global_block(self, tree: Tree[Any]) -> None:
        message = (
            "VAR_GLOBAL inside a PROGRAM (globals of its scope, edition 2): padt declares "
            "globals outside the POUs or in the CONFIGURATION; move them there"
        )
        self.errors.append(Diagnostic.at(self._pos(tree), Code.PROGRAM_SCOPE_BLOCK, message))

    @v_args(tree=True)
    def program_access_block(self, tree: Tree[Any]) -> None:
        message = (
            "VAR_ACCESS inside a PROGRAM (edition 2): padt declares access paths in the "
            "CONFIGURATION (`VAR_ACCESS name : Resource.Program.var : TYPE; END_VAR`)"
        )
        self.errors.append(Diagnostic.at(self._pos(tree), Code.PROGRAM_SCOPE_BLOCK, message))

    @v_args(tree=True)
    def function_block_decl(self, tree: Tree[Any]) -> ast.Pou:
        return self._pou("FUNCTION_BLOCK", tree)

    @v_args(tree=True)
    def function_decl(self, tree: Tree[Any]) -> ast.Pou:
        return self._pou("FUNCTION", tree)

    # ---- configurations
    def task_param(self, items: list[Any]) -> tuple[str, ast.Expr]:
        return (str(items[0]).upper(), items[1])

    def task_decl(self, items: list[Any]) -> ast.TaskDecl:
        name, *params = items
        return ast.TaskDecl(str(name), tuple(params), self._pos(name))

    @v_args(meta=True)
    def program_config(self, meta: Any, items: list[Any]) -> ast.ProgramInstanceDecl:
        # its arguments are ignored (W0602): the addresses they name declare nothing
        offset = self.line_offset
        span = ((meta.line + offset, meta.column), (meta.end_line + offset, meta.end_column))
        self.addresses = [
            (address, pos)
            for address, pos in self.addresses
            if not span[0] <= (pos.line, pos.col) <= span[1]
        ]
        names = [i for i in items if isinstance(i, Token) and i.type == "NAME"]
        args = tuple(i for i in items if isinstance(i, ast.Argument))
        task = str(names[1]) if len(names) == 3 else None
        return ast.ProgramInstanceDecl(
            self._declared(names[0]), task, str(names[-1]), args, self._pos(names[0])
        )

    def resource_body(self, items: list[Any]) -> tuple[str, list[Any]]:
        return ("BODY", items)

    def _resource(self, name: Token, blocks: list[Any], body: list[Any]) -> ast.ResourceDecl:
        tasks = tuple(i for i in body if isinstance(i, ast.TaskDecl))
        programs = tuple(i for i in body if isinstance(i, ast.ProgramInstanceDecl))
        return ast.ResourceDecl(str(name), tuple(blocks), tasks, programs, self._pos(name))

    def resource_decl(self, items: list[Any]) -> ast.ResourceDecl:
        name, _target, *rest = items
        blocks = [i for i in rest if isinstance(i, ast.VarBlock)]
        body = next(i for i in rest if isinstance(i, tuple))[1]
        return self._resource(name, blocks, body)

    def configuration_decl(self, items: list[Any]) -> ast.Configuration:
        name, *rest = items
        blocks = tuple(i for i in rest if isinstance(i, ast.VarBlock))
        resources = [i for i in rest if isinstance(i, ast.ResourceDecl)]
        for item in rest:  # a configuration without RESOURCE is one unnamed resource
            if isinstance(item, tuple):
                resources.append(self._resource(name, [], item[1]))
        lists = [i for i in rest if isinstance(i, list)]
        access = tuple(a for group in lists for a in group if isinstance(a, ast.AccessDecl))
        inits = tuple(c for group in lists for c in group if isinstance(c, ast.ConfigInit))
        pos = self._pos(name)
        return ast.Configuration(str(name), blocks, tuple(resources), pos, access, inits)

    def access_block(self, items: list[ast.AccessDecl]) -> list[ast.AccessDecl]:
        return items

    def access_path(self, items: list[Token]) -> tuple[str, ...]:
        return tuple(str(i).upper() if i.type == "DIRECT_ADDRESS" else str(i) for i in items)

    def access_decl(self, items: list[Any]) -> ast.AccessDecl:
        name, path, type_ref, *direction = items
        writable = bool(direction) and str(direction[0]).upper() == "READ_WRITE"
        return ast.AccessDecl(str(name), path, type_ref, writable, self._pos(name))

    def config_block(self, items: list[ast.ConfigInit]) -> list[ast.ConfigInit]:
        return items

    def config_init(self, items: list[Any]) -> ast.ConfigInit:
        names = [i for i in items if isinstance(i, Token)]
        rest = [i for i in items if not isinstance(i, Token)]
        location = rest.pop(0) if rest and isinstance(rest[0], str) else None
        type_ref, *init = rest
        path = tuple(str(n) for n in names)
        return ast.ConfigInit(
            path, location, type_ref, init[0] if init else None, self._pos(names[0])
        )

    def start(self, items: list[Any]) -> list[Any]:
        return items


def _start(expr: ast.Expr) -> Pos:
    """Where an expression's text starts (a binary operation is placed at its operator)."""
    while isinstance(expr, ast.Binary):
        expr = expr.left
    return expr.pos


def _syntax_diagnostic(file: str, exc: UnexpectedInput) -> Diagnostic:
    line, col = exc.line if exc.line > 0 else 1, exc.column if exc.column > 0 else 1
    if isinstance(exc, UnexpectedToken):
        token = exc.token
        found = "end of file" if token.type == "$END" else f"'{token}'"
        # what ends or assigns a statement first: an expression may also stand there now
        # (W0807), whose operators would push `:=` out of the eight shown
        described = [_describe(t) for t in sorted(exc.accepts or exc.expected)]
        described.sort(key=lambda text: text not in ("':='", "';'"))
        hint = ", ".join(described[:8])
        message = f"syntax error: unexpected {found}; expected {hint}"
    elif isinstance(exc, UnexpectedCharacters):
        message = f"syntax error: unexpected character {exc.char!r}"
    elif isinstance(exc, UnexpectedEOF):
        message = "syntax error: unexpected end of file"
    else:
        message = "syntax error"
    return Diagnostic.at(Pos(file, line, col), Code.SYNTAX, message)


def _describe(terminal: str) -> str:
    if terminal == "$END":
        return "end of file"
    pattern = _parser().get_terminal(terminal).pattern
    if pattern.type == "str":
        return f"'{pattern.value}'"
    return terminal.lower().replace("_", " ")


@dataclass
class TokenBudget:
    """The tokens a project may still have: each file parsed takes its own, also when it
    turns out to be wrong, since they cost time all the same."""

    left: int = MAX_PROJECT_TOKENS

    @property
    def spent(self) -> bool:
        return self.left < 0


def _tree(file: str, text: str, budget: TokenBudget) -> Tree[Token]:
    """The parse tree; parsing stops at the first token beyond the budget."""
    parser = _parser().parse_interactive(text)
    last: Token | None = None
    try:
        for last in parser.iter_parse():
            budget.left -= 1
            if budget.spent:
                where = Pos(file, last.line or 1, last.column or 1)
                message = f"the project has more than {MAX_PROJECT_TOKENS:,} tokens"
                raise CompileError([Diagnostic.at(where, Code.PROJECT_SIZE, message)])
        end = Token("$END", "", 0, 1, 1) if last is None else Token.new_borrow_pos("$END", "", last)
        tree: Tree[Token] = parser.feed_token(end)
    except UnexpectedInput as exc:
        exc.interactive_parser = parser  # as Lark.parse does: it tells what was expected
        raise CompileError([_syntax_diagnostic(file, exc)]) from None
    return tree


# What the nesting limits count, in the parse tree: the walkers of the AST recurse, so a
# tree too deep for them never becomes one.
_LOOPS = frozenset({"while_statement", "repeat_statement", "for_statement"})
_BLOCKS = _LOOPS | {"if_statement", "case_statement"}
_STATEMENTS = _BLOCKS | {
    "assignment", "set_reset_assignment", "ref_assignment", "call_statement",
    "return_statement", "exit_statement", "continue_statement", "empty_statement",
}  # fmt: skip
_OPERATIONS = frozenset({
    "binary", "unary", "member_ref", "index_ref", "bit_ref", "deref", "call", "keyword_call",
    "method_call", "instance_call", "array_initializer", "struct_initializer",
})  # fmt: skip
_OPERANDS = frozenset({
    "name_ref", "direct_ref", "int_literal", "real_literal", "time_literal", "date_literal",
    "bool_literal", "string_literal", "wstring_literal", "typed_literal", "enum_literal",
    "null_literal",
})  # fmt: skip


@dataclass(frozen=True)
class _Nesting:
    """How deep a node of the parse tree lies, by what the limits count."""

    blocks: int = 0  # IF, CASE and loops around it
    loops: int = 0  # WHILE, REPEAT and FOR around it
    branches: int = 0  # the blocks, and in each the ELSIF or CASE branches before its own
    operations: int = 0  # operations of an expression, the node's own included
    arrays: int = 0  # ARRAY ... OF, the node's own included


def _too_deep(kind: str, at: _Nesting) -> tuple[Code, str] | None:
    if kind in _STATEMENTS and at.blocks >= MAX_STATEMENT_DEPTH:
        return Code.STATEMENT_DEPTH, f"statements nested deeper than {MAX_STATEMENT_DEPTH}"
    if kind in _LOOPS and at.loops >= MAX_LOOP_DEPTH:
        return Code.STATEMENT_DEPTH, f"loops nested deeper than {MAX_LOOP_DEPTH}"
    if at.branches > MAX_BRANCH_DEPTH:
        message = f"ELSIF and CASE branches nested deeper than {MAX_BRANCH_DEPTH:,}"
        return Code.STATEMENT_DEPTH, message
    if at.operations + (1 if kind in _OPERANDS else 0) > MAX_EXPRESSION_DEPTH:
        return Code.EXPRESSION_DEPTH, f"expression nested deeper than {MAX_EXPRESSION_DEPTH}"
    if at.arrays > MAX_DATA_DEPTH:
        return Code.DATA_DEPTH, f"array types nested deeper than {MAX_DATA_DEPTH}"
    return None


def _branch_indices(kind: str, children: list[Tree[Token]]) -> list[int]:
    """For each child of an IF or CASE, the branch it belongs to: generated code puts each
    ELSIF and each CASE branch inside the one before (`elif`), and the ELSE inside the last."""
    indices: list[int] = []
    branch = 0
    labels = 0
    for child in children:
        if kind == "if_statement" and child.data in ("elsif_clause", "else_clause"):
            branch += 1
        elif kind == "case_statement" and child.data == "case_labels":
            branch, labels = labels, labels + 1
        elif kind == "case_statement" and child.data == "else_clause":
            branch = labels
        indices.append(branch)
    return indices


def _nesting_problem(file: str, tree: Tree[Token], line_offset: int = 0) -> Diagnostic | None:
    """The first place, in source order, where statements, an expression or array types
    nest too deep, without recursion."""
    pending: list[tuple[Tree[Token], _Nesting]] = [(tree, _Nesting())]
    while pending:
        node, around = pending.pop()
        kind = node.data
        at = replace(
            around,
            operations=around.operations + (1 if kind in _OPERATIONS else 0),
            arrays=around.arrays + (1 if kind == "array_type" else 0),
        )
        found = _too_deep(kind, at)
        if found is not None:
            meta = node.meta
            line, col = (1, 1) if meta.empty else (meta.line, meta.column)
            where = Pos(file, line + line_offset, col)
            return Diagnostic.at(where, *found)
        children = [child for child in node.children if isinstance(child, Tree)]
        if kind not in _BLOCKS:
            pending.extend((child, at) for child in reversed(children))
            continue
        inside = replace(at, blocks=at.blocks + 1, loops=at.loops + (1 if kind in _LOOPS else 0))
        indices = _branch_indices(kind, children)
        pending.extend(
            (child, replace(inside, branches=inside.branches + 1 + index))
            for child, index in reversed(list(zip(children, indices, strict=True)))
        )
    return None


def _pragma_diagnostic(file: str, pragma: tuple[int, int, str], line_offset: int) -> Diagnostic:
    """A skipped `{{ C code }}` block changes what runs: a warning; a `{...}` pragma of
    CODESYS or TwinCAT (`{attribute 'hide'}`, `{warning '...'}`) only a note."""
    line, col, text = pragma
    where = Pos(file, line + line_offset, col)
    if text.startswith("{{"):
        return Diagnostic.at(where, Code.PRAGMA_SKIPPED, "pragma skipped")
    words = text[1:-1].split()
    name = words[0] if words else ""
    message = f"pragma '{name[:40]}' ignored: CODESYS/TwinCAT, not IEC 61131-3"
    return Diagnostic.at(where, Code.ATTRIBUTE_PRAGMA, message)


@dataclass(frozen=True)
class SyntaxTree:
    """A text's parse tree, or the syntax error that stopped it (of no file yet, its line
    counted from the text's start), with the tokens read and the pragmas skipped on the
    way. It depends on the text alone, so one may serve every file that has the text."""

    tree: Tree[Token] | None
    error: Diagnostic | None
    tokens: int
    pragmas: tuple[tuple[int, int, str], ...]  # line, column, text


def syntax_tree(text: str, budget: TokenBudget | None = None) -> SyntaxTree:
    """The parse tree of `text`, taking its tokens from `budget`."""
    budget = budget or TokenBudget()
    before = budget.left
    with _LEXING:
        _PRAGMAS.clear()
        try:
            tree: Tree[Token] | None = _tree("", text, budget)
            error = None
        except CompileError as exc:
            tree, error = None, exc.diagnostics[0]
        pragmas = tuple((t.line or 1, t.column or 1, str(t)) for t in _PRAGMAS)
    return SyntaxTree(tree, error, before - budget.left, pragmas)


def placed(diagnostic: Diagnostic, file: str, line_offset: int) -> Diagnostic:
    """A diagnostic of a text put where that text is: in `file`, after `line_offset` lines."""
    return replace(diagnostic, file=file, line=diagnostic.line + line_offset)


@dataclass(frozen=True)
class Piece:
    """A file's text, or a part of it that holds whole declarations, turned into AST items:
    before ACTIONS blocks and members declared after their owner are put with it (which
    needs the whole file). `stopped`: the problem that left no items, with its stage
    (1: nesting too deep, 2: a literal without a value), since a whole file reports the
    first problem of the earliest stage."""

    items: tuple[Any, ...]
    errors: tuple[Diagnostic, ...]
    warnings: tuple[Diagnostic, ...]
    addresses: tuple[tuple[str, Pos], ...]
    stopped: tuple[int, Diagnostic] | None = None


def piece_of(file: str, parsed: SyntaxTree, line_offset: int = 0) -> Piece:
    """The AST items of a text that parsed, placed in `file` after `line_offset` lines."""
    assert parsed.tree is not None, "a text with a syntax error has no items"
    too_deep = _nesting_problem(file, parsed.tree, line_offset)
    if too_deep is not None:
        return Piece((), (), (), (), (1, too_deep))
    transformer = _ToAst(file, line_offset)
    try:
        items = transformer.transform(parsed.tree)
    except VisitError as exc:  # a literal that parses but has no value (16#_, D#2024-13-01)
        where = transformer._pos(exc.obj)
        problem = str(exc.orig_exc) or type(exc.orig_exc).__name__
        message = f"invalid literal: {problem}"
        return Piece((), (), (), (), (2, Diagnostic.at(where, Code.INVALID_LITERAL, message)))
    pragmas = (_pragma_diagnostic(file, p, line_offset) for p in parsed.pragmas)
    warnings = (*pragmas, *transformer.warnings)
    return Piece(tuple(items), tuple(transformer.errors), warnings, tuple(transformer.addresses))


def unit_of(file: str, pieces: Sequence[Piece]) -> ast.SourceUnit:
    """A file's unit from the pieces of its text, in order, each of which parsed. Raises
    `CompileError` as `parse_source` does."""
    stopped = sorted(p.stopped for p in pieces if p.stopped is not None)
    if stopped:
        raise CompileError([stopped[0][1]])
    items, misplaced = _with_actions_blocks([i for p in pieces for i in p.items])
    errors = [e for p in pieces for e in p.errors]
    if errors or misplaced:
        raise CompileError(errors + misplaced)
    globals_ = tuple(i for i in items if isinstance(i, ast.VarBlock))
    pous, drawing_warnings = _with_drawings_lowered(
        file, tuple(i for i in items if isinstance(i, ast.Pou)), globals_
    )
    types = tuple(t for i in items if isinstance(i, list) for t in i)
    configurations = tuple(i for i in items if isinstance(i, ast.Configuration))
    # globals of a configuration or resource are globals like any other
    globals_ += tuple(
        block
        for c in configurations
        for block in (*c.globals, *(b for r in c.resources for b in r.globals))
    )
    warnings = tuple(w for p in pieces for w in p.warnings) + drawing_warnings
    addresses = tuple(a for p in pieces for a in p.addresses)
    interfaces = tuple(i for i in items if isinstance(i, ast.Interface))
    return ast.SourceUnit(
        file, pous, globals_, types, warnings, configurations, addresses, interfaces
    )


def _with_drawings_lowered(
    file: str, pous: tuple[ast.Pou, ...], globals_: tuple[ast.VarBlock, ...]
) -> tuple[tuple[ast.Pou, ...], tuple[Diagnostic, ...]]:
    """The POUs with each drawn body (FBD, LD) of a POU or an action lowered to statements,
    which the rest of the compiler takes as it takes any body, and the warnings of the
    drawings. Raises `CompileError` for a drawing that does not lower."""
    result = []
    problems: list[Diagnostic] = []
    warnings: list[Diagnostic] = []
    for pou in pous:
        actions = pou.sfc.actions if pou.sfc is not None else ()
        if pou.graphic is None and all(a.graphic is None for a in actions):
            result.append(pou)
            continue
        try:
            lowered, found = _lowered_pou(file, pou, context_of(pou, pous, globals_))
        except CompileError as exc:
            problems += exc.diagnostics
            continue
        result.append(lowered)
        warnings += found
    if problems:
        raise CompileError(problems)
    return tuple(result), tuple(warnings)


def _lowered_pou(file: str, pou: ast.Pou, context: Context) -> tuple[ast.Pou, list[Diagnostic]]:
    """`pou` with its drawn body and actions lowered, and their warnings."""
    hidden: list[ast.VarBlock] = []
    warnings: list[Diagnostic] = []

    def lowered(body: GraphicBody, action: str = "") -> tuple[ast.Statement, ...]:
        done = lower(body, file, context, action)
        warnings.extend(d for d in done.diagnostics if d.severity != "error")
        errors = [d for d in done.diagnostics if d.severity == "error"]
        if errors:
            raise CompileError(errors)
        statements, blocks = _parsed_lowering(file, body, done)
        hidden.extend(blocks)
        return statements

    body = lowered(pou.graphic) if pou.graphic is not None else pou.body
    sfc = pou.sfc
    if sfc is not None:
        actions = tuple(
            replace(a, body=lowered(a.graphic, a.name)) if a.graphic is not None else a
            for a in sfc.actions
        )
        sfc = replace(sfc, actions=actions)
    blocks = pou.var_blocks + tuple(hidden)
    return replace(pou, body=body, sfc=sfc, var_blocks=blocks), warnings


def _parsed_lowering(
    file: str, body: GraphicBody, lowered: Lowered
) -> tuple[tuple[ast.Statement, ...], tuple[ast.VarBlock, ...]]:
    """The statements of a lowered drawing, each placed at its element, and the
    declarations of its hidden variables."""
    # the lowered text, parsed as the body of a program: line 1 is its header, then the
    # hidden variables, then one line of statements per element
    header = ["PROGRAM lowered"]
    if lowered.temporaries:
        header.append(temporaries_block(lowered))
    text = "\n".join([*header, *(line.text for line in lowered.lines), "END_PROGRAM"])
    at = Pos(file, body.line, body.col)
    places = [at] * len(header) + [
        Pos(file, line.element.line, line.element.col) if line.element else at
        for line in lowered.lines
    ]
    parsed = syntax_tree(text)
    if parsed.error is not None:
        raise CompileError([_moved(parsed.error, places, at)])
    try:
        unit = unit_of(file, [piece_of(file, parsed)])
    except CompileError as exc:
        raise CompileError([_moved(d, places, at) for d in exc.diagnostics]) from None
    (program,) = unit.pous

    def moved(node: Any) -> Any:
        pos = getattr(node, "pos", None)
        if not isinstance(pos, Pos):
            return node
        return replace(node, pos=places[pos.line - 1] if 0 < pos.line <= len(places) else at)

    return ast.rebuilt(program.body, moved), ast.rebuilt(program.var_blocks, moved)


def _moved(diagnostic: Diagnostic, places: list[Pos], at: Pos) -> Diagnostic:
    """A diagnostic of the lowered text put at the element its line comes from."""
    place = places[diagnostic.line - 1] if 0 < diagnostic.line <= len(places) else at
    return replace(diagnostic, file=place.file, line=place.line, col=place.col)


def parse_as_drawn(file: str, text: str) -> tuple[tuple[ast.Pou, ...], tuple[ast.VarBlock, ...]]:
    """The POUs and globals of one file as written: a drawn body is not lowered (`padt
    convert` lowers it into the text). Raises `CompileError` as `parse_source` does."""
    parsed = syntax_tree(text)
    if parsed.error is not None:
        raise CompileError([placed(parsed.error, file, 0)])
    piece = piece_of(file, parsed)
    if piece.stopped is not None:
        raise CompileError([piece.stopped[1]])
    if piece.errors:
        raise CompileError(list(piece.errors))
    pous = tuple(i for i in piece.items if isinstance(i, ast.Pou))
    return pous, tuple(i for i in piece.items if isinstance(i, ast.VarBlock))


def parse_source(file: str, text: str, budget: TokenBudget | None = None) -> ast.SourceUnit:
    """Parse one ST file, taking its tokens from the project's `budget`. Raises
    `CompileError` with a `file:line:col` diagnostic."""
    parsed = syntax_tree(text, budget)
    if parsed.error is not None:
        raise CompileError([placed(parsed.error, file, 0)])
    return unit_of(file, [piece_of(file, parsed)])
