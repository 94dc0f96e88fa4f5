"""padt.toml as forms edit it: the project's name, the resource and its parameters, the
program instances, the safe values, the Modbus server and devices with their points.

Read into typed dataclasses; a draft is checked field by field as one types
(`settings_problems`: each parameter against its range, the resource's name, then a
compile of the project with the draft padt.toml for what only the compiler knows, with its
codes); written with tomlkit, only what changed, so that comments, order and untouched
values stay as they were and a Git diff shows the change alone. The PES accounts
(`[[resource.user]]`) are kept as they are: `padt passwd` makes them. A draft with an
error is never written; a write is whole or not at all (project_files).
"""

from __future__ import annotations

import copy
import re
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import tomlkit
from tomlkit.items import AoT

from backend.compiler.toml_lines import key_lines
from backend.engineering.project import (
    PROJECT_FILE,
    ProjectError,
    compile_project,
    configured_project,
    project_sources,
)
from backend.engineering.project_access import READ, WRITE, Editor, require
from backend.engineering.project_files import Saved, read_file, save_file
from backend.engineering.project_shelf import ProjectShelf, resource_name_problem
from runtime.contract.artifact import ResourceConfig
from runtime.contract.parameters import (
    PROGRAM_BY_NAME,
    RESOURCE_BY_NAME,
    ParameterError,
    ParameterSpec,
    resource_consistency,
)
from runtime.contract.refusal import Refusal

PROJECT_KEYS = ("name", "version", "author", "date")
IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]{0,63}")
# a program instance's parameters; its program_id is the instance's `id`, not one of them
_PROGRAM_PARAMETERS = {name: spec for name, spec in PROGRAM_BY_NAME.items() if name != "program_id"}


@dataclass
class ProgramSettings:
    name: str  # the instance's name
    pou: str  # the PROGRAM it instantiates
    id: int
    parameters: dict[str, Any] = field(default_factory=dict)  # priority, max_duration_us, ...


@dataclass
class ModbusPoint:
    variable: str
    area: str  # coil, discrete_input, holding_register, input_register
    address: int
    settings: dict[str, Any] = field(default_factory=dict)  # safe_value, ...


@dataclass
class ModbusDevice:
    name: str
    host: str
    port: int
    settings: dict[str, Any] = field(default_factory=dict)  # unit_id, period_ms, timeout_ms
    points: list[ModbusPoint] = field(default_factory=list)


@dataclass
class Settings:
    project: dict[str, str]  # name, version, author, date
    resource: str  # the resource's name
    parameters: dict[str, Any]  # the resource's parameters (docs/parameters.md)
    programs: list[ProgramSettings]
    safe_values: dict[str, Any] = field(default_factory=dict)
    modbus: dict[str, Any] | None = None  # the server ([modbus] but its devices); None: none
    devices: list[ModbusDevice] = field(default_factory=list)


@dataclass(frozen=True)
class SettingsFile:
    settings: Settings
    hash: str  # of padt.toml, the base of a write


@dataclass(frozen=True)
class Problem:
    field: str  # a key path of padt.toml: resource.watchdog_ms, resource.program.0.priority
    message: str
    code: str = ""  # the compiler's code, when the compiler found it
    severity: str = "error"


def read_settings(shelf: ProjectShelf, project: str, editor: Editor) -> SettingsFile:
    require(editor, READ)
    current = read_file(shelf, project, PROJECT_FILE, editor)
    try:
        data = tomllib.loads(current.text)
    except (tomllib.TOMLDecodeError, RecursionError) as exc:
        raise Refusal("project", f"padt.toml cannot be read: {exc}") from None
    return SettingsFile(settings_of(data), current.hash)


def settings_of(data: dict[str, Any]) -> Settings:
    """The settings of padt.toml's data as tomllib reads it (what is missing, empty)."""
    meta = _table(data.get("project"))
    res = _table(data.get("resource"))
    modbus = data.get("modbus")
    server = {k: v for k, v in _table(modbus).items() if k != "device"} if modbus else None
    return Settings(
        project={k: str(meta[k]) for k in PROJECT_KEYS if k in meta},
        resource=str(res.get("name", "")),
        parameters={k: v for k, v in sorted(res.items()) if k in RESOURCE_BY_NAME},
        programs=[
            ProgramSettings(
                str(p.get("name", "")),
                str(p.get("pou", p.get("name", ""))),
                p.get("id", 0),
                {k: v for k, v in sorted(p.items()) if k not in ("name", "pou", "id")},
            )
            for p in _tables(res.get("program"))
        ],
        safe_values=dict(sorted(_table(res.get("safe_values")).items())),
        modbus=server,
        devices=[
            ModbusDevice(
                str(d.get("name", "")),
                str(d.get("host", "")),
                d.get("port", 0),
                {k: v for k, v in sorted(d.items()) if k not in ("name", "host", "port", "point")},
                [
                    ModbusPoint(
                        str(p.get("variable", "")),
                        str(p.get("area", "")),
                        p.get("address", 0),
                        {
                            k: v
                            for k, v in sorted(p.items())
                            if k not in ("variable", "area", "address")
                        },
                    )
                    for p in _tables(d.get("point"))
                ],
            )
            for d in _tables(_table(modbus).get("device"))
        ],
    )


