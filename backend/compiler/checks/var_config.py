"""Partly specified locations (`AT %I*`, `%Q*`, `%M*`), completed per instance by the
CONFIGURATION's VAR_CONFIG (`Resource.Program.inst.var AT %IX1.0 : BOOL;`), and the access
paths of its VAR_ACCESS (`Name : Resource.Program.var : INT READ_ONLY;`). Checked once the
user programs are known, since only their instances have the paths these name."""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field

from backend.compiler import ast
from backend.compiler.ast import key
from backend.compiler.codes import Code
from backend.compiler.diagnostics import Diagnostic
from backend.compiler.resolve import Resolved, Variable
from backend.compiler.source import Pos
from backend.compiler.types import ElementaryType, FbType
from runtime.contract.artifact import AccessPath, ProgramConfig

SIZE_BITS = {"X": 1, "B": 8, "W": 16, "D": 32, "L": 64}


def partly_located(location: str | None) -> bool:
    return location is not None and location.endswith("*")


@dataclass
class Configured:
    """What the configuration adds to the artifact, and what is wrong with it."""

    located: tuple[tuple[str, str], ...] = ()
    access_paths: tuple[AccessPath, ...] = ()
    diagnostics: list[Diagnostic] = field(default_factory=list)

    def report(self, pos: Pos, code: Code, message: str) -> None:
        self.diagnostics.append(Diagnostic.at(pos, code, message))


def instance_variables(
    resolved: Resolved, programs: list[ProgramConfig]
) -> dict[str, tuple[str, Variable]]:
    """Every variable of the resource by upper-case path (`MAIN.D1.OPEN`), with the path as
    the runtime spells it: the globals by name, the programs' variables and, through block
    instances, their members."""
    found = {key(v.name): (v.name, v) for v in resolved.globals}
    for program in programs:
        pou = resolved.pous.get(key(program.pou))
        if pou is not None:
            found.update(_members(resolved, pou.variables, program.name, 0))
    return found


def _members(
    resolved: Resolved, variables: list[Variable], prefix: str, depth: int
) -> Iterator[tuple[str, tuple[str, Variable]]]:
    for variable in variables:
        if variable.kind in ("VAR_GLOBAL", "VAR_EXTERNAL", "VAR_TEMP", "VAR_IN_OUT"):
            continue
        path = f"{prefix}.{variable.name}"
        yield key(path), (path, variable)
        block = (
            resolved.pous.get(key(variable.type.name))
            if isinstance(variable.type, FbType)
            else None
        )
        if block is not None and depth < 64:  # a block holding itself is reported elsewhere
            yield from _members(resolved, block.variables, path, depth + 1)


def check_configuration(
    resolved: Resolved,
    configurations: list[ast.Configuration],
    resource: str,
    programs: list[ProgramConfig],
) -> Configured:
    result = Configured()
    _check_declarations(resolved, result)
    variables = instance_variables(resolved, programs)
    inits = [init for c in configurations for init in c.var_config]
    tried: set[str] = set()
    located = _complete(result, variables, inits, resource, tried)
    for upper, (path, variable) in sorted(variables.items()):
        unnamed = variable.name == variable.location  # reported with its declaration
        if partly_located(variable.location) and upper not in tried and not unnamed:
            result.report(
                variable.pos,
                Code.UNCONFIGURED_LOCATION,
                f"'{path}' is declared AT {variable.location}: give it its address in the "
                f"configuration's VAR_CONFIG ({resource}.{path} AT ... : {variable.type.name};)",
            )
    result.located = tuple(sorted(located.values()))
    accesses = [a for c in configurations for a in c.access]
    result.access_paths = _access_paths(result, variables, located, accesses, resource)
    return result


def _check_declarations(resolved: Resolved, result: Configured) -> None:
    """Only variables of instances can be completed: a VAR of a program or block, or a
    global, each with a name; an input or output of one too, as in TwinCAT (W0810)."""
    for pou in resolved.sorted_pous():
        for variable in pou.variables:
            if not partly_located(variable.location):
                continue
            instance_io = pou.kind in ("PROGRAM", "FUNCTION_BLOCK") and variable.kind in (
                "VAR_INPUT",
                "VAR_OUTPUT",
            )
            if variable.name == variable.location:
                where = "needs a name for VAR_CONFIG to complete it"
            elif instance_io:
                # TwinCAT links a block's inputs and outputs to its terminals this way
                message = (
                    f"'{variable.name}' AT {variable.location} in {variable.kind} is TwinCAT; "
                    "IEC 61131-3 locates only a VAR of a program or function block partly"
                )
                result.report(variable.pos, Code.LOCATED_PARAMETER, message)
                continue
            elif pou.kind == "FUNCTION" or variable.kind not in ("VAR", "VAR_GLOBAL"):
                where = "is no VAR of a program or function block, so no instance has it"
            else:
                continue
            result.report(
                variable.pos,
                Code.UNCONFIGURED_LOCATION,
                f"'{variable.name}' AT {variable.location} {where}",
            )


