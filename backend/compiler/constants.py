"""Folding constant integer expressions: array bounds, string lengths, enum values, CASE
labels, FOR steps, constant indices. One folder for every stage; what a name stands for is
the caller's business (resolve knows declarations, check knows scopes)."""

from __future__ import annotations

from collections.abc import Callable

from backend.compiler import ast
from backend.compiler.limits import MAX_EXPRESSION_DEPTH

# The value of a leaf that is not a literal (a named constant, an enum value), or None.
Leaf = Callable[[ast.NameRef | ast.EnumLiteral], int | None]


def truncated_quotient(a: int, b: int) -> int:
    """IEC integer division: toward zero, exactly (no float on the way)."""
    quotient = abs(a) // abs(b)
    return quotient if (a >= 0) == (b >= 0) else -quotient


_OPERATIONS: dict[str, Callable[[int, int], int]] = {
    "+": lambda a, b: a + b,
    "-": lambda a, b: a - b,
    "*": lambda a, b: a * b,
    "/": truncated_quotient,
    "MOD": lambda a, b: a - b * truncated_quotient(a, b),
}


# Folded values are exact, but one of more bits than this is no constant: a chain of squares
# (`c2 := c1 * c1`, ...) would soon need more memory than there is.
_MAX_BITS = 4096


def fold_int(expr: ast.Initializer | None, leaf: Leaf) -> int | None:
    """The value of a constant integer expression, or None when it is not one (or divides
    by zero, which is left to the run-time check)."""
    match expr:
        case ast.IntLiteral(value=value):
            return value
        case ast.Unary(op="-", operand=operand):
            inner = fold_int(operand, leaf)
            return None if inner is None else -inner
        case ast.Binary(op=op, left=left, right=right) if op in _OPERATIONS:
            a, b = fold_int(left, leaf), fold_int(right, leaf)
            if a is None or b is None or (op in ("/", "MOD") and b == 0):
                return None
            value = _OPERATIONS[op](a, b)
            return value if value.bit_length() <= _MAX_BITS else None
        case ast.NameRef() | ast.EnumLiteral():
            return leaf(expr)
    return None


def is_zero_literal(expr: ast.Expr) -> bool:
    """The untyped literal 0: what CODESYS compares a POINTER with for NULL (`p <> 0`)."""
    return isinstance(expr, ast.IntLiteral) and expr.value == 0 and expr.type_name is None


class _TooDeep(Exception):
    """A constant defined through more names than the folder follows."""


class Guarded:
    """A leaf that refuses to follow a name into itself (`c : INT := c + 1`), asks the leaf
    once per name in the source (`c2 := c1 + c1`, `c3 := c2 + c2` ... would double the work
    with every line), and gives up on a name defined through more than MAX_EXPRESSION_DEPTH
    others in a row, since the folder recurses through them (`cut_short` then tells)."""

    def __init__(self, leaf: Leaf) -> None:
        self.leaf = leaf
        self.visiting: set[str] = set()
        self.known: dict[int, int | None] = {}  # by the id of the name's node
        self.cut_short = False

    def __call__(self, expr: ast.NameRef | ast.EnumLiteral) -> int | None:
        name = expr.name.upper() if isinstance(expr, ast.NameRef) else None
        if name is None:
            return self.leaf(expr)
        if id(expr) in self.known:
            return self.known[id(expr)]
        if name in self.visiting:
            return None
        if len(self.visiting) >= MAX_EXPRESSION_DEPTH:
            self.cut_short = True
            raise _TooDeep
        outermost = not self.visiting
        self.visiting.add(name)
        try:
            value = self.leaf(expr)
        except _TooDeep:
            if not outermost:
                raise
            return None  # the name counts as no constant
        finally:
            self.visiting.discard(name)
        self.known[id(expr)] = value
        return value
