"""The statements of the typed form: one frozen dataclass per kind, each with the ST line it
comes from (0: none), the line a fault in it names and a breakpoint stops at. Their
expressions are typed-form expressions (typed_form.py)."""

from __future__ import annotations

from dataclasses import dataclass

from runtime.contract.code.typed_form import BinaryOp, Expr


@dataclass(frozen=True, slots=True)
class Assign:
    """`target = value`; with `augmented`, `target op= value`."""

    target: Expr
    value: Expr
    line: int
    augmented: BinaryOp | None = None


@dataclass(frozen=True, slots=True)
class Evaluate:
    """An expression evaluated for what it does (a call); its value is dropped."""

    value: Expr
    line: int


@dataclass(frozen=True, slots=True)
class Elif:
    """A further branch of an `If`: an ELSIF, a label of a CASE."""

    test: Expr
    body: tuple[Stmt, ...]
    line: int


@dataclass(frozen=True, slots=True)
class If:
    """`body` where `test` holds, else the first of `elifs` whose test holds, else
    `orelse`. The branches are a list rather than an `If` in each `orelse`, so that a
    thousand ELSIFs are a thousand items, not a form nested a thousand deep."""

    test: Expr
    body: tuple[Stmt, ...]
    orelse: tuple[Stmt, ...]
    line: int
    elifs: tuple[Elif, ...] = ()


@dataclass(frozen=True, slots=True)
class While:
    test: Expr
    body: tuple[Stmt, ...]
    line: int


@dataclass(frozen=True, slots=True)
class ForEach:
    """`for name in numbers:` over a range of counter values; `orelse` runs when the loop
    was not left by a break."""

    name: str
    numbers: Expr
    body: tuple[Stmt, ...]
    orelse: tuple[Stmt, ...]
    line: int


@dataclass(frozen=True, slots=True)
class Break:
    line: int


@dataclass(frozen=True, slots=True)
class Continue:
    line: int


@dataclass(frozen=True, slots=True)
class Return:
    value: Expr | None
    line: int


@dataclass(frozen=True, slots=True)
class Pass:
    line: int


Stmt = Assign | Evaluate | If | While | ForEach | Break | Continue | Return | Pass
