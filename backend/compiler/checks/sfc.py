"""Sequential function charts: one initial step per chain, known steps and actions, qualifiers
and their times."""

from __future__ import annotations

from collections.abc import Iterator

from backend.compiler import ast
from backend.compiler.ast import key
from backend.compiler.checks.statements import check_block, check_condition
from backend.compiler.codes import Code
from backend.compiler.infer import Scope
from backend.compiler.types import BOOL, ElementaryType

QUALIFIERS = ("N", "R", "S", "P", "P0", "P1", "L", "D", "SD", "DS", "SL")


TIMED_QUALIFIERS = ("L", "D", "SD", "DS", "SL")


def sfc_networks(sfc: ast.Sfc) -> list[list[ast.Step]]:
    """The independent step chains of a POU (steps linked by transitions), in text order."""
    owner = {key(step.name): key(step.name) for step in sfc.steps}

    def root(name: str) -> str:
        while owner[name] != name:
            owner[name] = owner[owner[name]]  # halving the path: chains stay short
            name = owner[name]
        return name

    for transition in sfc.transitions:
        names = [key(n) for n in (*transition.sources, *transition.targets) if key(n) in owner]
        for other in names[1:]:
            owner[root(other)] = root(names[0])
    networks: dict[str, list[ast.Step]] = {}
    for step in sfc.steps:
        networks.setdefault(root(key(step.name)), []).append(step)
    return list(networks.values())


def bool_actions(sfc: ast.Sfc) -> Iterator[ast.NameRef]:
    """The BOOL variables named as a step's action (no ACTION has the name), where named:
    the chart writes each in every cycle (it follows its action's Q), a global too."""
    actions = {key(action.name) for action in sfc.actions}
    for step in sfc.steps:
        for association in step.associations:
            if key(association.action) not in actions:
                yield ast.NameRef(association.action, association.pos)


def step_times(sfc: ast.Sfc) -> Iterator[ast.Expr]:
    """The times of the timed qualifiers (L, D, SD, DS, SL): the chart reads each in every
    cycle."""
    for step in sfc.steps:
        for association in step.associations:
            if association.duration is not None:
                yield association.duration


def check_sfc(scope: Scope, sfc: ast.Sfc) -> None:
    for network in sfc_networks(sfc):
        initial = [step for step in network if step.initial]
        if len(initial) != 1:
            where = initial[1].pos if len(initial) > 1 else network[0].pos
            names = ", ".join(step.name for step in network)
            scope.report(
                where,
                Code.INITIAL_STEP,
                f"the step chain {names} needs exactly one INITIAL_STEP, not {len(initial)}",
            )
    steps = {key(step.name) for step in sfc.steps}
    actions: dict[str, ast.Action] = {}
    for action in sfc.actions:
        if key(action.name) in actions:
            scope.report(
                action.pos, Code.DUPLICATE_ACTION, f"action '{action.name}' is declared twice"
            )
        actions[key(action.name)] = action
        check_block(scope, action.body, loop_depth=0)
    for step in sfc.steps:
        for association in step.associations:
            check_association(scope, association, actions)
    for transition in sfc.transitions:
        for name in (*transition.sources, *transition.targets):
            if key(name) not in steps:
                scope.report(
                    transition.pos,
                    Code.UNKNOWN_STEP,
                    f"transition refers to '{name}', which is no step",
                )
        check_condition(scope, transition.condition)


def check_association(
    scope: Scope, association: ast.ActionAssociation, actions: dict[str, ast.Action]
) -> None:
    if key(association.action) not in actions:
        variable = scope.variable(association.action)
        if variable is None or variable.type != BOOL:
            scope.report(
                association.pos,
                Code.UNKNOWN_ACTION,
                f"'{association.action}' is neither an ACTION nor a BOOL variable",
            )
    qualifier = association.qualifier
    if qualifier not in QUALIFIERS:
        scope.report(
            association.pos, Code.UNKNOWN_QUALIFIER, f"unknown action qualifier '{qualifier}'"
        )
        return
    if qualifier in TIMED_QUALIFIERS:
        if association.duration is None:
            scope.report(
                association.pos,
                Code.QUALIFIER_NEEDS_TIME,
                f"qualifier {qualifier} needs a time: ({qualifier}, T#1s)",
            )
            return
        duration = scope.type_of(association.duration)
        if duration is not None and not (
            isinstance(duration, ElementaryType) and duration.category == "time"
        ):
            scope.report(
                association.pos, Code.QUALIFIER_TIME_TYPE, f"the time of {qualifier} must be a TIME"
            )
    elif association.duration is not None:
        scope.report(
            association.pos, Code.QUALIFIER_TAKES_NO_TIME, f"qualifier {qualifier} takes no time"
        )
