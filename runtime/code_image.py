"""Executable form of an artifact: its generated source run into one namespace per resource,
plus the flat variable paths used for OLT values."""

from __future__ import annotations

from collections.abc import Callable
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

    def __init__(
        self, artifact: Artifact, system: SystemView, printf: Callable[..., int] | None = None
    ) -> None:
        self.artifact = artifact
        self.system = system
        self._namespace = namespace(system) if printf is None else namespace(system, printf)
        self._pous = {pou.name.upper(): pou for pou in (*artifact.types, *artifact.pous)}
        # Functions come last: their default arguments may read globals, which need the
        # classes of structs and function blocks first.
        classes = [*artifact.types, *(p for p in artifact.pous if p.kind != "FUNCTION")]
        for unit in classes:
            self._run(unit)
        self.globals: Any = None
        if artifact.globals is not None:
            self._run(artifact.globals)
            self.globals = self._namespace[artifact.globals.class_name]()
            self._namespace["_G"] = self.globals
        for unit in artifact.pous:
            if unit.kind == "FUNCTION":
                self._run(unit)

    def _run(self, unit: PouCode) -> None:
        code = compile(unit.source, f"<{unit.kind} {unit.name}>", "exec")
        exec(code, self._namespace)

    def register_program(self, pou_name: str, instance: Any) -> None:
        """Make a program instance callable from ST by its POU name (`prog();`)."""
        class_name = self._pous[pou_name.upper()].class_name
        programs = self._namespace["_P"]
        if not hasattr(programs, class_name):
            setattr(programs, class_name, instance)

    def program_instance(self, pou_name: str) -> Any:
        class_name = self._pous[pou_name.upper()].class_name
        return getattr(self._namespace["_P"], class_name)

    def function(self, pou_name: str) -> Callable[..., Any]:
        pou = self._pous[pou_name.upper()]
        function: Callable[..., Any] = self._namespace[pou.class_name]
        return function

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
