"""The served address space, planned: which of the resource's variables are nodes, and the
objects that hold them, mirroring the configuration.

Below the resource's object (`Tank1`) stand its programs and its globals; a function block
instance or a structure is an object holding its members, an array of them an object
holding one object per element (`[2]`); an elementary variable, or an array of elementary
values, is a variable node. Every node's id is `ns=<ours>;s=<resource>.<path>`, the path as
the runtime names the variable (`Tank1.TankControl.refillDelay.ET`, `Tank1.gPoints[2].x`),
so a client can write the id of what it wants without browsing.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from runtime.code.instances import BoundVariable
from runtime.contract.opcua import OpcuaServer
from runtime.contract.values import array_shape
from runtime.field_io.opcua.types import variant_type

_SEGMENT = re.compile(r"[^.\[\]]+|\[[^\]]*\]")
_ANY_INDEX = re.compile(r"\[[^\]]*\]")


@dataclass(frozen=True)
class PlannedNode:
    """One node below the resource's object."""

    path: str  # the runtime's path of what it shows ("" for the resource's object)
    parent: str  # the path of the object holding it
    name: str  # its browse name: the last segment of the path
    description: str
    variable: BoundVariable | None = None  # None: an object
    writable: bool = False

    @property
    def is_variable(self) -> bool:
        return self.variable is not None


@dataclass(frozen=True)
class Plan:
    objects: tuple[PlannedNode, ...]  # parents before their members
    variables: tuple[PlannedNode, ...]  # in the order of the variables given


def plan(bound: list[BoundVariable], server: OpcuaServer) -> Plan:
    """The nodes of the variables `server` exposes, among `bound` (the configuration's)."""
    exposed = _Prefixes(server.exposed)
    writable = _Prefixes(server.writable)
    descriptions = _Descriptions(server.descriptions)
    objects: dict[str, PlannedNode] = {}
    variables: list[PlannedNode] = []
    for variable in bound:
        path = variable.path.path
        if not exposed.cover(path) or variant_type(variable.path.type) is None:
            continue  # not exposed, or of a type OPC UA is not given (references)
        segments = _SEGMENT.findall(path)
        parent = ""
        for count in range(1, len(segments)):
            prefix = _joined(segments[:count])
            if prefix.upper() not in objects:
                objects[prefix.upper()] = PlannedNode(
                    prefix, parent, segments[count - 1], descriptions.of(prefix)
                )
            parent = objects[prefix.upper()].path
        variables.append(
            PlannedNode(
                path,
                parent,
                segments[-1],
                descriptions.of(path),
                variable,
                # an online write takes elementary values: arrays are served read-only
                writable.cover(path)
                and not variable.path.constant
                and array_shape(variable.path.type) is None,
            )
        )
    return Plan(tuple(objects.values()), tuple(variables))


def _joined(segments: list[str]) -> str:
    text = ""
    for segment in segments:
        text += segment if segment.startswith("[") or not text else f".{segment}"
    return text


class _Descriptions:
    """The declarations' comments by path; what lies inside the elements of an array is
    described once for all of them, with the index written `[*]` (`gPoints[*].x`)."""

    def __init__(self, descriptions: tuple[tuple[str, str], ...]) -> None:
        self._by_path = {path.upper(): text for path, text in descriptions}

    def of(self, path: str) -> str:
        upper = path.upper()
        found = self._by_path.get(upper)
        return found if found is not None else self._by_path.get(_ANY_INDEX.sub("[*]", upper), "")


class _Prefixes:
    """Paths that each cover themselves and everything below them (case-insensitively)."""

    def __init__(self, paths: tuple[str, ...]) -> None:
        self._paths = tuple(path.upper() for path in paths)

    def cover(self, path: str) -> bool:
        upper = path.upper()
        return any(upper == p or upper.startswith((f"{p}.", f"{p}[")) for p in self._paths)
