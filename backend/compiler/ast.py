"""The abstract syntax tree: what the parse stage produces and the resolve stage consumes.

Every node carries its source position so that any later stage can report
`file:line:col`. Names keep the spelling of the source; ST is case-insensitive, so
comparisons go through `key()` (upper case) everywhere.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, fields, is_dataclass, replace
from typing import Any

from backend.compiler.diagnostics import Diagnostic
from backend.compiler.source import Pos


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


@dataclass(frozen=True)
class ArrayType:
    ranges: tuple[tuple[Expr, Expr] | None, ...]  # None: an open range `*`
    element: TypeRef
    pos: Pos


@dataclass(frozen=True)
class VariadicType:
    pos: Pos


@dataclass(frozen=True)
class RefType:
    """`REF_TO T` (IEC 61131-3 ed. 3), or CODESYS `POINTER TO T` (`pointer`)."""

    target: TypeRef
    pos: Pos
    pointer: bool = False
    implicit: bool = False  # CODESYS `REFERENCE TO T`: used as the T it refers to


@dataclass(frozen=True)
class EnumSpec:
    base: str | None
    values: tuple[tuple[str, Expr | None, Pos], ...]
    pos: Pos


@dataclass(frozen=True)
class StructSpec:
    members: tuple[VarDecl, ...]
    pos: Pos


@dataclass(frozen=True)
class SubrangeSpec:
    base: str
    low: Expr
    high: Expr
    pos: Pos


TypeRef = (
    NamedType
    | StringType
    | ArrayType
    | VariadicType
    | RefType
    | EnumSpec
    | StructSpec
    | SubrangeSpec
)


# ---- expressions -------------------------------------------------------------------------


@dataclass(frozen=True)
class IntLiteral:
    value: int
    pos: Pos
    type_name: str | None = None  # `INT#5`
    based: bool = False  # 16#FFFF: a bit pattern, which may stand for a negative value


@dataclass(frozen=True)
class RealLiteral:
    value: float
    text: str
    pos: Pos
    type_name: str | None = None


@dataclass(frozen=True)
class BoolLiteral:
    value: bool
    pos: Pos
    type_name: str | None = None


@dataclass(frozen=True)
class TimeLiteral:
    nanoseconds: int
    type_name: str  # TIME, LTIME, DATE, TIME_OF_DAY, DATE_AND_TIME (and L-forms)
    pos: Pos


@dataclass(frozen=True)
class StringLiteral:
    value: str
    wide: bool
    pos: Pos
    type_name: str | None = None


@dataclass(frozen=True)
class EnumLiteral:
    type_name: str
    value: str
    pos: Pos
    qualified: bool = False  # written `Color.Red` (CODESYS/TwinCAT), not `Color#Red`


@dataclass(frozen=True)
class NullLiteral:
    """NULL, the reference to nothing (IEC 61131-3 ed. 3)."""

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
class IndexRef:
    base: Expr
    indices: tuple[Expr, ...]
    pos: Pos


@dataclass(frozen=True)
class BitRef:
    """`x.3` or `x.%X3` (a bit), `x.%B1` / `%W` / `%D` (a byte, word, double word)."""

    base: Expr
    bit: int  # index of the part, counted in parts of `width` bits
    pos: Pos
    width: int = 1


@dataclass(frozen=True)
class Deref:
    base: Expr
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
    value: Expr | None  # None only for an unconnected output `Q =>`
    is_output: bool  # `name => variable`
    pos: Pos
    negated: bool = False  # `NOT Q => variable`


@dataclass(frozen=True)
class Call:
    name: str
    args: tuple[Argument, ...]
    pos: Pos
    receiver: Expr | None = None  # `instance.method(...)`
    # the function block instance called, given by an expression (`fbs[1](...)`); `name`
    # is then its spelling, for messages
    instance: Expr | None = None


@dataclass(frozen=True)
class ArrayInit:
    items: tuple[tuple[Expr | None, Initializer], ...]  # (repeat count, value)
    pos: Pos


@dataclass(frozen=True)
class StructInit:
    members: tuple[tuple[str, Initializer], ...]
    pos: Pos


Literal = (
    IntLiteral | RealLiteral | BoolLiteral | TimeLiteral | StringLiteral | EnumLiteral | NullLiteral
)
Expr = Literal | NameRef | MemberRef | IndexRef | BitRef | Deref | Unary | Binary | Call
Initializer = Expr | ArrayInit | StructInit


# ---- statements --------------------------------------------------------------------------


@dataclass(frozen=True)
class Assign:
    target: Expr
    value: Initializer
    pos: Pos
    bind: bool = False  # CODESYS `r REF= x`: the REFERENCE TO r now refers to x (value REF(x))
    attempt: bool = False  # `itf ?= x`: x where it fits the target's type, else NULL


@dataclass(frozen=True)
class CallStatement:
    call: Call
    pos: Pos


@dataclass(frozen=True)
class ExprStatement:
    """An expression other than a call as a statement (`+x;`): CODESYS evaluates it and
    drops its value (W0807)."""

    expr: Expr
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
class CaseRange:
    low: Expr
    high: Expr
    pos: Pos


@dataclass(frozen=True)
class Case:
    selector: Expr
    branches: tuple[tuple[tuple[Expr | CaseRange, ...], tuple[Statement, ...]], ...]
    orelse: tuple[Statement, ...]
    pos: Pos


@dataclass(frozen=True)
class Exit:
    pos: Pos


@dataclass(frozen=True)
class Continue:
    pos: Pos


@dataclass(frozen=True)
class Return:
    pos: Pos


Statement = (
    Assign
    | CallStatement
    | ExprStatement
    | If
    | Case
    | While
    | Repeat
    | For
    | Exit
    | Continue
    | Return
)


# ---- declarations and POUs -----------------------------------------------------------------


@dataclass(frozen=True)
class VarDecl:
    name: str
    type: TypeRef
    init: Initializer | None
    location: str | None
    pos: Pos
    edge: str | None = None  # R_EDGE or F_EDGE on a BOOL input


@dataclass(frozen=True)
class VarBlock:
    kind: str  # VAR, VAR_INPUT, VAR_OUTPUT, VAR_IN_OUT, VAR_TEMP, VAR_EXTERNAL, VAR_GLOBAL
    qualifiers: tuple[str, ...]  # CONSTANT, RETAIN, NON_RETAIN
    decls: tuple[VarDecl, ...]
    pos: Pos


@dataclass(frozen=True)
class ActionAssociation:
    action: str
    qualifier: str  # N (default), R, S, P, P0, P1, L, D, SD, DS, SL
    duration: Expr | None  # the time of L, D, SD, DS, SL
    pos: Pos


@dataclass(frozen=True)
class Step:
    name: str
    initial: bool
    associations: tuple[ActionAssociation, ...]
    pos: Pos


@dataclass(frozen=True)
class Transition:
    name: str | None
    priority: int | None
    sources: tuple[str, ...]
    targets: tuple[str, ...]
    condition: Expr
    pos: Pos


@dataclass(frozen=True)
class Action:
    name: str
    body: tuple[Statement, ...]
    pos: Pos
    graphic: Any = None  # a drawn body, lowered into `body` as a POU's (see `Pou.graphic`)


@dataclass(frozen=True)
class Sfc:
    steps: tuple[Step, ...]
    transitions: tuple[Transition, ...]
    actions: tuple[Action, ...]


@dataclass(frozen=True)
class Method:
    """`METHOD [access] [ABSTRACT|FINAL|OVERRIDE] Name [: Type] ... END_METHOD` of a function
    block, program or interface (a prototype there, without a body)."""

    name: str
    access: str | None  # PUBLIC, PRIVATE, PROTECTED, INTERNAL; None: not written
    modifiers: tuple[str, ...]  # ABSTRACT, FINAL, OVERRIDE
    return_type: TypeRef | None
    var_blocks: tuple[VarBlock, ...]
    body: tuple[Statement, ...]
    pos: Pos


@dataclass(frozen=True)
class Accessor:
    """The GET or SET of a property."""

    kind: str  # GET or SET
    var_blocks: tuple[VarBlock, ...]
    body: tuple[Statement, ...]
    pos: Pos


@dataclass(frozen=True)
class Property:
    """`PROPERTY [access] Name : Type GET ... END_GET SET ... END_SET END_PROPERTY`."""

    name: str
    access: str | None
    modifiers: tuple[str, ...]
    type: TypeRef
    accessors: tuple[Accessor, ...]
    pos: Pos


@dataclass(frozen=True)
class Pou:
    kind: str  # PROGRAM, FUNCTION_BLOCK, FUNCTION
    name: str
    return_type: TypeRef | None
    var_blocks: tuple[VarBlock, ...]
    body: tuple[Statement, ...]
    pos: Pos
    sfc: Sfc | None = None
    methods: tuple[Method, ...] = ()
    properties: tuple[Property, ...] = ()
    extends: tuple[str, ...] = ()  # the base function block (IEC allows one)
    implements: tuple[str, ...] = ()
    modifiers: tuple[str, ...] = ()  # ABSTRACT, FINAL
    # a body drawn in FBD or LD (`backend.compiler.graphics.model.GraphicBody`); `body` is
    # then its lowering to statements, each at the line of the element it comes from
    graphic: Any = None


@dataclass(frozen=True)
class Interface:
    """`INTERFACE Name [EXTENDS I1, I2] METHOD ... END_METHOD ... END_INTERFACE`."""

    name: str
    extends: tuple[str, ...]
    methods: tuple[Method, ...]
    properties: tuple[Property, ...]
    pos: Pos


@dataclass(frozen=True)
class TaskDecl:
    name: str
    params: tuple[tuple[str, Expr], ...]  # INTERVAL, PRIORITY, SINGLE
    pos: Pos


@dataclass(frozen=True)
class ProgramInstanceDecl:
    name: str
    task: str | None
    pou: str
    args: tuple[Argument, ...]
    pos: Pos


@dataclass(frozen=True)
class ResourceDecl:
    name: str
    globals: tuple[VarBlock, ...]
    tasks: tuple[TaskDecl, ...]
    programs: tuple[ProgramInstanceDecl, ...]
    pos: Pos


@dataclass(frozen=True)
class ConfigInit:
    """A VAR_CONFIG entry: `Resource.Program.inst.var AT %IX1.0 : BOOL;`."""

    path: tuple[str, ...]
    location: str | None
    type: TypeRef
    init: Initializer | None
    pos: Pos


@dataclass(frozen=True)
class AccessDecl:
    """A VAR_ACCESS entry: `name : Resource.Program.var : TYPE READ_ONLY;`."""

    name: str
    path: tuple[str, ...]  # the last part may be a direct address
    type: TypeRef
    writable: bool  # READ_WRITE; READ_ONLY is the default
    pos: Pos


@dataclass(frozen=True)
class Configuration:
    name: str
    globals: tuple[VarBlock, ...]
    resources: tuple[ResourceDecl, ...]
    pos: Pos
    access: tuple[AccessDecl, ...] = ()
    var_config: tuple[ConfigInit, ...] = ()


@dataclass(frozen=True)
class TypeDecl:
    name: str
    spec: TypeRef
    init: Initializer | None
    pos: Pos


@dataclass(frozen=True)
class SourceUnit:
    """One parsed source file."""

    file: str
    pous: tuple[Pou, ...]
    globals: tuple[VarBlock, ...] = field(default=())
    types: tuple[TypeDecl, ...] = field(default=())
    warnings: tuple[Diagnostic, ...] = field(default=())
    configurations: tuple[Configuration, ...] = field(default=())
    # direct addresses its statements name (`%MW10 := 42;`), upper-case, first use first
    addresses: tuple[tuple[str, Pos], ...] = field(default=())
    interfaces: tuple[Interface, ...] = field(default=())


def spelling(expr: Expr) -> str:
    """How a variable reads in messages: `fbs[...]`, `s.fb`, `p^`."""
    match expr:
        case NameRef(name=name):
            return name
        case MemberRef(base=base, member=member):
            return f"{spelling(base)}.{member}"
        case IndexRef(base=base):
            return f"{spelling(base)}[...]"
        case Deref(base=base):
            return f"{spelling(base)}^"
        case BitRef(base=base, bit=bit):
            return f"{spelling(base)}.{bit}"
        case _:
            return "..."


def rebuilt(
    value: Any, after: Callable[[Any], Any], enter: Callable[[Any], None] | None = None
) -> Any:
    """`value` (a node, a tuple of them, or a plain value) rebuilt bottom-up: each node's
    children first, then `after(node)`, which gives the node or what replaces it; `enter`
    sees each node before its children. A subtree nothing changed in is returned as it
    is (the AST is immutable, so sharing it is safe)."""
    if isinstance(value, tuple):
        items = tuple(rebuilt(item, after, enter) for item in value)
        return value if all(a is b for a, b in zip(items, value, strict=True)) else items
    if not is_dataclass(value) or isinstance(value, Pos | type):
        return value
    if enter is not None:
        enter(value)
    changed = {}
    for item in fields(value):
        old = getattr(value, item.name)
        new = rebuilt(old, after, enter)
        if new is not old:
            changed[item.name] = new
    return after(replace(value, **changed) if changed else value)
