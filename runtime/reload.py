"""Carrying the values of a running configuration over to a new one (the switch-over of a
reload), as the reload plan says.

The new configuration is instantiated beforehand (outside the cycle); the switch-over
copies values from the old instances into the new ones and never writes to the old ones,
so it can be abandoned at any moment (too slow for the budget) with the old configuration
running on untouched. Declared variables follow the plan (kept, converted, initialised);
internal state that no declaration names (edge memories, action control blocks, the start
time of a step) follows the object it belongs to when that object is carried over.
"""

from __future__ import annotations

import copy
import functools
import time
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass
from typing import Any

from runtime.code_image import Accessor, slot_names
from runtime.contract.artifact import Artifact
from runtime.instances import BoundVariable, Instances
from runtime.reload_plan import (
    CONVERTED,
    KEPT,
    LiveState,
    ReloadPlan,
    chart_instances,
    convert,
    rename_source,
)
from runtime.user_program import UserProgram, share_globals

_SCALARS = (bool, int, float, str, type(None))
CHECK_EVERY = 256  # values between two looks at the clock


class SwitchOverTooLong(Exception):
    """The switch-over ran past its budget; nothing of the old configuration changed."""


def live_state(artifact: Artifact, instances: Instances) -> LiveState:
    """Step flags and action-control flags of the running charts, for the reload plan."""
    programs = {p.name.upper(): p.instance for p in instances.programs}
    objects: dict[str, tuple[Any, dict[str, str], dict[str, str]]] = {}
    pous = {p.name.upper(): p for p in artifact.pous}
    for chart in chart_instances(artifact):
        target = programs.get(chart.program.upper())
        for attr in chart.attrs:
            target = getattr(target, attr, None)
        if target is None:
            continue
        pou = pous[chart.pou.upper()]
        names = {step.upper() for step in chart.chart.steps}
        steps = {v.name.upper(): v.attr for v in pou.variables if v.name.upper() in names}
        controls = {action.upper(): slot for action, slot in chart.chart.controls}
        objects[chart.path.upper()] = (target, steps, controls)

    def read(instance: str, name: str) -> Any:
        found = objects.get(instance.upper())
        if found is None:
            return None
        target, steps, controls = found
        owner, _, flag = name.rpartition(".")
        slot = steps.get(owner.upper()) or controls.get(owner.upper())
        holder = getattr(target, slot, None) if slot is not None else None
        return getattr(holder, flag, None)

    return read


Converter = Callable[[Any], Any] | None


@dataclass
class SwitchOver:
    """Everything the switch-over will do, worked out beforehand (outside the cycle), so
    that between the two cycles only values move."""

    # (old root, attribute path to the parent, last accessor, new parent, last accessor,
    # conversion); the old parent is looked up at switch time: a struct may have been
    # replaced by an assignment since
    leaves: list[tuple[Any, tuple[Accessor, ...], Accessor, Any, Accessor, Converter]]
    # (old object, new object, internal slots): FB and program instances and steps are
    # never replaced, so these pairs hold
    internal: list[tuple[Any, Any, tuple[str, ...]]]
    programs: list[tuple[UserProgram, UserProgram]]


