"""Stage 1, parse: ST source text -> `ast.SourceUnit`, or diagnostics.

A lark LALR(1) parser with the contextual lexer (fast, and deterministic); the tree it
builds is turned into typed AST dataclasses right away so that no later stage sees lark.
"""

from __future__ import annotations

import functools
import re
from importlib import resources
from typing import Any

from lark import Lark, Token, Transformer, Tree, v_args
from lark.exceptions import UnexpectedCharacters, UnexpectedEOF, UnexpectedInput, UnexpectedToken

from backend.compiler import ast
from backend.compiler.diagnostics import CompileError, Diagnostic

_UNIT_NS = {
    "D": 86_400_000_000_000,
    "H": 3_600_000_000_000,
    "M": 60_000_000_000,
    "S": 1_000_000_000,
    "MS": 1_000_000,
    "US": 1_000,
    "NS": 1,
}
_TIME_PART = re.compile(r"([0-9][0-9_]*(?:\.[0-9_]+)?)(D|H|MS|M|S|US|NS)", re.IGNORECASE)


@functools.cache
def _parser() -> Lark:
    grammar = resources.files("backend.compiler").joinpath("grammar.lark").read_text()
    return Lark(grammar, parser="lalr", lexer="contextual", propagate_positions=True)


def parse_time_literal(text: str) -> tuple[int, bool]:
    """`T#1h2m3.5s` -> (nanoseconds, is_LTIME)."""
    prefix, _, body = text.partition("#")
    negative = body.startswith("-")
    body = body.lstrip("-")
    total = 0
    for number, unit in _TIME_PART.findall(body):
        value = float(number.replace("_", ""))
        total += round(value * _UNIT_NS[unit.upper()])
    return (-total if negative else total), prefix.upper() in ("LT", "LTIME")


def parse_int_literal(text: str) -> int:
    text = text.replace("_", "")
    if "#" in text:
        base, _, digits = text.partition("#")
        return int(digits, int(base))
    return int(text)


def decode_string_literal(text: str) -> str:
    """Decode the `$` escapes of an ST string literal (without the quotes)."""
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
            hex_digits = text[i + 1 : i + 3]
            if re.fullmatch(r"[0-9A-Fa-f]{2}", hex_digits):
                out.append(chr(int(hex_digits, 16)))
                i += 3
                continue
        out.append(ch)
        i += 1
    return "".join(out)


def _children(tree: Tree[Any]) -> list[Any]:
    """A transformed node's children: AST nodes by now, which lark's types cannot know."""
    return list(tree.children)


