"""Carrying the values of a running configuration over to a new one (the switch-over of a
reload), as the reload plan says.

The new configuration is instantiated beforehand (outside the cycle), and so is the list
of what moves: objects the new configuration adopts as they are (`adoption.py`: nothing
below them changes but their code) and values copied into fresh objects (everything else
the plan keeps or converts). Until its point of no return the switch-over writes only
into the new instances, so it can be abandoned (too slow for the budget) with the old
configuration running on untouched; past it, the adopted objects are switched to their
new classes, which cannot fail. Declared variables follow the plan (kept, converted,
initialised); internal state that no declaration names (edge memories, action control
blocks, the start time of a step) follows the object it belongs to when that object is
carried over.
"""

from __future__ import annotations

import copy
import functools
import sys
import time
from collections.abc import Callable, Iterator, Mapping, Set
from dataclasses import dataclass, field
from operator import attrgetter
from typing import Any

from runtime.adoption import Adoption, Graft, plan_adoption, rebind, resolve
from runtime.code.code_image import Accessor, slot_names
from runtime.code.instances import BoundVariable, Instances
from runtime.code.user_program import UserProgram, share_globals
from runtime.contract.artifact import Artifact
from runtime.contract.values import array_shape
from runtime.reload_plan import (
    CONVERTED,
    KEPT,
    SWITCH_NS_PER_VALUE,
    LiveState,
    ReloadPlan,
    chart_instances,
    convert,
    rename_source,
)

_SCALARS = (bool, int, float, str, type(None))
CHECK_EVERY = 256  # values between two looks at the clock
# the rest of the switch-over's cost (measured by tests/bench/bench_reload.py, rounded up;
# SWITCH_NS_PER_VALUE is a copied value): the fixed part, per object whose class changes,
# per adopted object put in place
SWITCH_BASE_NS = 100_000
SWITCH_NS_PER_OBJECT = 100
SWITCH_NS_PER_GRAFT = 2_000


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
# (old accessor, new accessor, conversion, whether the value is an array: copied)
Move = tuple[Accessor, Accessor, Converter, bool]


@dataclass
class Moves:
    """The values copied from one old object into one new object."""

    old_root: Any
    # looked up at switch time: a struct may have been replaced by an assignment since
    old_attrs: tuple[Accessor, ...]
    new_parent: Any
    plain: tuple[str, ...]  # attributes of the same name, values as they are
    get_plain: Callable[[Any], tuple[Any, ...]] | None  # all `plain` values at once
    others: list[Move] = field(default_factory=list)


@dataclass
class SwitchOver:
    """Everything the switch-over will do, worked out beforehand (outside the cycle), so
    that between the two cycles only values and objects move."""

    adoption: Adoption
    moves: list[Moves]
    # (old object, new object, internal slots): FB and program instances and steps are
    # never replaced, so these pairs hold
    internal: list[tuple[Any, Any, tuple[str, ...]]]
    programs: list[tuple[UserProgram, UserProgram]]
    carried: int  # values the plan keeps or converts (adopted or copied)

    @property
    def copied(self) -> int:
        return sum(len(m.plain) + len(m.others) for m in self.moves)

    @property
    def estimate_ns(self) -> int:
        """What the switch-over will take between two cycles (the budget check's figure)."""
        return (
            SWITCH_BASE_NS
            + self.copied * SWITCH_NS_PER_VALUE
            + self.adoption.objects * SWITCH_NS_PER_OBJECT
            + len(self.adoption.grafts) * SWITCH_NS_PER_GRAFT
        )


def prepare_switch_over(
    old: Instances, new: Instances, plan: ReloadPlan, renames: Mapping[str, str]
) -> SwitchOver:
    adoption, adopted = plan_adoption(old, new, plan)
    groups: dict[tuple[int, tuple[Accessor, ...], int], tuple[Moves, list[str]]] = {}
    carried = 0
    for change in plan.changes:
        if change.action not in (KEPT, CONVERTED) or change.source is None:
            continue
        carried += 1
        if change.path.upper() in adopted.paths:
            continue
        source, target = old.by_name[change.source.upper()], new.by_name[change.path.upper()]
        converter: Converter = None
        if change.action == CONVERTED:
            old_type, new_type = change.old_type or "", change.new_type or ""
            converter = functools.partial(convert, old_type=old_type, new_type=new_type)
        attrs, new_attrs = source.path.attrs, target.path.attrs
        root, new_parent = _owner(old, source), resolve(_owner(new, target), new_attrs[:-1])
        key = (id(root), attrs[:-1], id(new_parent))
        if key not in groups:
            groups[key] = (Moves(root, attrs[:-1], new_parent, (), None), [])
        moves, plain = groups[key]
        last, new_last = attrs[-1], new_attrs[-1]
        is_array = array_shape(target.path.type) is not None
        if converter is None and not is_array and last == new_last and isinstance(last, str):
            plain.append(sys.intern(last))  # the class's own slot name: found at once
        else:
            moves.others.append((last, new_last, converter, is_array))
    for moves, plain in groups.values():
        if len(plain) > 1:  # attrgetter gives a tuple only for two names or more
            moves.plain, moves.get_plain = tuple(plain), attrgetter(*plain)
        else:
            moves.others.extend((name, name, None, False) for name in plain)
    old_declared, new_declared = old.image.declared_attrs(), new.image.declared_attrs()
    old_objects = dict(_objects(old))
    internal = []
    # not what is adopted anyway (but what is new below an object adopted on its own)
    for path, target in _objects(new, adopted.replaced, adopted.shallow):
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
    # what the adopted objects replace is garbage: freed here, on the worker thread, rather
    # than by the cycle thread after the switch-over
    for graft in adoption.grafts:
        if not graft.patches:
            _empty(graft.fresh)
    return SwitchOver(adoption, [m for m, _ in groups.values()], internal, programs, carried)