def settings_problems(
    shelf: ProjectShelf, project: str, draft: Settings, editor: Editor
) -> list[Problem]:
    """What is wrong with a draft, by field, in the order of padt.toml; empty when it
    would be written. The compile runs only when each field is right on its own."""
    require(editor, READ)
    problems = _field_problems(draft)
    if problems:
        return problems
    current = read_file(shelf, project, PROJECT_FILE, editor)
    text = settings_text(current.text, draft)
    sources = project_sources(shelf.folder(project))
    try:
        result = compile_project(configured_project(text, sources, PROJECT_FILE))
    except ProjectError as exc:
        return [Problem("", str(exc).removeprefix(f"{PROJECT_FILE}: "))]
    lines = sorted((line, key) for key, line in key_lines(text).items())
    found = []
    for diagnostic in result.diagnostics:
        if diagnostic.file != PROJECT_FILE:
            continue
        at = [key for line, key in lines if line == diagnostic.line]
        found.append(
            Problem(
                max(at, key=len) if at else "",
                diagnostic.message,
                diagnostic.code,
                diagnostic.severity,
            )
        )
    return found


def write_settings(
    shelf: ProjectShelf, project: str, draft: Settings, base_hash: str, editor: Editor
) -> Saved:
    """padt.toml with the draft's settings, when it has no error; refused (`settings`,
    with the problems) otherwise, or as a conflict when padt.toml changed since
    `base_hash`."""
    require(editor, WRITE)
    problems = [
        p for p in settings_problems(shelf, project, draft, editor) if p.severity == "error"
    ]
    if problems:
        first = problems[0]
        raise Refusal(
            "settings",
            f"{first.field or PROJECT_FILE}: {first.message}"
            + (f" (and {len(problems) - 1} more)" if len(problems) > 1 else ""),
            problems=[p.__dict__ for p in problems],
        )
    current = read_file(shelf, project, PROJECT_FILE, editor)
    text = settings_text(current.text, draft)
    return save_file(shelf, project, PROJECT_FILE, text, base_hash, editor)


def settings_text(text: str, draft: Settings) -> str:
    """`text` (padt.toml) with the draft's settings: only the values that differ are
    written; comments, order and every other table stay. Refused (`project`) for a
    padt.toml that does not parse or whose form the settings cannot keep (an inline table
    where they write tables: edit it as text)."""
    try:
        document = tomlkit.parse(text)
    except tomlkit.exceptions.ParseError as exc:
        raise Refusal("project", f"padt.toml cannot be read: {exc}") from None
    try:
        written = _with_settings(document, draft)
        tomllib.loads(written)  # what tomlkit wrote into an inline table may not be TOML
        return written
    except (
        tomlkit.exceptions.TOMLKitError,
        tomllib.TOMLDecodeError,
        TypeError,
        ValueError,
        AttributeError,
    ) as exc:
        raise Refusal(
            "project", f"padt.toml has a form these settings cannot keep ({exc}): edit it as text"
        ) from None


def _with_settings(document: Any, draft: Settings) -> str:
    meta = _child(document, "project")
    _merge(meta, {k: v for k, v in draft.project.items() if v != ""}, PROJECT_KEYS)
    res = _child(document, "resource")
    _merge(res, {"name": draft.resource}, ("name",))
    _merge(res, draft.parameters, tuple(RESOURCE_BY_NAME))
    _merge_array(
        res,
        "program",
        [{"name": p.name, "pou": p.pou, "id": p.id, **p.parameters} for p in draft.programs],
    )
    if draft.safe_values or "safe_values" in res:
        values = _child(res, "safe_values")
        _merge(values, draft.safe_values, tuple(values) + tuple(draft.safe_values))
    if draft.modbus is None and not draft.devices:
        if "modbus" in document:
            del document["modbus"]
    else:
        server = _child(document, "modbus")
        keys = tuple(k for k in server if k != "device") + tuple(draft.modbus or {})
        _merge(server, draft.modbus or {}, keys)
        _merge_array(
            server,
            "device",
            [
                {
                    "name": d.name,
                    "host": d.host,
                    "port": d.port,
                    **d.settings,
                    "point": [
                        {"variable": p.variable, "area": p.area, "address": p.address, **p.settings}
                        for p in d.points
                    ],
                }
                for d in draft.devices
            ],
        )
    return tomlkit.dumps(document)


