"""No name of the user may be one that the generated code of its POU uses itself.

A variable of a FUNCTION, and a VAR_TEMP of a PROGRAM or FUNCTION_BLOCK, is a Python local:
named `_ix`, `min` or `s`, it would hide the helper, the built-in or the instance that the
code needs (a call of MIN becomes `min(...)`). Which names the code needs depends on what it
does, so the POU is generated once more with its locals named apart (a name with `__`, which
no user name has) and every name left in that code's scope is one of its own: exact, and
valid programs keep their code. A variable of a PROGRAM or FUNCTION_BLOCK is a slot of its
class and must not be one of the class's own (an edge memory, an action).

Dunders and Python's private names are out of reach already: an identifier has no `__`.
"""

from __future__ import annotations

import symtable
from dataclasses import replace

from backend.compiler.codes import Code
from backend.compiler.diagnostics import Diagnostic
from backend.compiler.generate import (
    class_members,
    class_name,
    function_name,
    generate_pou,
    python_locals,
)
from backend.compiler.limits import MAX_UNIT_CODE
from backend.compiler.resolve import PouSymbols, Resolved, Variable


def check_generated_names(resolved: Resolved, pou: PouSymbols) -> list[Diagnostic]:
    """Variables of `pou` named like something its code uses; `pou` is free of errors and
    its code was generated within the limits."""
    clashing: list[Variable] = []
    if pou.kind != "FUNCTION":
        members = class_members(pou)
        clashing += [v for v in pou.variables if v.kind != "VAR_GLOBAL" and v.attr in members]
    locals_ = python_locals(pou)
    if locals_:
        used = _names_of_the_code(resolved, pou, locals_)
        clashing += [v for v in locals_ if v.attr in used]
    return [
        Diagnostic.at(
            variable.pos,
            Code.GENERATED_NAME,
            f"'{variable.name}' is a name the code generated for '{pou.name}' uses itself; "
            "rename it",
        )
        for variable in clashing
    ]


def _names_of_the_code(resolved: Resolved, pou: PouSymbols, locals_: list[Variable]) -> set[str]:
    """The names in the scope of the POU's code (its function, or its class's `__call__`,
    with their comprehensions) once its locals are named apart."""
    apart = {id(v): replace(v, attr=f"{v.attr}__") for v in locals_}
    probe = replace(
        pou,
        variables=[apart.get(id(v), v) for v in pou.variables],
        by_key={name: apart.get(id(v), v) for name, v in pou.by_key.items()},
    )  # its methods, base and properties as they are
    # longer names make longer code (three times at worst): the POU's own code was within
    # the limit, and this copy is only read
    source = generate_pou(resolved, probe, max_size=3 * MAX_UNIT_CODE).source
    module = symtable.symtable(source, pou.name, "exec")
    if pou.kind == "FUNCTION":
        scope = module.lookup(function_name(pou.name)).get_namespace()
    else:
        methods = module.lookup(class_name(pou.name)).get_namespace()
        scope = methods.lookup("__call__").get_namespace()
    names: set[str] = set()
    pending = [scope]
    while pending:
        table = pending.pop()
        names.update(table.get_identifiers())
        pending.extend(table.get_children())
    return names
