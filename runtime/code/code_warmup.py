"""Fresh code at full speed from its first CPU cycle.

CPython 3.11 runs a code object on its generic instructions up to its eighth call, and only
then "quickens" it: from there on each instruction specializes on the values it meets. A
loop counts towards those eight only when it jumps back unconditionally, which the loops of
WHILE, REPEAT and most FOR statements never do. A program is called once per CPU cycle, so
after a start or an online change its first seven cycles ran its new code about 1.6 times
slower (the reload benchmark's program: 1.3 ms against 0.8 ms), each of them a risk for a
tight target cycle time. CPython 3.12 and later quicken code when it is made.

`warm_up` makes those seven calls when the code is compiled: at a load, or on the worker
thread that prepares a reload, never on the cycle thread. Each call gets arguments and
globals that refuse every access, so it stops at the code's first reference and no user
code has any effect. The eighth call is the first real one: every instruction specializes
on the real values, not on the stand-ins.

Code a reload keeps (its unit's source did not change) is not reused as it ran: its
instructions are specialized for the classes the reload replaces. `unspecialized` copies
it instead, and the copy is warmed up like new code.
"""

from __future__ import annotations

import contextlib
import inspect
import sys
from collections.abc import Iterable, Iterator
from types import CellType, CodeType, FunctionType
from typing import Any

# the calls before CPython quickens a code object: one call short of it, so that the first
# real call does it
CALLS_BEFORE_QUICKENING = 7 if sys.version_info[:2] == (3, 11) else 0


class _Refusing:
    """A stand-in for an argument: no attributes, items, calls or arithmetic, so that any
    use of it raises. (`is`, `==` and truth tests answer without touching anything.)"""

    __slots__ = ()


_REFUSING = _Refusing()


def warm_up(codes: Iterable[CodeType]) -> None:
    """Bring every function in freshly compiled units (module code) one call short of its
    quickening. For code already run, it must not be used: the stand-ins would count as
    misses of the instructions that met them."""
    if not CALLS_BEFORE_QUICKENING:
        return
    for code in codes:
        for function in _functions(code):
            _call_refused(function, CALLS_BEFORE_QUICKENING)


def unspecialized(code: CodeType) -> CodeType:
    """A copy of `code` (a unit's module code, every function in it included) that has
    never run: the same instructions, none of them specialized. Code kept over a reload
    runs on objects whose classes the reload replaced, so its instructions specialized on
    the old classes miss, and CPython 3.11 specializes an instruction anew only after some
    fifty misses: a program called once per cycle ran 50 to 90 cycles about 1.7 times
    slower after a reload that changed some other POU."""
    consts = tuple(unspecialized(c) if isinstance(c, CodeType) else c for c in code.co_consts)
    return code.replace(co_consts=consts)


def _functions(code: CodeType) -> Iterator[CodeType]:
    """The code of every function defined in `code`, at any depth (the methods of a class
    are in the code of its body; a class body itself is not a function)."""
    for const in code.co_consts:
        if isinstance(const, CodeType):
            if const.co_flags & inspect.CO_OPTIMIZED:
                yield const
            yield from _functions(const)


def _call_refused(code: CodeType, calls: int) -> None:
    # no builtins, no globals, empty cells: a name or a free variable raises as it is read
    cells = tuple(CellType() for _ in code.co_freevars)
    function = FunctionType(code, {"__builtins__": {}}, code.co_name, None, cells or None)
    positional = code.co_varnames[: code.co_argcount]
    keywords = code.co_varnames[code.co_argcount : code.co_argcount + code.co_kwonlyargcount]
    for _ in range(calls):
        # a comprehension's hidden argument is an iterator that the interpreter trusts
        # without a test: an empty one, never a stand-in
        args = [iter(()) if name == ".0" else _REFUSING for name in positional]
        with contextlib.suppress(Exception):  # the stand-ins are there to make it raise
            result: Any = function(*args, **dict.fromkeys(keywords, _REFUSING))
            if code.co_flags & inspect.CO_GENERATOR:  # its body runs at the first next()
                next(result)