def _empty(target: Any) -> None:
    """Drop what a fresh object holds (it is replaced, and only its identity matters)."""
    if isinstance(target, list):
        target.clear()
        return
    for slot in slot_names(target):
        if not isinstance(getattr(target, slot, None), _SCALARS):
            setattr(target, slot, None)


def switch_over(prepared: SwitchOver, new: Instances, deadline_ns: int | None) -> int:
    """Fill the new instances from the old ones; returns the number of values carried.
    Raises SwitchOverTooLong past `deadline_ns` (perf_counter time), before the point of
    no return: until then nothing of the old configuration changed."""
    adopted = [_graft(graft, new) for graft in prepared.adoption.grafts]
    since_check = 0
    for moves in prepared.moves:
        parent = resolve(moves.old_root, moves.old_attrs)
        new_parent = moves.new_parent
        if moves.get_plain is not None:
            for name, value in zip(moves.plain, moves.get_plain(parent), strict=True):
                setattr(new_parent, name, value)
        for last, new_last, converter, is_array in moves.others:
            value = parent[last] if isinstance(last, int) else getattr(parent, last)
            if is_array:
                value = _copied(value)  # the new list must not be the old one
            if converter is not None:
                value = converter(value)
            if isinstance(new_last, int):
                new_parent[new_last] = value
            else:
                setattr(new_parent, new_last, value)
        since_check += len(moves.plain) + len(moves.others)
        if since_check >= CHECK_EVERY:
            since_check = 0
            if deadline_ns is not None and time.perf_counter_ns() > deadline_ns:
                raise SwitchOverTooLong()
    for source, target, slots in prepared.internal:
        for slot in slots:
            value = getattr(source, slot)
            setattr(target, slot, value if isinstance(value, _SCALARS) else copy.deepcopy(value))
    for previous, program in prepared.programs:
        program.state, program.error = previous.state, previous.error
        program.time_ns, program.last_start_ns = previous.time_ns, previous.last_start_ns
        program.stats = copy.copy(previous.stats)
    share_globals(new.globals, new.programs)
    if deadline_ns is not None and time.perf_counter_ns() > deadline_ns:
        raise SwitchOverTooLong()
    # the point of no return: the adopted objects take their new children and run the
    # new code from now on
    for graft, target in zip(prepared.adoption.grafts, adopted, strict=True):
        for slot, child in graft.patches:
            setattr(target, slot, child)
    rebind(adopted, prepared.adoption.classes, prepared.adoption.children)
    return prepared.carried + sum(len(slots) for _, _, slots in prepared.internal)


def _graft(graft: Graft, new: Instances) -> Any:
    """Put an adopted object in its place in the new instances (which alone change)."""
    adopted = resolve(graft.old_root, graft.old_attrs)
    if graft.new_parent is not None:
        if isinstance(graft.last, int):
            graft.new_parent[graft.last] = adopted
        else:
            setattr(graft.new_parent, str(graft.last), adopted)
    elif graft.new_owner is not None:
        graft.new_owner.instance = adopted
        new.image.adopt_program(graft.fresh, adopted)
    else:
        new.globals = adopted
        new.image.adopt_globals(adopted)
        for program in new.programs:
            if program.view is graft.fresh:
                program.view = adopted
    return adopted


def _copied(value: Any) -> Any:
    """A copy of an array: of its elements too, unless they are elementary values."""
    if value and not isinstance(value[0], _SCALARS):
        return copy.deepcopy(value)
    return value[:]


def _owner(instances: Instances, bound: BoundVariable) -> Any:
    return bound.program.instance if bound.program is not None else instances.globals


def _objects(
    instances: Instances, skip: Set[int] = frozenset(), hide: Set[int] = frozenset()
) -> Iterator[tuple[str, Any]]:
    """Every generated object below the program and global instances, by a path of
    attribute names (`Main.fb`, `Main.arr#2` for the third object of a list); not the
    objects whose id is in `skip` and what is below them, nor those in `hide`."""
    roots: list[tuple[str, Any]] = [(p.name, p.instance) for p in instances.programs]
    if instances.globals is not None:
        roots.append(("", instances.globals))
    stack = list(reversed(roots))
    while stack:
        path, target = stack.pop()
        if id(target) in skip:
            continue
        if id(target) not in hide:
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
