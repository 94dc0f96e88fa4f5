"""Executable form of an artifact: its generated source run into one namespace per resource,
plus the flat variable paths used for OLT values."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from runtime.artifact import Artifact, PouCode
from runtime.intrinsics import SystemView, namespace


@dataclass(frozen=True)
class VariablePath:
    path: str  # e.g. "TankControl.refillDelay.ET"
    attrs: tuple[str, ...]  # attribute chain below the program instance
    type: str


class CodeImage:
    """The loaded code of one configuration; instances are created from it."""

    def __init__(self, artifact: Artifact, system: SystemView) -> None:
        self.artifact = artifact
        self.system = system
        self._namespace = namespace(system)
        self._pous = {pou.name.upper(): pou for pou in artifact.pous}
        for pou in artifact.pous:
            code = compile(pou.source, f"<{pou.kind} {pou.name}>", "exec")
            exec(code, self._namespace)

    def new_instance(self, pou_name: str) -> Any:
        pou = self._pous[pou_name.upper()]
        return self._namespace[pou.class_name]()

    def variable_paths(self, program: str, pou_name: str) -> list[VariablePath]:
        """Every elementary variable of a program instance, FB members included."""
        paths: list[VariablePath] = []
        self._collect(self._pous[pou_name.upper()], program, (), paths)
        return paths

    def _collect(
        self, pou: PouCode, prefix: str, attrs: tuple[str, ...], out: list[VariablePath]
    ) -> None:
        for var in pou.variables:
            inner = self._pous.get(var.type.upper())
            if inner is not None:
                self._collect(inner, f"{prefix}.{var.name}", (*attrs, var.attr), out)
            else:
                out.append(VariablePath(f"{prefix}.{var.name}", (*attrs, var.attr), var.type))


def read_path(instance: Any, path: VariablePath) -> Any:
    value = instance
    for attr in path.attrs:
        value = getattr(value, attr)
    return value


def write_path(instance: Any, path: VariablePath, value: Any) -> None:
    target = instance
    for attr in path.attrs[:-1]:
        target = getattr(target, attr)
    setattr(target, path.attrs[-1], value)
