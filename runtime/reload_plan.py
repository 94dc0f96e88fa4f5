"""What a reload would do, worked out from the old and the new artifact (spec section 9):
for every variable whether its value is kept, converted, initialised, new or deleted; the
known traps of step chains and actions; and whether a reload is possible at all.

Values carry over BY NAME: globals by their name, locals by their full instance path
(`Program.fbInstance.var`). A renamed variable, FB instance or program starts from its
initial values unless the user maps the old name to the new one. The PADT shows this plan
as the reload preview; the runtime computes it again, with its live state, before it
switches. Both use this module, so the preview is what happens.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass
from typing import Any

from runtime.code.code_image import CodeImage, VariablePath
from runtime.code.intrinsics import SystemView
from runtime.contract.artifact import Artifact, ChartInfo, PouCode, ResourceConfig
from runtime.contract.exchange import ExchangeConfig
from runtime.contract.parameters import RESOURCE_BY_NAME
from runtime.contract.protocol import Hazard, ProgramChanges, ReloadPlanInfo, VariableChange
from runtime.contract.values import array_shape, base_type, is_reference_type

KEPT, CONVERTED, INITIALISED, NEW, DELETED = "kept", "converted", "initialised", "new", "deleted"
TIMED_QUALIFIERS = ("L", "D", "SD", "DS", "SL")
# per value copied, what the switch-over between two cycles costs (measured by
# tests/bench/bench_reload.py on the reference machine, rounded up); a plan made without
# the running instances assumes every transferred value is copied, the runtime's own plan
# knows which objects it adopts instead (runtime/reload.py)
SWITCH_NS_PER_VALUE = 250


@dataclass(frozen=True)
class ReloadPlan:
    old_crc: str
    new_crc: str
    changes: tuple[VariableChange, ...]
    hazards: tuple[Hazard, ...]
    refusals: tuple[str, ...]  # why this change needs STOP and a download
    programs_added: tuple[str, ...]
    programs_removed: tuple[str, ...]
    programs_changed: tuple[str, ...]
    estimate_ns: int  # extra time of the switch-over between two cycles

    @property
    def possible(self) -> bool:
        return not self.refusals

    def count(self, action: str) -> int:
        return sum(1 for change in self.changes if change.action == action)

    def info(self) -> ReloadPlanInfo:
        """The plan as the protocol sends it (the reload preview)."""
        return ReloadPlanInfo(
            old_crc=self.old_crc,
            new_crc=self.new_crc,
            possible=self.possible,
            refusals=list(self.refusals),
            hazards=list(self.hazards),
            programs=ProgramChanges(
                list(self.programs_added), list(self.programs_removed), list(self.programs_changed)
            ),
            summary={a: self.count(a) for a in (KEPT, CONVERTED, INITIALISED, NEW, DELETED)},
            changes=list(self.changes),
            estimate_us=self.estimate_ns / 1000,
        )


# ---- which values carry over


_INT_BITS = {
    "SINT": (8, True), "INT": (16, True), "DINT": (32, True), "LINT": (64, True),
    "USINT": (8, False), "UINT": (16, False), "UDINT": (32, False), "ULINT": (64, False),
}  # fmt: skip
_BIT_STRINGS = {"BYTE": 8, "WORD": 16, "DWORD": 32, "LWORD": 64}
_MANTISSA = {"REAL": 24, "LREAL": 53}


def conversion(old_type: str, new_type: str) -> str | None:
    """How a value of `old_type` becomes one of `new_type`: KEPT (same type), CONVERTED
    (every value converts exactly), or None (it cannot: the variable is initialised)."""
    if old_type.upper() == new_type.upper():
        return KEPT
    old, old_length = base_type(old_type)
    new, new_length = base_type(new_type)
    if old in _INT_BITS and new in _INT_BITS:
        (old_bits, old_signed), (new_bits, new_signed) = _INT_BITS[old], _INT_BITS[new]
        if old_signed == new_signed and new_bits >= old_bits:
            return CONVERTED
        if not old_signed and new_signed and new_bits > old_bits:
            return CONVERTED
        return None
    if old in _BIT_STRINGS and new in _BIT_STRINGS:
        return CONVERTED if _BIT_STRINGS[new] >= _BIT_STRINGS[old] else None
    if old in _INT_BITS and new in _MANTISSA:
        bits, signed = _INT_BITS[old]
        return CONVERTED if bits - (1 if signed else 0) <= _MANTISSA[new] else None
    if (old, new) == ("REAL", "LREAL") or {old, new} == {"TIME", "LTIME"}:
        return CONVERTED
    if old == new and old in ("STRING", "WSTRING") and new_length >= old_length:
        return CONVERTED
    old_shape, new_shape = array_shape(old_type), array_shape(new_type)
    if old_shape is not None and new_shape is not None and old_shape.dims == new_shape.dims:
        return CONVERTED if conversion(old_shape.element, new_shape.element) else None
    return None


def convert(value: Any, old_type: str, new_type: str) -> Any:
    """A value converted exactly (only where `conversion` says it can be)."""
    shape = array_shape(new_type)
    old_shape = array_shape(old_type)
    if isinstance(value, list) and shape is not None and old_shape is not None:
        return [convert(item, old_shape.element, shape.element) for item in value]
    new, _ = base_type(new_type)
    if new in _MANTISSA:
        return float(value)
    return value


def rename_source(path: str, renames: Mapping[str, str]) -> str:
    """The old path a new path's value comes from, after the user's rename map (NEW name
    -> OLD name, for a variable, an FB instance or a program: everything below follows)."""
    upper = path.upper()
    for new, old in sorted(renames.items(), key=lambda item: -len(item[0])):
        prefix = new.upper()
        if upper == prefix or upper.startswith((prefix + ".", prefix + "[")):
            return old + path[len(new) :]
    return path


def variable_paths(artifact: Artifact) -> list[VariablePath]:
    """Every elementary variable of a configuration: program locals, then globals."""
    image = CodeImage(artifact, SystemView())
    paths = [
        p for program in artifact.programs for p in image.variable_paths(program.name, program.pou)
    ]
    return paths + image.global_paths()


def _holds_references(type_name: str) -> bool:
    """A reference (REF_TO, an interface variable), or an array of them (one value)."""
    shape = array_shape(type_name)
    return is_reference_type(shape.element if shape is not None else type_name)


def _changes(
    old: list[VariablePath], new: list[VariablePath], renames: Mapping[str, str]
) -> list[VariableChange]:
    by_path = {p.path.upper(): p for p in old}
    used: set[str] = set()
    changes = []
    for path in new:
        source_name = rename_source(path.path, renames)
        source = by_path.get(source_name.upper())
        if source is None:
            changes.append(VariableChange(path.path, NEW, None, path.type))
            continue
        used.add(source.path.upper())
        renamed = source.path if source.path.upper() != path.path.upper() else None
        how = conversion(source.type, path.type)
        if _holds_references(path.type):
            # what it refers to is an object of the configuration being replaced
            reason = (
                "a reference does not carry over a reload: it starts again at its initial "
                "value (NULL unless declared := REF(x))"
            )
            changes.append(
                VariableChange(path.path, INITIALISED, source.type, path.type, renamed, reason)
            )
        elif how is None:
            reason = f"type {source.type} does not convert exactly to {path.type}"
            changes.append(
                VariableChange(path.path, INITIALISED, source.type, path.type, renamed, reason)
            )
        else:
            reason = f"renamed from {renamed}" if renamed else ""
            if how == CONVERTED:
                reason = f"{source.type} -> {path.type}" + (f", {reason}" if reason else "")
            changes.append(
                VariableChange(path.path, how, source.type, path.type, source.path, reason)
            )
    listed = {c.path.upper() for c in changes}
    changes.extend(
        VariableChange(p.path, DELETED, p.type, None)
        for p in old
        if p.path.upper() not in used and p.path.upper() not in listed
    )
    return changes


# ---- the traps of step chains and actions


@dataclass(frozen=True)
class ChartInstance:
    path: str  # `Program` or `Program.fb`
    attrs: tuple[str, ...]  # below the program instance
    program: str
    chart: ChartInfo
    pou: str


def chart_instances(artifact: Artifact) -> Iterator[ChartInstance]:
    """Every program and FB instance (not inside arrays) that runs a chart."""
    pous = {p.name.upper(): p for p in artifact.pous}

    def walk(
        pou: PouCode, path: str, attrs: tuple[str, ...], program: str
    ) -> Iterator[ChartInstance]:
        if pou.chart is not None:
            yield ChartInstance(path, attrs, program, pou.chart, pou.name)
        for var in pou.variables:
            inner = pous.get(var.type.upper())
            if inner is not None and inner.kind == "FUNCTION_BLOCK":
                yield from walk(inner, f"{path}.{var.name}", (*attrs, var.attr), program)

    for program in artifact.programs:
        pou = pous.get(program.pou.upper())
        if pou is not None:
            yield from walk(pou, program.name, (), program.name)


# live state: (instance path, name) -> value, for step flags ("S1.X") and action-control
# flags ("A.stored", "A.p0_prev"); None when a plan is made without a running resource
LiveState = Callable[[str, str], Any]


def _hazards(
    old: Artifact, new: Artifact, renames: Mapping[str, str], live: LiveState | None
) -> list[Hazard]:
    old_charts = {i.path.upper(): i for i in chart_instances(old)}
    hazards = []
    for target in chart_instances(new):
        instance = old_charts.get(rename_source(target.path, renames).upper())
        if instance is not None:  # a new or renamed instance starts afresh: no trap
            hazards.extend(_chart_hazards(instance, target.chart, live))
    return hazards + _exchange_hazards(old.exchange, new.exchange)


def _exchange_hazards(old: ExchangeConfig | None, new: ExchangeConfig | None) -> list[Hazard]:
    """What a changed exchange with other resources does (docs/exchange.md): the driver is
    made anew, so every subscription starts again from its safe values."""
    before, after = old or ExchangeConfig(), new or ExchangeConfig()
    if before == after:
        return []
    hazards = []
    old_subscriptions = {s.name: s for s in before.subscriptions}
    for subscription in after.subscriptions:
        names = ", ".join(p.variable for p in subscription.points)
        kept = subscription.name in old_subscriptions
        hazards.append(
            Hazard(
                "exchange-restarted" if kept else "exchange-subscribed",
                subscription.name,
                f"{names}: safe values until the next message of "
                f"{subscription.name} (within its publisher's period)",
            )
        )
    for name in sorted(old_subscriptions.keys() - {s.name for s in after.subscriptions}):
        names = ", ".join(p.variable for p in old_subscriptions[name].points)
        hazards.append(
            Hazard(
                "exchange-unsubscribed",
                name,
                f"{names}: the last values stay, no longer updated from {name}",
            )
        )
    new_publications = {p.name: p for p in after.publications}
    for publication in before.publications:
        changed = new_publications.get(publication.name)
        if changed is None:
            message = "is no longer published: its subscribers take their safe values"
            hazards.append(Hazard("exchange-unpublished", publication.name, message))
        elif {v.variable for v in publication.variables} - {v.variable for v in changed.variables}:
            message = (
                "loses variables: a subscriber that takes one of them refuses its messages "
                "and takes its safe values"
            )
            hazards.append(Hazard("exchange-publication-changed", publication.name, message))
    return hazards


# qualifiers whose deletion matters only while their action-control flag is TRUE:
# (hazard kind, the flag, how the message says it is TRUE, what happens)
_LATCHED = {
    "S": ("set-qualifier-deleted", "stored", " while the action is set", "the action stays set"),
    "P0": ("p0-deleted", "p0_prev", " while its flag is TRUE", "the trigger fires"),
}


def _active(live: LiveState | None, instance: str, step: str) -> bool | None:
    return None if live is None else bool(live(instance, f"{step}.X"))


def _chart_hazards(instance: ChartInstance, new: ChartInfo, live: LiveState | None) -> list[Hazard]:
    old, where = instance.chart, instance.path
    upper_new_steps = {s.upper() for s in new.steps}
    hazards = []
    for step in old.steps:
        if step.upper() in upper_new_steps:
            continue
        active = _active(live, where, step)
        if active is not False:
            state = "is active" if active else "may be active"
            hazards.append(
                Hazard(
                    "active-step-deleted",
                    where,
                    f"step {step} of {where} {state} and is deleted: the chain is left "
                    "with no active step",
                )
            )
    old_steps = {s.upper() for s in old.steps}
    for step in new.initial:
        if step.upper() in old_steps:
            continue
        others = [s for s in old.steps if s.upper() in upper_new_steps]
        running = [s for s in others if _active(live, where, s) is not False]
        if running:
            hazards.append(
                Hazard(
                    "initial-step-renamed",
                    where,
                    f"the initial step {step} of {where} is new (renamed?) while step "
                    f"{', '.join(running)} may be active: the chain gets two active steps",
                )
            )
    new_associations = {(a.step.upper(), a.action.upper(), a.qualifier) for a in new.associations}
    for a in old.associations:
        if (a.step.upper(), a.action.upper(), a.qualifier) in new_associations:
            continue
        if a.qualifier in TIMED_QUALIFIERS:
            hazards.append(
                Hazard(
                    "timed-qualifier-deleted",
                    where,
                    f"qualifier {a.qualifier} of action {a.action} in step {a.step} of {where} "
                    "is deleted: its timer expires at once, so the action's Q may go TRUE",
                )
            )
        elif a.qualifier in _LATCHED:
            kind, flag, while_set, outcome = _LATCHED[a.qualifier]
            flagged = None if live is None else bool(live(where, f"{a.action}.{flag}"))
            if flagged is not False:
                hazards.append(
                    Hazard(
                        kind,
                        where,
                        f"qualifier {a.qualifier} of action {a.action} in step {a.step} of "
                        f"{where} is deleted{while_set if flagged else ''}: {outcome}",
                    )
                )
    return hazards


# ---- whether reload can do it at all


def _refusals(old: Artifact, new: Artifact) -> list[str]:
    refusals = []
    if old.resource.name != new.resource.name:
        refusals.append(
            f"the resource identity changes ({old.resource.name} -> {new.resource.name})"
        )
    for field in dataclasses.fields(ResourceConfig):
        spec = RESOURCE_BY_NAME.get(field.name)
        if spec is None or spec.online:
            continue
        before, after = getattr(old.resource, field.name), getattr(new.resource, field.name)
        if before != after:
            refusals.append(f"resource parameter {field.name} changes ({before} -> {after})")
    if not new.programs:
        refusals.append("no user program would remain")
    if not old.resource.reload_allowed:
        refusals.append("Reload Allowed of the resource is OFF")
    new_by_name = {p.name: p for p in new.programs}
    for program in old.programs:
        changed = new_by_name.get(program.name)
        if (changed is None or changed.crc != program.crc) and not program.reload_allowed:
            refusals.append(f"Reload Allowed of program {program.name} is OFF")
    return refusals


def plan_reload(
    old: Artifact,
    new: Artifact,
    renames: Mapping[str, str] | None = None,
    live: LiveState | None = None,
    old_paths: list[VariablePath] | None = None,
    new_paths: list[VariablePath] | None = None,
) -> ReloadPlan:
    """The plan for replacing `old` by `new` (renames: NEW path -> OLD path). The
    variable paths of either side, when the caller has them at hand, save compiling it."""
    renames = dict(renames or {})
    old_paths = old_paths if old_paths is not None else variable_paths(old)
    new_paths = new_paths if new_paths is not None else variable_paths(new)
    changes = _changes(old_paths, new_paths, renames)
    old_programs = {p.name: p for p in old.programs}
    new_programs = {p.name: p for p in new.programs}
    transferred = sum(1 for c in changes if c.action in (KEPT, CONVERTED))
    return ReloadPlan(
        old_crc=old.crc,
        new_crc=new.crc,
        changes=tuple(changes),
        hazards=tuple(_hazards(old, new, renames, live)),
        refusals=tuple(_refusals(old, new)),
        programs_added=tuple(sorted(set(new_programs) - set(old_programs))),
        programs_removed=tuple(sorted(set(old_programs) - set(new_programs))),
        programs_changed=tuple(
            sorted(
                n
                for n in new_programs
                if n in old_programs and new_programs[n].crc != old_programs[n].crc
            )
        ),
        estimate_ns=transferred * SWITCH_NS_PER_VALUE,
    )
