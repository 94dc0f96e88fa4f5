"""The ST expressions of breakpoint conditions and logpoints, read by the runtime as data:
parsed here into a small tree and evaluated against a frame's names. Nothing of them is
ever compiled or executed as code; what is not in this subset is refused when it is set.

The subset: variables with members and array indices; BOOL, integer (with 2#, 8#, 16#),
REAL and 'string' literals; NOT, unary -, * / MOD, + -, comparisons (= <> < <= > >=),
AND (&), XOR, OR, by IEC precedence; parentheses.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from runtime.contract.refusal import Refusal
from runtime.contract.values import format_value, parse_time_literal
from runtime.debugging.scope import Names, Typed, element

_TOKEN = re.compile(
    r"\s*(?:(?P<real>\d[\d_]*\.\d[\d_]*(?:[eE][+-]?\d+)?|\d[\d_]*[eE][+-]?\d+)"
    r"|(?P<int>(?:2#[01_]+|8#[0-7_]+|16#[0-9A-Fa-f_]+|\d[\d_]*))"
    r"|(?P<time>(?:LTIME|TIME|LT|T)#-?[0-9][0-9_.A-Za-z]*)"
    r"|(?P<string>'(?:[^'$]|\$.)*')"
    r"|(?P<name>[A-Za-z_][A-Za-z0-9_]*)"
    r"|(?P<op><=|>=|<>|[-+*/=<>()\[\].,&]))"
)
MAX_NESTING = 32  # parentheses in one expression
_TIME_PREFIXES = {"T", "TIME", "LT", "LTIME"}
_WORDS = {"AND", "OR", "XOR", "NOT", "MOD", "TRUE", "FALSE"}
_LEVELS: tuple[tuple[str, ...], ...] = (
    ("OR",),
    ("XOR",),
    ("AND", "&"),
    ("=", "<>", "<", "<=", ">", ">="),
    ("+", "-"),
    ("*", "/", "MOD"),
)


@dataclass(frozen=True)
class Node:
    op: str  # "const", "time", "var", "member", "index", "not", "neg", or a binary operator
    args: tuple[Any, ...]


def parse(text: str) -> Node:
    """The tree of an expression; Refusal `bad_value` naming what is wrong and where."""
    tokens = _tokens(text)
    parser = _Parser(tokens, text)
    node = parser.expression(0)
    if parser.at < len(tokens):
        raise Refusal("bad_value", f"'{text}': unexpected '{tokens[parser.at]}'")
    return node


def _tokens(text: str) -> list[str]:
    found: list[str] = []
    at = 0
    while at < len(text):
        if text[at:].strip() == "":
            break
        match = _TOKEN.match(text, at)
        if match is None or match.end() == at:
            raise Refusal("bad_value", f"'{text}': cannot read '{text[at:].strip()[:20]}'")
        found.append(match.group(match.lastgroup or "op"))
        at = match.end()
    if not found:
        raise Refusal("bad_value", "an empty expression")
    return found


class _Parser:
    def __init__(self, tokens: list[str], text: str) -> None:
        self.tokens, self.text, self.at = tokens, text, 0
        self.depth = 0  # parentheses open here

    def peek(self) -> str:
        return self.tokens[self.at] if self.at < len(self.tokens) else ""

    def take(self, expected: str | None = None) -> str:
        token = self.peek()
        if not token or (expected is not None and token.upper() != expected):
            wanted = f"'{expected}'" if expected else "more"
            raise Refusal("bad_value", f"'{self.text}': {wanted} expected")
        self.at += 1
        return token

    def expression(self, level: int) -> Node:
        if level == len(_LEVELS):
            return self.unary()
        node = self.expression(level + 1)
        while self.peek().upper() in _LEVELS[level]:
            op = self.take().upper()
            op = "AND" if op == "&" else op
            node = Node(op, (node, self.expression(level + 1)))
            if level == 3 and self.peek() in _LEVELS[3]:
                raise Refusal("bad_value", f"'{self.text}': comparisons do not chain")
        return node

    def unary(self) -> Node:
        token = self.peek().upper()
        if token == "NOT":
            self.take()
            return Node("not", (self.unary(),))
        if token == "-":
            self.take()
            return Node("neg", (self.unary(),))
        return self.primary()

    def primary(self) -> Node:
        token = self.take()
        upper = token.upper()
        if token == "(":
            self.depth += 1
            if self.depth > MAX_NESTING:  # each level is a few Python frames deep
                raise Refusal("bad_value", f"'{self.text[:40]}...': nested too deep")
            node = self.expression(0)
            self.take(")")
            self.depth -= 1
            return node
        if upper in ("TRUE", "FALSE"):
            return Node("const", (upper == "TRUE",))
        if "#" in token and token.split("#")[0].upper() in _TIME_PREFIXES:
            return Node("time", (parse_time_literal(token)[0],))
        if token[0].isdigit():
            return Node("const", (_number(token),))
        if token.startswith("'"):
            return Node("const", (re.sub(r"\$(.)", r"\1", token[1:-1]),))
        if not (token[0].isalpha() or token[0] == "_") or upper in _WORDS:
            raise Refusal("bad_value", f"'{self.text}': unexpected '{token}'")
        node = Node("var", (token,))
        while self.peek() in (".", "["):
            if self.take() == ".":
                node = Node("member", (node, self.take()))
            else:
                node = Node("index", (node, self.expression(0)))
                while self.peek() == ",":
                    self.take()
                    node = Node("index", (node, self.expression(0)))
                self.take("]")
        return node


def _number(token: str) -> int | float:
    token = token.replace("_", "")
    if "#" in token:
        base, digits = token.split("#")
        return int(digits, int(base))
    return float(token) if any(c in token for c in ".eE") else int(token)


_BINARY: dict[str, Callable[[Any, Any], Any]] = {
    "OR": lambda a, b: a or b if isinstance(a, bool) else a | b,
    "XOR": lambda a, b: a != b if isinstance(a, bool) else a ^ b,
    "AND": lambda a, b: a and b if isinstance(a, bool) else a & b,
    "=": lambda a, b: a == b,
    "<>": lambda a, b: a != b,
    "<": lambda a, b: a < b,
    "<=": lambda a, b: a <= b,
    ">": lambda a, b: a > b,
    ">=": lambda a, b: a >= b,
    "+": lambda a, b: a + b,
    "-": lambda a, b: a - b,
    "*": lambda a, b: a * b,
    "/": lambda a, b: a // b if isinstance(a, int) and isinstance(b, int) else a / b,
    "MOD": lambda a, b: a % b,
}


def evaluate(node: Node, scope: Names) -> Any:
    """The value of an expression in a frame; Refusal when a name is unknown or an
    operation does not apply (a division by zero, comparing a text with a number)."""
    try:
        return _plain(_evaluate(node, scope))
    except (ArithmeticError, TypeError, ValueError) as exc:
        raise Refusal("bad_value", f"cannot evaluate: {exc}") from None


def locate(path: str, names: Names) -> Typed:
    """The variable a path names ("Main.valve1", "a.sub", "arr[2]")."""
    try:
        found = _evaluate(parse(path), names)
    except (ArithmeticError, TypeError, ValueError) as exc:
        raise Refusal("bad_value", f"'{path}': {exc}") from None
    if not isinstance(found, Typed):
        raise Refusal("bad_value", f"'{path}' is not a variable")
    return found


def literal_of(node: Node, scope: Names) -> str:
    """The value of an expression as an ST literal (TRUE, T#1s500ms, 'text'): a variable's
    by its type, anything else by its Python type."""
    try:
        found = _evaluate(node, scope)
    except (ArithmeticError, TypeError, ValueError) as exc:
        raise Refusal("bad_value", f"cannot evaluate: {exc}") from None
    if isinstance(found, Typed):
        return format_value(found.value, found.type)
    return format_value(found, "LREAL" if isinstance(found, float) else "")


def _plain(value: Any) -> Any:
    return value.value if isinstance(value, Typed) else value


def _evaluate(node: Node, scope: Names) -> Any:
    op, args = node.op, node.args
    if op == "const":
        return args[0]
    if op == "time":  # typed, so that it is shown as the literal it is
        return Typed(args[0], "TIME", None)
    if op == "var":
        return scope.lookup(args[0])
    if op == "member":
        owner = _evaluate(args[0], scope)
        if not isinstance(owner, Typed):
            raise Refusal("bad_value", f"'{args[1]}': not a member of a value")
        return scope.table.member(owner, args[1])
    if op == "index":
        owner = _evaluate(args[0], scope)
        index = _plain(_evaluate(args[1], scope))
        if not isinstance(owner, Typed) or not isinstance(index, int):
            raise Refusal("bad_value", "an index needs an array and an integer")
        return element(owner, index)
    if op == "not":
        value = _plain(_evaluate(args[0], scope))
        return not value if isinstance(value, bool) else ~value
    if op == "neg":
        return -_plain(_evaluate(args[0], scope))
    left = _plain(_evaluate(args[0], scope))
    right = _plain(_evaluate(args[1], scope))
    return _BINARY[op](left, right)