def _parameter_problems(
    where: str, values: Mapping[str, Any], specs: Mapping[str, ParameterSpec]
) -> list[Problem]:
    """Each value that is no parameter of `specs` or out of its range, at `where.name`."""
    problems = []
    for name, value in values.items():
        spec = specs.get(name)
        if spec is None:
            problems.append(Problem(f"{where}.{name}", f"unknown parameter '{name}'"))
            continue
        try:
            spec.check(value)
        except ParameterError as exc:
            problems.append(Problem(f"{where}.{name}", str(exc)))
    return problems


def _field_problems(draft: Settings) -> list[Problem]:
    problems = []
    name_problem = resource_name_problem(draft.resource)
    if name_problem is not None:
        problems.append(Problem("resource.name", name_problem))
    problems += _parameter_problems("resource", draft.parameters, RESOURCE_BY_NAME)
    if not problems:
        # with the defaults of the parameters not set, as the resource will have them
        values = ResourceConfig(name=draft.resource, **draft.parameters).__dict__
        problems += [Problem("resource", p) for p in resource_consistency(values)]
    seen: dict[str, int] = {}
    for index, program in enumerate(draft.programs):
        where = f"resource.program.{index}"
        if not IDENTIFIER.fullmatch(program.name):
            problems.append(
                Problem(
                    f"{where}.name",
                    "an instance's name is a name of ST: a letter or _, then letters, digits or _",
                )
            )
        elif program.name.casefold() in seen:
            problems.append(Problem(f"{where}.name", f"a second instance named {program.name}"))
        seen[program.name.casefold()] = index
        if not IDENTIFIER.fullmatch(program.pou):
            problems.append(Problem(f"{where}.pou", "the name of the PROGRAM it runs"))
        try:
            PROGRAM_BY_NAME["program_id"].check(program.id)
        except ParameterError as exc:
            problems.append(Problem(f"{where}.id", str(exc).replace("program_id", "id")))
        problems += _parameter_problems(where, program.parameters, _PROGRAM_PARAMETERS)
    ids = [p.id for p in draft.programs]
    for index, program in enumerate(draft.programs):
        if ids.count(program.id) > 1 and ids.index(program.id) != index:
            problems.append(
                Problem(f"resource.program.{index}.id", f"id {program.id} is taken already")
            )
    return problems


def _table(value: Any) -> dict[str, Any]:
    return value if isinstance(value, dict) else {}


def _tables(value: Any) -> list[dict[str, Any]]:
    return [v for v in value if isinstance(v, dict)] if isinstance(value, list) else []


def _child(parent: Any, key: str) -> Any:
    """The table `key` of `parent`, added (at the end) when missing."""
    if key not in parent or not isinstance(parent[key], dict):
        parent[key] = tomlkit.table()
    return parent[key]


def _merge(table: Any, wanted: dict[str, Any], keys: tuple[str, ...]) -> None:
    """Of `keys`: each in `wanted` set when it differs (an unchanged item keeps its
    comment), each not in `wanted` removed."""
    for key in dict.fromkeys(keys):
        if key in wanted:
            if key not in table or _plain(table[key]) != wanted[key]:
                table[key] = copy.deepcopy(wanted[key])
        elif key in table:
            del table[key]


def _merge_array(table: Any, key: str, wanted: list[dict[str, Any]]) -> None:
    """An array of tables, entry by entry in place (each keeps its comments), the extra
    ones removed, new ones appended; nested arrays of tables (a device's points) alike."""
    if not wanted:
        if key in table:
            del table[key]
        return
    if key not in table or not isinstance(table[key], AoT | list):
        table[key] = tomlkit.aot()
    entries = table[key]
    while len(entries) > len(wanted):
        entries.pop()
    for index, values in enumerate(wanted):
        if index >= len(entries):
            if index > 0:
                entries[index - 1].add(tomlkit.nl())  # a blank line before the new table
            entries.append(tomlkit.table())
        entry = entries[index]
        nested = {
            k: v for k, v in values.items() if isinstance(v, list) and v and isinstance(v[0], dict)
        }
        plain = {k: v for k, v in values.items() if k not in nested}
        known = tuple(k for k in entry if not isinstance(entry[k], AoT)) + tuple(plain)
        _merge(entry, {k: v for k, v in plain.items() if not _empty_array_of_tables(v)}, known)
        for name, rows in nested.items():
            _merge_array(entry, name, rows)
        for name in [k for k in entry if isinstance(entry[k], AoT) and k not in nested]:
            del entry[name]


def _empty_array_of_tables(value: Any) -> bool:
    return isinstance(value, list) and not value


def _plain(item: Any) -> Any:
    return item.unwrap() if hasattr(item, "unwrap") else item
