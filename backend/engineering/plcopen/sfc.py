"""An SFC network of a PLCopen body (elements joined by `connection refLocalId`) into the
textual SFC of IEC 61131-3: INITIAL_STEP/STEP with their action associations, TRANSITION
FROM .. TO .. := condition, and an ACTION for each inline action of an action block.

Connections point backwards (an element names its predecessors), so a transition's source
steps are found walking back through selection divergences and simultaneous convergences,
its target steps walking forward through simultaneous divergences, selection convergences
and jumps.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass, field

from backend.engineering.plcopen.xml_tree import Element, st_source

IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")
DURATION = re.compile(r"(T|TIME|LT|LTIME)#[0-9a-zA-Z_.]+\Z|[A-Za-z_][A-Za-z0-9_]*\Z", re.IGNORECASE)
QUALIFIERS = {"N", "R", "S", "P", "P0", "P1", "L", "D", "SD", "DS", "SL"}
TIMED = {"L", "D", "SD", "DS", "SL"}
PASS_BACK = {"selectionDivergence", "simultaneousConvergence"}  # to the steps before
PASS_ON = {"simultaneousDivergence", "selectionConvergence"}  # to the steps after
NOT_PARTS = {"comment", "documentation", "addData"}


class SfcProblem(Exception):
    """The network has no textual form padt compiles; the message says where."""


@dataclass
class Chart:
    text: str
    inline_actions: list[tuple[str, str]] = field(default_factory=list)  # (name, ST)


@dataclass
class _Network:
    by_id: dict[str, Element]
    before: dict[str, list[str]]  # localId -> the localIds it is connected from
    after: dict[str, list[str]]
    connectors: dict[str, str]  # connector name -> its localId

    def previous(self, element: Element) -> list[str]:
        if element.tag == "continuation":  # a connector's continuation: where it comes from
            connector = self.connectors.get(element.attrs.get("name", "").upper())
            return self.before.get(connector, []) if connector else []
        return self.before.get(element.attrs["localId"], [])

    def following(self, element: Element) -> list[str]:
        found = list(self.after.get(element.attrs["localId"], []))
        if element.tag == "connector":
            name = element.attrs.get("name", "").upper()
            found += [
                local
                for local, e in self.by_id.items()
                if e.tag == "continuation" and e.attrs.get("name", "").upper() == name
            ]
        return found


def _network(sfc: Element) -> _Network:
    by_id: dict[str, Element] = {}
    before: dict[str, list[str]] = {}
    after: dict[str, list[str]] = {}
    connectors: dict[str, str] = {}
    for element in sfc.children:
        if element.tag in NOT_PARTS:
            continue
        local = element.attrs.get("localId")
        if local is None:
            raise SfcProblem(f"<{element.tag}> at line {element.where.line} has no localId")
        if local in by_id:
            raise SfcProblem(f"localId {local} used twice (line {element.where.line})")
        by_id[local] = element
        if element.tag == "step" and not IDENTIFIER.match(element.attrs.get("name", "")):
            raise SfcProblem(f"the step at line {element.where.line} has no valid name")
        if element.tag == "connector":
            connectors[element.attrs.get("name", "").upper()] = local
        sources = [
            connection.attrs.get("refLocalId", "")
            for point in element.all("connectionPointIn")
            for connection in point.all("connection")
        ]
        before[local] = sources
        for source in sources:
            after.setdefault(source, []).append(local)
    return _Network(by_id, before, after, connectors)


def _sources(network: _Network, transition: Element) -> list[str]:
    def back(element: Element) -> list[str]:
        if element.tag == "step":
            return [element.attrs["name"]]
        if element.tag in PASS_BACK or element.tag in ("connector", "continuation"):
            todo.extend(network.previous(element))
            return []
        raise SfcProblem(
            f"the transition at line {transition.where.line} follows a <{element.tag}>"
        )

    todo = list(network.previous(transition))
    return _walk(network, todo, back)


def _targets(network: _Network, transition: Element) -> list[str]:
    def forward(element: Element) -> list[str]:
        if element.tag == "step":
            return [element.attrs["name"]]
        if element.tag == "jumpStep":
            target = element.attrs.get("targetName", "")
            if not IDENTIFIER.match(target):
                raise SfcProblem(f"the jump at line {element.where.line} has no target step")
            return [target]
        if element.tag in PASS_ON or element.tag in ("connector", "continuation"):
            todo.extend(network.following(element))
            return []
        raise SfcProblem(f"the transition at line {transition.where.line} leads to <{element.tag}>")

    todo = network.following(transition)
    return _walk(network, todo, forward)


def _walk(network: _Network, todo: list[str], step: Callable[[Element], list[str]]) -> list[str]:
    """The step names reached from the elements in `todo`: `step` gives an element's names,
    or adds the elements to walk on to `todo`."""
    names: list[str] = []
    seen: set[str] = set()
    while todo:
        local = todo.pop(0)
        if local in seen:
            continue
        seen.add(local)
        element = network.by_id.get(local)
        if element is None:
            raise SfcProblem(f"a connection to localId {local}, which is no element")
        names += [n for n in step(element) if n not in names]
    return names


def _inline_st(holder: Element, what: str) -> str:
    st = holder.child("ST")
    if st is None:
        languages = [c.tag for c in holder.children if c.tag not in NOT_PARTS]
        raise SfcProblem(f"{what} in {', '.join(languages) or 'no language'}")
    return st_source(st)


def _condition(transition: Element, named: dict[str, str]) -> str:
    where = f"the transition at line {transition.where.line}"
    condition = transition.child("condition")
    if condition is None:
        raise SfcProblem(f"{where} has no condition")
    inline = condition.child("inline")
    if inline is not None:
        text = _inline_st(inline, f"the condition of {where}").strip().removesuffix(";")
        return " ".join(text.split()) if "(*" not in text and "//" not in text else text
    reference = condition.child("reference")
    if reference is not None:
        name = reference.attrs.get("name", "")
        if name.upper() not in named:
            raise SfcProblem(f"{where} names transition {name!r}, which the POU does not have")
        return named[name.upper()]
    raise SfcProblem(f"{where} has its condition in FBD or LD")


def sfc_text(sfc: Element, named: dict[str, str], actions: set[str]) -> Chart:
    """`named`: the POU's named transitions (upper-case name -> condition); `actions`: the
    upper-case names of its actions (an inline action gets a name none of them has)."""
    network = _network(sfc)
    chart = Chart("")
    taken = set(actions)
    steps, transitions = [], []
    for local, element in network.by_id.items():
        if element.tag == "step":
            name = element.attrs["name"]  # checked by _network
            taken.add(name.upper())
            associations = []
            for block_id in network.after.get(local, []):
                block = network.by_id[block_id]
                if block.tag == "actionBlock":
                    associations += [
                        _association(action, name, taken, chart) for action in block.all("action")
                    ]
            keyword = "INITIAL_STEP" if _flag(element, "initialStep") else "STEP"
            body = "".join(f"    {a}\n" for a in associations)
            steps.append(f"{keyword} {name}:\n{body}END_STEP\n")
        elif element.tag == "transition":
            sources, targets = _sources(network, element), _targets(network, element)
            if not sources or not targets:
                raise SfcProblem(
                    f"the transition at line {element.where.line} joins no step to a step"
                )
            priority = element.attrs.get("priority", "").strip()
            prioritised = f" (PRIORITY := {priority})" if priority.isdigit() else ""
            condition = _condition(element, named)
            transitions.append(
                f"TRANSITION{prioritised} FROM {_names(sources)} TO {_names(targets)} := "
                f"{condition};\nEND_TRANSITION\n"
            )
        elif element.tag == "macroStep":
            raise SfcProblem(f"a macro step at line {element.where.line}")
    if not any(e.tag == "step" for e in network.by_id.values()):
        raise SfcProblem("a chart without a step")
    chart.text = "\n".join([*steps, *transitions]).rstrip("\n")
    return chart


def _flag(element: Element, attribute: str) -> bool:
    return element.attrs.get(attribute, "false").strip().lower() in ("true", "1")


def _names(names: list[str]) -> str:
    return names[0] if len(names) == 1 else f"({', '.join(names)})"


def _association(action: Element, step: str, taken: set[str], chart: Chart) -> str:
    """`Name(Q);` or `Name(Q, T#5s);`; an inline action gets a name after its step."""
    qualifier = action.attrs.get("qualifier", "N").strip().upper() or "N"
    if qualifier not in QUALIFIERS:
        raise SfcProblem(f"action qualifier {qualifier!r} at line {action.where.line}")
    reference = action.child("reference")
    if reference is not None:
        name = reference.attrs.get("name", "")
        if not IDENTIFIER.match(name):
            raise SfcProblem(f"the action at line {action.where.line} names no action")
    else:
        inline = action.child("inline")
        if inline is None:
            raise SfcProblem(f"the action at line {action.where.line} has no body")
        body = _inline_st(inline, f"the action at line {action.where.line}")
        number = 1
        while f"{step}_INLINE{number}".upper() in taken:
            number += 1
        name = f"{step}_INLINE{number}"
        taken.add(name.upper())
        chart.inline_actions.append((name, body))
    parts = [qualifier]
    duration = action.attrs.get("duration", "").strip()
    if qualifier in TIMED:
        if not DURATION.match(duration):
            raise SfcProblem(f"the {qualifier} action at line {action.where.line} needs a time")
        parts.append(duration)
    if action.attrs.get("indicator", "").strip():
        raise SfcProblem(f"an indicator variable at line {action.where.line}")
    return f"{name}({', '.join(parts)});"
