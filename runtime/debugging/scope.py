"""What a name means at a stopped (or traced) line: a frame's locals, the variables of the
instance whose code runs, the globals; members of structures and instances and elements of
arrays below them. ST names are case-insensitive; the artifact's variable tables say which
slot holds which variable and its type."""

from __future__ import annotations

import re
from dataclasses import dataclass
from types import FrameType
from typing import Any, Protocol

from runtime.contract.artifact import VarInfo
from runtime.contract.refusal import Refusal

_ARRAY = re.compile(r"ARRAY\s*\[\s*(-?\d+)\s*\.\.\s*(-?\d+)\s*(,[^\]]*)?\]\s*OF\s+(.+)", re.I)
_SCALARS = (bool, int, float, str)


@dataclass(frozen=True)
class Typed:
    value: Any
    type: str  # "" where the artifact does not say (a FUNCTION's locals)
    path: str | None  # the variable's path on the resource (None: a local)


class VariableTable:
    """The declared variables of each generated class."""

    def __init__(self, by_class: dict[type, tuple[VarInfo, ...]]) -> None:
        self._names = {
            kind: {info.name.upper(): info for info in infos} for kind, infos in by_class.items()
        }
        self._ordered = by_class

    def declared(self, obj: Any) -> tuple[VarInfo, ...] | None:
        """The variables of a generated object in declaration order; None: not one."""
        return self._ordered.get(type(obj))

    def member(self, owner: Typed, name: str) -> Typed:
        infos = self._names.get(type(owner.value))
        info = infos.get(name.upper()) if infos is not None else None
        if info is None:
            raise Refusal("unknown_variable", f"'{name}' is not a member of {owner.type or 'it'}")
        return Typed(getattr(owner.value, info.attr), info.type, _below(owner.path, info.name))


def element(owner: Typed, index: int) -> Typed:
    """An element of an array by its ST index (the array's own bounds)."""
    found = _ARRAY.fullmatch(owner.type.strip())
    if not isinstance(owner.value, list) or found is None:
        raise Refusal("bad_value", f"{owner.path or 'it'} is not an array")
    low, high = int(found.group(1)), int(found.group(2))
    if not low <= index <= high:
        raise Refusal("bad_value", f"index {index} is outside {low}..{high}")
    rest = found.group(3)
    inner = f"ARRAY[{rest[1:].strip()}] OF {found.group(4)}" if rest else found.group(4)
    path = f"{owner.path}[{index}]" if owner.path else None
    return Typed(owner.value[index - low], inner.strip(), path)


def elements(owner: Typed) -> list[tuple[int, Typed]]:
    found = _ARRAY.fullmatch(owner.type.strip())
    if found is None:
        return []
    low = int(found.group(1))
    return [(low + n, element(owner, low + n)) for n in range(len(owner.value))]


class Names(Protocol):
    """Where names are looked up: a frame, or the resource's roots (programs, globals)."""

    @property
    def table(self) -> VariableTable: ...

    def lookup(self, name: str) -> Typed: ...


def local_name(python_name: str) -> str | None:
    """The ST name of a local of generated code (a method's parameters and result carry a
    `__` suffix); None for the code's own temporaries and the instance."""
    if python_name == "s" or python_name.startswith("_"):
        return None
    return python_name[:-2] if python_name.endswith("__") else python_name


@dataclass(frozen=True)
class FrameScope:
    """The names visible in one frame of generated code."""

    frame: FrameType
    table: VariableTable
    instance_path: str | None  # of `s`, the instance whose code runs
    globals_view: Any

    def locals(self) -> list[tuple[str, Typed]]:
        found = []
        for python_name, value in self.frame.f_locals.items():
            name = local_name(python_name)
            if name is not None:
                found.append((name, Typed(value, _scalar_type(value), None)))
        return found

    def instance(self) -> Typed | None:
        obj = self.frame.f_locals.get("s")
        if obj is None or self.table.declared(obj) is None:
            return None
        return Typed(obj, type(obj).__name__, self.instance_path)

    def lookup(self, name: str) -> Typed:
        wanted = name.upper()
        for local, typed in self.locals():
            if local.upper() == wanted:
                return typed
        owner = self.instance()
        if owner is not None:
            try:
                return self.table.member(owner, name)
            except Refusal:
                pass
        if self.globals_view is not None:
            try:
                return self.table.member(Typed(self.globals_view, "", ""), name)
            except Refusal:
                pass
        raise Refusal("unknown_variable", f"no variable '{name}' here")


def _below(path: str | None, name: str) -> str | None:
    """The path of a member: None below a local, a global's own name below the globals
    (path "")."""
    if path is None:
        return None
    return f"{path}.{name}" if path else name


def _scalar_type(value: Any) -> str:
    if isinstance(value, bool):
        return "BOOL"
    if isinstance(value, int):
        return "DINT"
    if isinstance(value, float):
        return "LREAL"
    if isinstance(value, str):
        return "STRING"
    return ""


def plain(value: Any) -> Any:
    """The value as a reply carries it: scalars as they are, anything else null."""
    return value if isinstance(value, _SCALARS) else None