class _ToAst(Transformer[Token, Any]):
    """Bottom-up conversion of the lark tree into AST nodes."""

    def __init__(self, file: str) -> None:
        super().__init__()
        self.file = file

    def _pos(self, item: Any) -> ast.Pos:
        if isinstance(item, Token):
            return ast.Pos(self.file, item.line or 0, item.column or 0)
        return ast.Pos(self.file, item.meta.line, item.meta.column)

    # ---- literals
    def int_literal(self, items: list[Token]) -> ast.IntLiteral:
        return ast.IntLiteral(parse_int_literal(str(items[0])), self._pos(items[0]))

    def real_literal(self, items: list[Token]) -> ast.RealLiteral:
        text = str(items[0]).replace("_", "")
        return ast.RealLiteral(float(text), text, self._pos(items[0]))

    def bool_literal(self, items: list[Token]) -> ast.BoolLiteral:
        return ast.BoolLiteral(str(items[0]).upper() == "TRUE", self._pos(items[0]))

    def time_literal(self, items: list[Token]) -> ast.TimeLiteral:
        ns, long = parse_time_literal(str(items[0]))
        return ast.TimeLiteral(ns, long, self._pos(items[0]))

    def string_literal(self, items: list[Token]) -> ast.StringLiteral:
        return ast.StringLiteral(decode_string_literal(str(items[0])[1:-1]), self._pos(items[0]))

    # ---- expressions
    def name_ref(self, items: list[Token]) -> ast.NameRef:
        return ast.NameRef(str(items[0]), self._pos(items[0]))

    def member_ref(self, items: list[Any]) -> ast.MemberRef:
        base, member = items
        return ast.MemberRef(base, str(member), base.pos)

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
        name, _arrow, target = items
        return ast.Argument(str(name), target, True, self._pos(name))

    def positional_arg(self, items: list[Any]) -> ast.Argument:
        return ast.Argument(None, items[0], False, items[0].pos)

    def call(self, items: list[Any]) -> ast.Call:
        name, *args = items
        return ast.Call(str(name), tuple(a for a in args if a is not None), self._pos(name))

    # ---- statements
    @v_args(tree=True)
    def assignment(self, tree: Tree[Any]) -> ast.Assign:
        target, value = _children(tree)
        return ast.Assign(target, value, self._pos(tree))

    def call_statement(self, items: list[Any]) -> ast.CallStatement:
        return ast.CallStatement(items[0], items[0].pos)

    def statement_list(self, items: list[Any]) -> tuple[ast.Statement, ...]:
        return tuple(s for s in items if s is not None)

    def empty_statement(self, items: list[Any]) -> None:
        return None

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
        return ast.NamedType(str(items[0]), self._pos(items[0]))

    def string_type(self, items: list[Any]) -> ast.StringType:
        kw = items[0]
        length = items[1] if len(items) > 1 else None
        return ast.StringType(str(kw).upper() == "WSTRING", length, self._pos(kw))

    def location(self, items: list[Token]) -> str:
        return str(items[0]).upper()

    def var_qualifier(self, items: list[Token]) -> str:
        return str(items[0]).upper()

    def var_decl(self, items: list[Any]) -> list[ast.VarDecl]:
        names = [i for i in items if isinstance(i, Token) and i.type == "NAME"]
        rest = [i for i in items if not (isinstance(i, Token) and i.type == "NAME")]
        location = next((r for r in rest if isinstance(r, str)), None)
        typed = [r for r in rest if not isinstance(r, str)]
        type_ref = typed[0]
        init = typed[1] if len(typed) > 1 else None
        return [ast.VarDecl(str(n), type_ref, init, location, self._pos(n)) for n in names]

    def _block(self, kind: str, pos: ast.Pos, items: list[Any]) -> ast.VarBlock:
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
        name, *rest = _children(tree)
        return_type = None
        if kind == "FUNCTION":
            return_type, *rest = rest
        blocks = tuple(r for r in rest if isinstance(r, ast.VarBlock))
        body = rest[-1]
        return ast.Pou(kind, str(name), return_type, blocks, body, self._pos(tree))

    @v_args(tree=True)
    def program_decl(self, tree: Tree[Any]) -> ast.Pou:
        return self._pou("PROGRAM", tree)

    @v_args(tree=True)
    def function_block_decl(self, tree: Tree[Any]) -> ast.Pou:
        return self._pou("FUNCTION_BLOCK", tree)

    @v_args(tree=True)
    def function_decl(self, tree: Tree[Any]) -> ast.Pou:
        return self._pou("FUNCTION", tree)

    def start(self, items: list[Any]) -> list[Any]:
        return items


def _syntax_diagnostic(file: str, exc: UnexpectedInput) -> Diagnostic:
    line, col = exc.line if exc.line > 0 else 1, exc.column if exc.column > 0 else 1
    if isinstance(exc, UnexpectedToken):
        token = exc.token
        found = "end of file" if token.type == "$END" else f"'{token}'"
        expected = sorted(exc.accepts or exc.expected)
        hint = ", ".join(_describe(t) for t in expected[:8])
        message = f"syntax error: unexpected {found}; expected {hint}"
    elif isinstance(exc, UnexpectedCharacters):
        message = f"syntax error: unexpected character {exc.char!r}"
    elif isinstance(exc, UnexpectedEOF):
        message = "syntax error: unexpected end of file"
    else:
        message = "syntax error"
    return Diagnostic(file, line, col, "error", message)


def _describe(terminal: str) -> str:
    pattern = _parser().get_terminal(terminal).pattern
    if pattern.type == "str":
        return f"'{pattern.value}'"
    return terminal.lower().replace("_", " ")


def parse_source(file: str, text: str) -> ast.SourceUnit:
    """Parse one ST file. Raises `CompileError` with a `file:line:col` diagnostic."""
    try:
        tree = _parser().parse(text)
    except UnexpectedInput as exc:
        raise CompileError([_syntax_diagnostic(file, exc)]) from None
    items = _ToAst(file).transform(tree)
    pous = tuple(i for i in items if isinstance(i, ast.Pou))
    globals_ = tuple(i for i in items if isinstance(i, ast.VarBlock))
    return ast.SourceUnit(file, pous, globals_)
