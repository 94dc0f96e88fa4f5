"""The expressions of the typed form: one frozen dataclass per kind of node, each with the
IEC type of its value (as the artifact spells types: `INT`, `STRING[80]`, `ARRAY[1..3] OF
REAL`; empty where a node is no value of the program, such as a class or a list of
bounds).

The compiler lowers every expression of ST to these nodes, with every decision taken:
where an integer wraps and to how many bits, where an index is checked against which
bounds, which intrinsic (runtime/contract/intrinsic_table.py) or FUNCTION a call names.
`python_text` prints them as the Python tier runs them; the C tier is made from the same
nodes, so the two cannot read a program differently.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

# where a variable lives: a Python local (a FUNCTION's variable, a temporary), a slot of the
# instance the code runs on, of the globals, of the system variables, a program instance
Where = Literal["local", "instance", "globals", "system", "programs"]
UnaryOp = Literal["not", "~", "-"]
BinaryOp = Literal[
    "+", "-", "*", "%", "&", "|", "^", "<<", ">>", "==", "!=", "<", ">", "<=", ">=",
    "is", "is not", "in",
]  # fmt: skip


@dataclass(frozen=True, slots=True)
class Const:
    """A constant: a number, a Boolean, a text, NULL (None); a float may be infinite or
    NaN."""

    value: bool | int | float | str | None
    type: str


@dataclass(frozen=True, slots=True)
class Var:
    name: str
    where: Where
    type: str


@dataclass(frozen=True, slots=True)
class This:
    """The instance the code runs on (THIS^, SUPER^, the root of an instance's slots)."""

    type: str


@dataclass(frozen=True, slots=True)
class Named:
    """Something of the generated code named as a value: a class (`POU_MOTOR`), a
    FUNCTION, an intrinsic passed to another (`_math.sin`)."""

    name: str
    type: str = ""


@dataclass(frozen=True, slots=True)
class Member:
    base: Expr
    name: str
    type: str


@dataclass(frozen=True, slots=True)
class Index:
    """An element of a list: an array's items at a flat offset already checked."""

    base: Expr
    offset: Expr
    type: str


@dataclass(frozen=True, slots=True)
class Slice:
    """`value[start:stop]`: a string cut to a length (stop), the tail of a list (start)."""

    value: Expr
    start: int | None
    stop: int | None
    type: str


@dataclass(frozen=True, slots=True)
class Unary:
    op: UnaryOp
    operand: Expr
    type: str


@dataclass(frozen=True, slots=True)
class Binary:
    """An operation on two values, computed unbounded (as Python does): a result that
    must fit its type is wrapped by a `Wrap` around it."""

    op: BinaryOp
    left: Expr
    right: Expr
    type: str


@dataclass(frozen=True, slots=True)
class Chain:
    """A chained comparison, `a < b < c`: each value evaluated once, left to right, the
    chain stopping at the first comparison that fails."""

    op: BinaryOp
    values: tuple[Expr, ...]
    type: str = "BOOL"


@dataclass(frozen=True, slots=True)
class Logic:
    """`a and b and ...` (`or`): Booleans, evaluated left to right only as far as needed."""

    op: Literal["and", "or"]
    values: tuple[Expr, ...]
    type: str = "BOOL"


@dataclass(frozen=True, slots=True)
class Choice:
    """`then` where `test` holds, else `orelse`; only the one chosen is evaluated."""

    test: Expr
    then: Expr
    orelse: Expr
    type: str


@dataclass(frozen=True, slots=True)
class Assigned:
    """`value`, also kept in the local `name` for a later read in the same expression."""

    name: str
    value: Expr
    type: str


@dataclass(frozen=True, slots=True)
class Wrap:
    """An integer (or time) brought into the range of `bits` bits, two's complement where
    `signed`, after adding `offset`."""

    value: Expr
    bits: int
    signed: bool
    offset: int
    type: str


@dataclass(frozen=True, slots=True)
class Call:
    """A call: `callee` names an intrinsic, a FUNCTION (`FN_...`), a conversion Python
    itself has (`float`, `int`, `str`, `abs`, `min`, `max`); or it is a value (a method of
    an instance, of a class). `keywords` are passed by parameter name."""

    callee: str | Expr
    args: tuple[Expr, ...]
    type: str
    keywords: tuple[tuple[str, Expr], ...] = ()


@dataclass(frozen=True, slots=True)
class Sequence:
    """A list (`[a, b]`), or a tuple (`(a, b)`), of values made now."""

    items: tuple[Expr, ...]
    type: str
    as_tuple: bool = False


@dataclass(frozen=True, slots=True)
class Repeated:
    """A list of `count` elements: the same value (`[v] * n`), or made anew for each (a
    structure, an instance: `[v for _ in range(n)]`)."""

    item: Expr
    count: int
    each_new: bool
    type: str


@dataclass(frozen=True, slots=True)
class Members:
    """Members of a structure or instance by slot name, to initialise (`{'x': 1}`)."""

    items: tuple[tuple[str, Expr], ...]
    type: str = ""


Expr = (
    Const | Var | This | Named | Member | Index | Slice | Unary | Binary | Chain | Logic | Choice
    | Assigned | Wrap | Call | Sequence | Repeated | Members
)  # fmt: skip
