"""The call stack of a program stopped in BKPT and the variables of its frames, named as
ST names them: the generated frames of its greenlet, innermost first."""

from __future__ import annotations

from dataclasses import dataclass
from types import FrameType
from typing import Any

from runtime.contract.artifact import PouCode
from runtime.contract.protocol import DebugFrame, DebugVariable
from runtime.debugging.condition import locate
from runtime.debugging.scope import FrameScope, Typed, VariableTable, elements, plain
from runtime.debugging.statements import StatementMap


@dataclass(frozen=True)
class CodeFrame:
    frame: FrameType
    unit: PouCode
    filename: str


def code_frames(frame: FrameType | None, statements: StatementMap) -> list[CodeFrame]:
    """The frames of generated code from `frame` outwards."""
    found: list[CodeFrame] = []
    while frame is not None:
        filename = frame.f_code.co_filename
        unit = statements.units.get(filename)
        if unit is not None:
            found.append(CodeFrame(frame, unit, filename))
        frame = frame.f_back
    return found


def instance_paths(roots: list[tuple[str, Any]], table: VariableTable) -> dict[int, str]:
    """The path of every generated object below `roots` (a program instance by its
    program's name, the globals by ""), by id: how a frame's instance is named."""
    paths: dict[int, str] = {}
    todo = [Typed(obj, "", path) for path, obj in roots]
    while todo:
        owner = todo.pop()
        declared = table.declared(owner.value)
        if declared is None:
            continue
        for info in declared:
            member = table.member(owner, info.name)
            for typed in [member, *(t for _, t in elements(member))]:
                if table.declared(typed.value) is not None and id(typed.value) not in paths:
                    paths[id(typed.value)] = typed.path or ""
                    todo.append(typed)
    return paths


def describe(
    frames: list[CodeFrame], statements: StatementMap, paths: dict[int, str]
) -> list[DebugFrame]:
    described = []
    for index, code in enumerate(frames):
        unit, name = code.unit, code.frame.f_code.co_name
        instance = code.frame.f_locals.get("s")
        where = paths.get(id(instance)) if instance is not None else None
        if unit.kind == "FUNCTION":
            kind, shown = "function", unit.name
        elif name.startswith("M__"):
            kind, shown = "method", f"{unit.name}.{name[3:]}"
        elif name.startswith(("GET__", "SET__")):
            kind, shown = "property", f"{unit.name}.{name.split('__', 1)[1]}"
        elif name == "__call__":
            kind = "program" if unit.kind == "PROGRAM" else "function block"
            shown = unit.name
        else:
            kind, shown = "action", f"{unit.name}.{name}"
        line = statements.st_line(code.filename, code.frame.f_lineno)
        described.append(DebugFrame(index, shown, kind, where, unit.name, unit.file, line))
    return described


def variables(scope: FrameScope, path: str) -> list[DebugVariable]:
    """The variables of a frame (`path` ""), or the members or elements of one of them."""
    if path:
        return variables_below(locate(path, scope), scope.table)
    found = [_variable(name, typed, scope.table) for name, typed in scope.locals()]
    instance = scope.instance()
    if instance is not None:
        found += variables_below(instance, scope.table)
    return found


def variables_below(owner: Typed, table: VariableTable) -> list[DebugVariable]:
    declared = table.declared(owner.value)
    if declared is not None:
        return [_variable(i.name, table.member(owner, i.name), table) for i in declared]
    return [_variable(f"[{index}]", typed, table) for index, typed in elements(owner)]


def _variable(name: str, typed: Typed, table: VariableTable) -> DebugVariable:
    nested = table.declared(typed.value) is not None or isinstance(typed.value, list)
    return DebugVariable(name, typed.type, plain(typed.value), typed.path, nested)