def prepare_switch_over(
    old: Instances, new: Instances, plan: ReloadPlan, renames: Mapping[str, str]
) -> SwitchOver:
    leaves = []
    for change in plan.changes:
        if change.action not in (KEPT, CONVERTED) or change.source is None:
            continue
        source, target = old.by_name[change.source.upper()], new.by_name[change.path.upper()]
        converter: Converter = None
        if change.action == CONVERTED:
            old_type, new_type = change.old_type or "", change.new_type or ""
            converter = functools.partial(convert, old_type=old_type, new_type=new_type)
        attrs, new_attrs = source.path.attrs, target.path.attrs
        new_parent = _resolve(_owner(new, target), new_attrs[:-1])
        leaves.append(
            (_owner(old, source), attrs[:-1], attrs[-1], new_parent, new_attrs[-1], converter)
        )
    old_declared, new_declared = old.image.declared_attrs(), new.image.declared_attrs()
    old_objects = dict(_objects(old))
    internal = []
    for path, target in _objects(new):
        counterpart = old_objects.get(rename_source(path, renames).upper())
        if counterpart is None or type(counterpart).__name__ != type(target).__name__:
            continue
        declared = new_declared.get(type(target), frozenset())
        known = old_declared.get(type(counterpart), frozenset())
        slots = tuple(
            slot
            for slot in slot_names(target)
            if slot not in declared and slot not in known and hasattr(counterpart, slot)
        )
        if slots:
            internal.append((counterpart, target, slots))
    old_programs = {p.name.upper(): p for p in old.programs}
    programs = [
        (previous, program)
        for program in new.programs
        if (previous := old_programs.get(rename_source(program.name, renames).upper()))
    ]
    return SwitchOver(leaves, internal, programs)


def switch_over(prepared: SwitchOver, new: Instances, deadline_ns: int | None) -> int:
    """Fill the new instances from the old ones; returns the number of values carried.
    Raises SwitchOverTooLong past `deadline_ns` (perf_counter time)."""
    parents: dict[tuple[int, tuple[Accessor, ...]], Any] = {}
    carried = 0
    for root, prefix, last, new_parent, new_last, converter in prepared.leaves:
        key = (id(root), prefix)
        parent = parents.get(key)
        if parent is None:
            parent = parents[key] = _resolve(root, prefix)
        value = parent[last] if isinstance(last, int) else getattr(parent, last)
        if isinstance(value, list):
            value = copy.deepcopy(value)  # the new list must not be the old one
        if converter is not None:
            value = converter(value)
        if isinstance(new_last, int):
            new_parent[new_last] = value
        else:
            setattr(new_parent, new_last, value)
        carried += 1
        checked = carried % CHECK_EVERY == 0
        if checked and deadline_ns is not None and time.perf_counter_ns() > deadline_ns:
            raise SwitchOverTooLong()
    for source, target, slots in prepared.internal:
        for slot in slots:
            value = getattr(source, slot)
            setattr(target, slot, value if isinstance(value, _SCALARS) else copy.deepcopy(value))
            carried += 1
    for previous, program in prepared.programs:
        program.state, program.error = previous.state, previous.error
        program.time_ns, program.last_start_ns = previous.time_ns, previous.last_start_ns
        program.stats = copy.copy(previous.stats)
    share_globals(new.globals, new.programs)
    if deadline_ns is not None and time.perf_counter_ns() > deadline_ns:
        raise SwitchOverTooLong()
    return carried


def _resolve(root: Any, attrs: tuple[Accessor, ...]) -> Any:
    target = root
    for accessor in attrs:
        target = target[accessor] if isinstance(accessor, int) else getattr(target, accessor)
    return target


def _owner(instances: Instances, bound: BoundVariable) -> Any:
    return bound.program.instance if bound.program is not None else instances.globals


def _objects(instances: Instances) -> Iterator[tuple[str, Any]]:
    """Every generated object below the program and global instances, by a path of
    attribute names (`Main.fb`, `Main.arr#2` for the third object of a list)."""
    roots: list[tuple[str, Any]] = [(p.name, p.instance) for p in instances.programs]
    if instances.globals is not None:
        roots.append(("", instances.globals))
    stack = list(reversed(roots))
    while stack:
        path, target = stack.pop()
        yield path.upper(), target
        for slot in slot_names(target):
            value = getattr(target, slot, None)
            inner = f"{path}.{slot}" if path else slot
            if isinstance(value, list):
                stack.extend(
                    (f"{inner}#{offset}", item)
                    for offset, item in enumerate(value)
                    if not isinstance(item, (*_SCALARS, list))
                )
            elif not isinstance(value, _SCALARS) and hasattr(type(value), "__slots__"):
                stack.append((inner, value))