def _complete(
    result: Configured,
    variables: dict[str, tuple[str, Variable]],
    inits: list[ast.ConfigInit],
    resource: str,
    tried: set[str],
) -> dict[str, tuple[str, str]]:
    """The paths VAR_CONFIG completes, with their path and address; `tried` gets every
    path it has an entry for."""
    located: dict[str, tuple[str, str]] = {}
    for init in inits:
        dotted = ".".join(init.path)
        if key(init.path[0]) != key(resource):
            message = f"'{dotted}' does not start with the resource '{resource}'"
            result.report(init.pos, Code.VAR_CONFIG_PATH, message)
            continue
        upper = key(".".join(init.path[1:]))
        path, variable = variables.get(upper, ("", None))
        if variable is None or not partly_located(variable.location):
            what = "is no variable" if variable is None else "has no partly specified location"
            message = f"'{dotted}' {what}; VAR_CONFIG gives addresses to AT %I*, %Q*, %M* only"
            result.report(init.pos, Code.VAR_CONFIG_PATH, message)
            continue
        if upper in located or upper in tried:
            result.report(init.pos, Code.VAR_CONFIG_PATH, f"'{dotted}' is configured twice")
            continue
        tried.add(upper)  # the entry's own problem is reported, not a missing entry
        problem = _misfit(init, variable)
        if problem is not None:
            result.report(init.pos, Code.VAR_CONFIG_ADDRESS, f"'{dotted}': {problem}")
            continue
        assert init.location is not None
        located[upper] = (path, init.location)
    return located


def _misfit(init: ast.ConfigInit, variable: Variable) -> str | None:
    declared = variable.location or ""
    address = init.location
    if address is None or address.endswith("*"):
        return f"needs a complete address (AT {declared[:2]}X1.0, ...)"
    if address[1:2] != declared[1:2]:
        return f"{address} is not in the area of {declared}"
    size = address[2:3] if address[2:3] in SIZE_BITS else ""
    declared_size = declared[2:3] if declared[2:3] in SIZE_BITS else ""
    bits = variable.type.bits if isinstance(variable.type, ElementaryType) else 0
    if not size or (declared_size and size != declared_size) or SIZE_BITS[size] != bits:
        return f"the size of {address} does not fit {variable.type.name}"
    if not isinstance(init.type, ast.NamedType) or key(init.type.name) != key(variable.type.name):
        return f"the type differs from its declaration ({variable.type.name})"
    if init.init is not None:
        return "instance-specific initial values are not supported; give the address only"
    return None


def _access_paths(
    result: Configured,
    variables: dict[str, tuple[str, Variable]],
    located: dict[str, tuple[str, str]],
    accesses: list[ast.AccessDecl],
    resource: str,
) -> tuple[AccessPath, ...]:
    by_address = {key(v.location): (path, v) for path, v in variables.values() if v.location}
    by_address.update(
        {key(address): (path, variables[upper][1]) for upper, (path, address) in located.items()}
    )
    paths: dict[str, AccessPath] = {}
    for access in accesses:
        parts = access.path
        if len(parts) > 1 and key(parts[0]) == key(resource):
            parts = parts[1:]
        dotted = ".".join(access.path)
        if parts[-1].startswith("%"):
            found = by_address.get(key(parts[-1])) if len(parts) == 1 else None
        else:
            found = variables.get(key(".".join(parts)))
        if key(access.name) in paths:
            result.report(access.pos, Code.ACCESS_PATH, f"access path '{access.name}' twice")
            continue
        if found is None:
            message = f"'{dotted}' names no variable of the resource '{resource}'"
            result.report(access.pos, Code.ACCESS_PATH, message)
            continue
        path, variable = found
        type_name = access.type.name if isinstance(access.type, ast.NamedType) else ""
        if key(type_name) != key(variable.type.name):
            message = f"'{dotted}' is {variable.type.name}, not {type_name or 'that type'}"
            result.report(access.pos, Code.ACCESS_PATH, message)
            continue
        if access.writable and variable.constant:
            message = f"'{dotted}' is a constant: READ_ONLY only"
            result.report(access.pos, Code.ACCESS_PATH, message)
            continue
        paths[key(access.name)] = AccessPath(access.name, path, variable.type.name, access.writable)
    return tuple(paths[name] for name in sorted(paths))
