"""Stage 3, check: every rule that can be decided before the code runs.

All problems are collected (not only the first) and returned as diagnostics. The rules live
in `backend.compiler.checks`, one module each: the statement rules walk the code, and the
rules on expressions (`checks.expressions`) run on each node as `Scope` types it;
program-level rules (IDs, one writer per global) are in `checks.programs`, run by the
pipeline once the user programs are known.
"""

from __future__ import annotations

from backend.compiler.checks.actions import check_action_names
from backend.compiler.checks.data import check_data
from backend.compiler.checks.expressions import check_expression
from backend.compiler.checks.initializers import (
    check_constant_initializer,
    check_initializer,
    declaration_order,
)
from backend.compiler.checks.locations import check_location_area
from backend.compiler.checks.methods import (
    check_abstract_instance,
    check_block_declaration,
    check_implementations,
    check_interface,
)
from backend.compiler.checks.open_arrays import check_open_array_data, check_open_array_variables
from backend.compiler.checks.references import check_reference_parameter
from backend.compiler.checks.sfc import check_sfc
from backend.compiler.checks.statements import check_block
from backend.compiler.codes import Code
from backend.compiler.diagnostics import Diagnostic
from backend.compiler.infer import Scope, is_external
from backend.compiler.resolve import PouSymbols, Resolved, Variable
from backend.compiler.types import BOOL


def check(resolved: Resolved) -> list[Diagnostic]:
    diagnostics = check_declarations(resolved)
    for pou in resolved.sorted_pous():
        diagnostics.extend(check_pou(resolved, pou))
    return diagnostics


def check_declarations(resolved: Resolved) -> list[Diagnostic]:
    """The rules on the project's data, globals, structures and interfaces."""
    diagnostics = check_data(resolved)
    if resolved.pous:
        any_pou = resolved.sorted_pous()[0]
        global_scope = Scope(resolved, PouSymbols(any_pou.pou, [], {}), check_expression)
        order = declaration_order(resolved.globals)
        for variable in resolved.globals:
            check_location_area(global_scope, variable)
            check_abstract_instance(global_scope, variable)
            check_initializer(global_scope, variable.type, variable.init)
            check_constant_initializer(global_scope, variable, order)
        for _, info in sorted(resolved.structs.items()):
            for member in info.members:
                check_initializer(global_scope, member.type, member.init)
        check_open_array_data(global_scope, resolved)
        for interface_key in sorted(resolved.interfaces):
            check_interface(global_scope, interface_key)
        diagnostics.extend(global_scope.diagnostics)
    return diagnostics


def check_pou(resolved: Resolved, pou: PouSymbols) -> list[Diagnostic]:
    """The rules on one POU: its variables, its body and its methods."""
    if is_external(pou):
        return []
    scope = Scope(resolved, pou, check_expression)
    order = declaration_order(pou.variables)
    inherited = _inherited(resolved, pou)
    for variable in pou.variables:
        if id(variable) in inherited:
            continue  # checked with the block that declares it
        _check_variable(scope, variable, order)
        if variable.edge is not None and (variable.kind != "VAR_INPUT" or variable.type != BOOL):
            scope.report(variable.pos, Code.EDGE_INPUT, f"{variable.edge} needs a BOOL input")
    check_open_array_variables(scope)
    check_block(scope, pou.pou.body, loop_depth=0)
    if pou.pou.sfc is not None:
        check_sfc(scope, pou.pou.sfc)
        check_action_names(scope, pou.pou.sfc)
    check_block_declaration(scope, pou)
    check_implementations(scope, pou)
    diagnostics = list(scope.diagnostics)
    for routine in pou.own_routines():
        diagnostics.extend(_check_method(resolved, routine))
    return diagnostics


def _check_variable(scope: Scope, variable: Variable, order: dict[int, int]) -> None:
    """What a block's and a method's variables both need: where it is, what it is an
    instance of, its initial value, and what a reference parameter may be."""
    if variable.kind != "VAR_GLOBAL":
        check_location_area(scope, variable)
        check_abstract_instance(scope, variable)
        check_initializer(scope, variable.type, variable.init)
        check_constant_initializer(scope, variable, order)
    check_reference_parameter(scope, variable)


def _inherited(resolved: Resolved, pou: PouSymbols) -> set[int]:
    """The variables a derived block has from its base (by id)."""
    if pou.base is None:
        return set()
    return {id(v) for v in resolved.pous[pou.base].variables}


def _check_method(resolved: Resolved, method: PouSymbols) -> list[Diagnostic]:
    """A method's variables and body, in a scope of its own that sees its block's
    variables."""
    scope = Scope(resolved, method, check_expression)
    order = declaration_order(method.variables)
    for variable in method.variables:
        if variable.kind in ("VAR_INST", "VAR_STAT"):
            message = (
                f"'{variable.name}': padt has no {variable.kind} in methods yet (a method's "
                "variables are temporary); declare it a VAR of the block"
            )
            scope.report(variable.pos, Code.METHOD_STATIC, message)
        _check_variable(scope, variable, order)
    check_open_array_variables(scope)
    check_block(scope, method.pou.body, loop_depth=0)
    return scope.diagnostics
