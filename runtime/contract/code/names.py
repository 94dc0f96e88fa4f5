"""The names of generated code: those it finds in its namespace, and those the compiler
gives units, methods and variables. The check of the typed form (form_check.py) allows
exactly these; the Python tier binds the runtime's (runtime/code/intrinsics.py) and the
compiler calls them (backend/compiler/conversions.py).
"""

from __future__ import annotations

import functools
import re

from runtime.contract.intrinsic_table import INTRINSICS as INTRINSIC_TABLE
from runtime.contract.system_variables import SYSTEM_VARIABLES

# The names generated code finds in its global namespace, from the one table of them
# (`intrinsic_table.py`; runtime/code/intrinsics.py `namespace` is checked against it).
# Called ones are only ever called: never read as a value, so no attribute of the functions
# behind them (`__globals__`) can be reached. The objects are only read (`_SYS`, `_G`,
# `_P`, `_tick`), `_math` only as `_safe_math(_math.f, x)`, `_SfcStep` only as the target
# of an alias (`STRUCT_SFC_STEP = _SfcStep`), and `_reference_roots` never named by
# generated code.
CALLED_INTRINSICS = frozenset(i.name for i in INTRINSIC_TABLE if i.called)
OBJECT_INTRINSICS = frozenset(i.name for i in INTRINSIC_TABLE if not i.called)
INTRINSICS = CALLED_INTRINSICS | OBJECT_INTRINSICS
# the builtins generated code calls (the whole of its `__builtins__` but `__build_class__`)
BUILTINS = frozenset({"float", "int", "abs", "len", "max", "min", "range", "str"})
# the functions of `math` the compiler passes to `_safe_math` (SQRT, LN, LOG, EXP, ...)
MATH_FUNCTIONS = frozenset(
    {"sqrt", "log", "log10", "exp", "sin", "cos", "tan", "asin", "acos", "atan"}
)
# the attributes of `_SYS`: one per system variable, and the running program's time
SYSTEM_ATTRS = frozenset({v.name for v in SYSTEM_VARIABLES} | {"now_ns"})
WRITABLE_SYSTEM_ATTRS = frozenset(v.name for v in SYSTEM_VARIABLES if v.writable)

IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")
UNIT_NAME = re.compile(r"(?:POU|FN|STRUCT)_[A-Za-z0-9_]+\Z|GLOBALS\Z")
CLASS_NAME = re.compile(r"(?:POU|STRUCT)_[A-Za-z0-9_]+\Z|GLOBALS\Z")
FUNCTION_NAME = re.compile(r"FN_[A-Za-z0-9_]+\Z")
# methods of a generated class: METHODs, property accessors, SFC actions
METHOD_NAME = re.compile(r"(?:M__|GET__|SET__|_action_)[A-Za-z0-9_]+\Z")


@functools.lru_cache(maxsize=1 << 16)  # a program names its variables many times
def is_plain_name(name: str) -> bool:
    """An ASCII identifier without a leading `__` (no dunder, no name-mangled private)."""
    return IDENTIFIER.match(name) is not None and not name.startswith("__")


def is_local_name(name: str) -> bool:
    """A name a function may bind: an ASCII identifier, not a dunder (the compiler's own
    locals are `__t1`, `__w`; a user's never have `__`)."""
    return IDENTIFIER.match(name) is not None and not (
        name.startswith("__") and name.endswith("__")
    )


@functools.lru_cache(maxsize=1 << 16)
def is_data_attr(name: str) -> bool:
    """A name generated code may read or write as a variable of an object: plain, and
    neither a method's name nor `KIND__`."""
    return is_plain_name(name) and METHOD_NAME.match(name) is None and name != "KIND__"


def is_runtime_name(name: str) -> bool:
    """A name of the namespace generated code runs in: the runtime's, a builtin, a unit's."""
    return name in INTRINSICS or name in BUILTINS or UNIT_NAME.match(name) is not None
