"""The Python tier's text of a typed-form expression (runtime/contract/code/typed_form.py).

Every compound node prints inside its own parentheses, so that no node depends on the
precedence of what holds it; where an expression stands alone (in brackets, as the test of
an `if` or a `while`) it prints without them.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from typing import NamedTuple

from runtime.contract.code.statements import (
    Assign,
    Break,
    Continue,
    Elif,
    Evaluate,
    ForEach,
    If,
    Pass,
    Return,
    Stmt,
    While,
)
from runtime.contract.code.typed_form import (
    Assigned as AssignedValue,
)
from runtime.contract.code.typed_form import (
    Binary,
    Call,
    Chain,
    Choice,
    Const,
    Expr,
    Index,
    Logic,
    Member,
    Members,
    Named,
    Repeated,
    Sequence,
    Slice,
    This,
    Unary,
    Var,
    Wrap,
)
from runtime.contract.code.units import Alias, Class, Function, Inherited, Unit

INDENT = "    "
_ROOT = {"instance": "s.", "globals": "_G.", "system": "_SYS.", "programs": "_P.", "local": ""}


def python_text(node: Expr) -> str:
    match node:
        case Const(value=value):
            if isinstance(value, float) and not math.isfinite(value):
                return f"float({str(value)!r})"  # no literal spells inf or nan
            return repr(value)
        case Var(name=name, where=where):
            return _ROOT[where] + name
        case This():
            return "s"
        case Named(name=name):
            return name
        case Member(base=base, name=name):
            return f"{python_text(base)}.{name}"
        case Index(base=base, offset=offset):
            return f"{python_text(base)}[{_bare(offset)}]"
        case Slice(value=value, start=start, stop=stop):
            low, high = ("" if bound is None else str(bound) for bound in (start, stop))
            return f"{python_text(value)}[{low}:{high}]"
        case Unary(op="not", operand=operand):
            return f"(not {python_text(operand)})"
        case Unary(op=op, operand=operand):
            return f"({op}{python_text(operand)})"
        case Binary(op=op, left=left, right=right):
            return f"({python_text(left)} {op} {python_text(right)})"
        case Chain(op=op, values=values) | Logic(op=op, values=values):
            return "(" + f" {op} ".join(python_text(value) for value in values) + ")"
        case Choice(test=test, then=then, orelse=orelse):
            return f"({python_text(then)} if {python_text(test)} else {python_text(orelse)})"
        case AssignedValue(name=name, value=value):
            return f"({name} := {python_text(value)})"
        case Wrap():
            return _wrap_text(node)
        case Call(callee=callee, args=args, keywords=keywords):
            called = callee if isinstance(callee, str) else python_text(callee)
            passed = [python_text(arg) for arg in args]
            passed += [f"{name}={python_text(value)}" for name, value in keywords]
            return f"{called}({', '.join(passed)})"
        case Sequence(items=items, as_tuple=True):
            texts = [python_text(item) for item in items]
            return f"({texts[0]},)" if len(texts) == 1 else f"({', '.join(texts)})"
        case Sequence(items=items):
            return f"[{', '.join(python_text(item) for item in items)}]"
        case Repeated(item=item, count=count, each_new=False):
            return f"[{python_text(item)}] * {count}"
        case Repeated(item=item, count=count):
            return f"[{python_text(item)} for _ in range({count})]"
        case Members(items=items):
            return "{" + ", ".join(f"{name!r}: {python_text(v)}" for name, v in items) + "}"
    raise AssertionError(f"no Python text for {node!r}")


def _bare(node: Expr) -> str:
    """The text of an expression that stands alone (an offset in brackets, the test of an
    `if`): without the parentheses of its own operation."""
    match node:
        case Binary(op=op, left=left, right=right):
            return f"{python_text(left)} {op} {python_text(right)}"
        case Chain(op=op, values=values) | Logic(op=op, values=values):
            return f" {op} ".join(python_text(value) for value in values)
        case Unary(op="not", operand=operand):
            return f"not {python_text(operand)}"
    return python_text(node)


def _wrap_text(node: Wrap) -> str:
    code, bits = python_text(node.value), node.bits
    mask, half = (1 << bits) - 1, 1 << (bits - 1)
    if bits >= 32:
        # the wrap's constants are numbers of several digits for CPython (30 bits a digit),
        # slower to add and mask than testing a value that is in range almost always: a
        # DINT store 67 -> 34 ns, a LINT or TIME one 53 -> 35. Nested wraps may share the
        # name: an inner one is read before an outer one binds it
        code = f"({code} + {node.offset})" if node.offset else code
        low, high = (-half, half - 1) if node.signed else (0, mask)
        wrap = f"(__w + {half} & {mask}) - {half}" if node.signed else f"__w & {mask}"
        return f"(__w if {low} <= (__w := {code}) <= {high} else {wrap})"
    if node.signed:  # the offset costs nothing: the wrap adds a constant anyway
        return f"((({code}) + {half + node.offset} & {mask}) - {half})"
    code = f"({code} + {node.offset})" if node.offset else code
    return f"(({code}) & {mask})"


class PrintedLine(NamedTuple):
    """A line of a unit's module text: its ST line (0 for the frame), and the statement,
    ELSIF branch or function whose header it is (None for the frame, an `else:`). The
    C tier (runtime/code/native/) numbers its statements by these, so that a fault there
    names the generated line a fault of the Python tier names."""

    text: str
    st_line: int
    header: Stmt | Elif | Function | None = None


def _statement_lines(
    statements: tuple[Stmt, ...] | list[Stmt], depth: int
) -> Iterator[PrintedLine]:
    """The lines of typed-form statements indented to `depth`."""
    pad = INDENT * depth
    for statement in statements:
        match statement:
            case Assign(target=target, value=value, augmented=op, line=line):
                sign = "=" if op is None else f"{op}="
                text = f"{pad}{python_text(target)} {sign} {python_text(value)}"
                yield PrintedLine(text, line, statement)
            case Evaluate(value=value, line=line):
                yield PrintedLine(pad + python_text(value), line, statement)
            case If(test=test, body=body, orelse=orelse, line=line, elifs=elifs):
                yield PrintedLine(f"{pad}if {_bare(test)}:", line, statement)
                yield from _statement_lines(body, depth + 1)
                for branch in elifs:
                    yield PrintedLine(f"{pad}elif {_bare(branch.test)}:", branch.line, branch)
                    yield from _statement_lines(branch.body, depth + 1)
                if orelse:
                    yield PrintedLine(f"{pad}else:", line)
                    yield from _statement_lines(orelse, depth + 1)
            case While(test=test, body=body, line=line):
                yield PrintedLine(f"{pad}while {_bare(test)}:", line, statement)
                yield from _statement_lines(body, depth + 1)
            case ForEach(name=name, numbers=numbers, body=body, orelse=orelse, line=line):
                text = f"{pad}for {name} in {python_text(numbers)}:"
                yield PrintedLine(text, line, statement)
                yield from _statement_lines(body, depth + 1)
                if orelse:
                    yield PrintedLine(f"{pad}else:", line)
                    yield from _statement_lines(orelse, depth + 1)
            case Break(line=line):
                yield PrintedLine(pad + "break", line, statement)
            case Continue(line=line):
                yield PrintedLine(pad + "continue", line, statement)
            case Return(value=value, line=line):
                text = pad + ("return" if value is None else f"return {python_text(value)}")
                yield PrintedLine(text, line, statement)
            case Pass(line=line):
                yield PrintedLine(pad + "pass", line, statement)


def python_lines(
    statements: tuple[Stmt, ...] | list[Stmt], depth: int
) -> Iterator[tuple[str, int]]:
    """The lines of typed-form statements indented to `depth`, each with its ST line."""
    for line in _statement_lines(statements, depth):
        yield line.text, line.st_line


def unit_lines(unit: Unit) -> Iterator[tuple[str, int]]:
    """The lines of a unit's module text, each with its ST line (0 for the frame)."""
    for line in printed_lines(unit):
        yield line.text, line.st_line


