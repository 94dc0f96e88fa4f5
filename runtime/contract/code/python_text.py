"""The Python tier's text of a typed-form expression (runtime/contract/code/typed_form.py).

Every compound node prints inside its own parentheses, so that no node depends on the
precedence of what holds it (an index's brackets hold an operation on their own).
"""

from __future__ import annotations

import math

from runtime.contract.code.typed_form import (
    Assigned,
    Binary,
    Call,
    Chain,
    Choice,
    Const,
    Expr,
    Index,
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
        case Index(base=base, offset=Binary(op=op, left=left, right=right)):
            # the brackets hold the offset's operation together: `a[i - 1]`
            return f"{python_text(base)}[{python_text(left)} {op} {python_text(right)}]"
        case Index(base=base, offset=offset):
            return f"{python_text(base)}[{python_text(offset)}]"
        case Slice(value=value, start=start, stop=stop):
            low, high = ("" if bound is None else str(bound) for bound in (start, stop))
            return f"{python_text(value)}[{low}:{high}]"
        case Unary(op="not", operand=operand):
            return f"(not {python_text(operand)})"
        case Unary(op=op, operand=operand):
            return f"({op}{python_text(operand)})"
        case Binary(op=op, left=left, right=right):
            return f"({python_text(left)} {op} {python_text(right)})"
        case Chain(op=op, values=values):
            return "(" + f" {op} ".join(python_text(value) for value in values) + ")"
        case Choice(test=test, then=then, orelse=orelse):
            return f"({python_text(then)} if {python_text(test)} else {python_text(orelse)})"
        case Assigned(name=name, value=value):
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
