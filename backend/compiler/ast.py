"""The abstract syntax tree: what the parse stage produces and the resolve stage consumes.

Every node carries its source position so that any later stage can report
`file:line:col`. Names keep the spelling of the source; ST is case-insensitive, so
comparisons go through `key()` (upper case) everywhere.
"""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass(frozen=True)
class Pos:
    file: str
    line: int
    col: int

    def __str__(self) -> str:
        return f"{self.file}:{self.line}:{self.col}"


def key(name: str) -> str:
    """The case-insensitive identity of an ST identifier."""
    return name.upper()


# ---- types in declarations --------------------------------------------------------------


@dataclass(frozen=True)
class NamedType:
    name: str
    pos: Pos


@dataclass(frozen=True)
class StringType:
    wide: bool
    length: Expr | None
    pos: Pos


TypeRef = NamedType | StringType


# ---- expressions -------------------------------------------------------------------------


@dataclass(frozen=True)
class IntLiteral:
    value: int
    pos: Pos


@dataclass(frozen=True)
class RealLiteral:
    value: float
    text: str
    pos: Pos


@dataclass(frozen=True)
class BoolLiteral:
    value: bool
    pos: Pos


@dataclass(frozen=True)
class TimeLiteral:
    nanoseconds: int
    long: bool
    pos: Pos


@dataclass(frozen=True)
class StringLiteral:
    value: str
    pos: Pos


@dataclass(frozen=True)
class NameRef:
    name: str
    pos: Pos


@dataclass(frozen=True)
class MemberRef:
    base: Expr
    member: str
    pos: Pos


@dataclass(frozen=True)
class Unary:
    op: str  # "-" or "NOT"
    operand: Expr
    pos: Pos


@dataclass(frozen=True)
class Binary:
    op: str  # upper case: OR XOR AND = <> < > <= >= + - * / MOD **
    left: Expr
    right: Expr
    pos: Pos


@dataclass(frozen=True)
class Argument:
    name: str | None  # None for a positional argument
    value: Expr
    is_output: bool  # `name => variable`
    pos: Pos


@dataclass(frozen=True)
class Call:
    name: str
    args: tuple[Argument, ...]
    pos: Pos


Literal = IntLiteral | RealLiteral | BoolLiteral | TimeLiteral | StringLiteral
Expr = Literal | NameRef | MemberRef | Unary | Binary | Call


# ---- statements --------------------------------------------------------------------------


@dataclass(frozen=True)
class Assign:
    target: Expr
    value: Expr
    pos: Pos


@dataclass(frozen=True)
class CallStatement:
    call: Call
    pos: Pos


@dataclass(frozen=True)
class If:
    branches: tuple[tuple[Expr, tuple[Statement, ...]], ...]  # IF and each ELSIF
    orelse: tuple[Statement, ...]
    pos: Pos


@dataclass(frozen=True)
class While:
    condition: Expr
    body: tuple[Statement, ...]
    pos: Pos


@dataclass(frozen=True)
class Repeat:
    body: tuple[Statement, ...]
    until: Expr
    pos: Pos


@dataclass(frozen=True)
class For:
    variable: str
    start: Expr
    stop: Expr
    step: Expr | None
    body: tuple[Statement, ...]
    pos: Pos


@dataclass(frozen=True)
class Exit:
    pos: Pos


@dataclass(frozen=True)
class Return:
    pos: Pos


Statement = Assign | CallStatement | If | While | Repeat | For | Exit | Return


# ---- declarations and POUs -----------------------------------------------------------------


@dataclass(frozen=True)
class VarDecl:
    name: str
    type: TypeRef
    init: Expr | None
    location: str | None
    pos: Pos


@dataclass(frozen=True)
class VarBlock:
    kind: str  # VAR, VAR_INPUT, VAR_OUTPUT, VAR_IN_OUT, VAR_TEMP, VAR_EXTERNAL, VAR_GLOBAL
    qualifiers: tuple[str, ...]  # CONSTANT, RETAIN, NON_RETAIN
    decls: tuple[VarDecl, ...]
    pos: Pos


@dataclass(frozen=True)
class Pou:
    kind: str  # PROGRAM, FUNCTION_BLOCK, FUNCTION
    name: str
    return_type: TypeRef | None
    var_blocks: tuple[VarBlock, ...]
    body: tuple[Statement, ...]
    pos: Pos


@dataclass(frozen=True)
class SourceUnit:
    """One parsed source file."""

    file: str
    pous: tuple[Pou, ...]
    globals: tuple[VarBlock, ...] = field(default=())