def printed_lines(unit: Unit) -> Iterator[PrintedLine]:
    """The lines of a unit's module text, in order (the first is line 1)."""
    match unit:
        case Alias(name=name, target=target):
            yield PrintedLine(f"{name} = {target}", 0)
        case Function():
            yield from _function_lines(unit, 0)
        case Class(name=name, slots=slots, kinds=kinds, functions=functions):
            yield PrintedLine(f"class {name}:", 0)
            yield PrintedLine(f"{INDENT}__slots__ = {tuple(slot.name for slot in slots)!r}", 0)
            if kinds:
                yield PrintedLine(f"{INDENT}KIND__ = {kinds!r}", 0)
            yield PrintedLine("", 0)
            yield PrintedLine(f"{INDENT}def __init__(s):", 0)
            if not slots:
                yield PrintedLine(f"{INDENT * 2}pass", 0)
            for slot in slots:
                yield PrintedLine(f"{INDENT * 2}s.{slot.name} = {python_text(slot.initial)}", 0)
            for function in functions:
                yield PrintedLine("", 0)
                if isinstance(function, Inherited):
                    text = f"{INDENT}{function.name} = {function.owner}.{function.name}"
                    yield PrintedLine(text, 0)
                else:
                    yield from _function_lines(function, 1)


def _function_lines(function: Function, depth: int) -> Iterator[PrintedLine]:
    params = [f"{param.name}={python_text(param.default)}" for param in function.params]
    if function.method:
        params.insert(0, "s")
    yield PrintedLine(f"{INDENT * depth}def {function.name}({', '.join(params)}):", 0, function)
    yield from _statement_lines(function.body, depth + 1)
