"""The files of the padt project an import writes: a `.st` file per POU, the data types,
the global variables, and `padt.toml` with the resource, its tasks and program instances.

One resource per project: the first resource of the first configuration is imported, as
the compiler does with an IEC CONFIGURATION (docs/language.md), and by the same rules:
each program instance is a user program with the priority of its task, the CPU cycle is
the shortest task interval.
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass, field

from backend.engineering.plcopen.issues import ImportCode, Where
from backend.engineering.plcopen.model import Configuration, PlcProject, Resource
from backend.engineering.plcopen.st_text import globals_text, interface_text, pou_text, types_text
from backend.engineering.project import PROJECT_FILE
from runtime.contract.artifact import ResourceConfig
from runtime.contract.parameters import PROGRAM_BY_NAME, RESOURCE_BY_NAME

TYPES_FILE = "data-types.st"  # a '-' in the name: no POU can be called so
GLOBALS_FILE = "global-variables.st"
DEFAULT_RESOURCE = "Resource1"
DEFAULT_CYCLE_MS = 100  # no task has an interval: as for an IEC CONFIGURATION


@dataclass
class Files:
    contents: dict[str, str] = field(default_factory=dict)  # relative path -> text
    warnings: list[tuple[Where, ImportCode, str]] = field(default_factory=list)
    programs: int = 0  # user programs in padt.toml
    global_variables: int = 0


def project_files(project: PlcProject, source_name: str) -> Files:
    files = Files()
    for pou in project.pous:
        files.contents[f"{pou.name}.st"] = pou_text(pou)
    for interface in project.interfaces:
        files.contents[f"{interface.name}.st"] = interface_text(interface)
    if project.types:
        files.contents[TYPES_FILE] = types_text(project.types)
    configuration, chosen = _chosen(project, files)
    sections = [*project.globals]
    if configuration is not None:
        sections += configuration.globals
    if chosen is not None:
        sections += chosen.globals
    files.global_variables = sum(len(section.variables) for section in sections)
    if sections:
        files.contents[GLOBALS_FILE] = globals_text(sections)
    files.contents[PROJECT_FILE] = _toml(project, source_name, chosen, files)
    files.contents = dict(sorted(files.contents.items()))
    return files


def _chosen(project: PlcProject, files: Files) -> tuple[Configuration | None, Resource | None]:
    """The first resource and its configuration (whose global variables come along); every
    other resource, and the global variables of every other configuration, reported."""
    resources = [(c, r) for c in project.configurations for r in c.resources]
    configuration, chosen = resources[0] if resources else (None, None)
    if configuration is None and project.configurations:
        configuration = project.configurations[0]
    for _, extra in resources[1:]:
        files.warnings.append(
            (
                extra.where,
                ImportCode.EXTRA_RESOURCE,
                f"resource {extra.name} ignored, with its tasks, programs and global "
                "variables: a padt project has one resource",
            )
        )
    for other in project.configurations:
        if other is not configuration and other.globals:
            files.warnings.append(
                (
                    other.where,
                    ImportCode.EXTRA_RESOURCE,
                    f"configuration {other.name} ignored, with its global variables: a padt "
                    "project has one resource",
                )
            )
    return configuration, chosen


def _string(text: str) -> str:
    """A TOML basic string: JSON's, with DEL escaped too (TOML forbids it bare)."""
    return json.dumps(text, ensure_ascii=False).replace("\x7f", "\\u007f")


def _comment(text: str) -> str:
    """Text for a TOML comment, which ends at a line break (a file name may hold one)."""
    return re.sub(r"[\x00-\x1f\x7f]", " ", text)


def _not_imported_lines(project: PlcProject) -> list[str]:
    if not project.not_imported and not project.dropped:
        return []
    lines = ["# Not imported (padt compiles ST and SFC; see docs/plcopen-import.md):"]
    lines += [f"#   {m.name}: {_comment(m.reason)}" for m in project.not_imported]
    lines += [f"#   {d.owner}: its CODESYS {d.what}" for d in project.dropped]
    return lines


def _toml(project: PlcProject, source_name: str, chosen: Resource | None, files: Files) -> str:
    lines = [f"# Imported from {_comment(source_name)} by padt import."]
    lines += _not_imported_lines(project)
    lines += ["", "[project]", f"name = {_string(project.name or source_name)}"]
    if project.version:
        lines.append(f"version = {_string(project.version)}")
    if chosen is None:
        lines += [
            "",
            "# the file has no configuration: every PROGRAM runs, in source order",
            "[resource]",
            f'name = "{DEFAULT_RESOURCE}"',
            f"target_cycle_ms = {DEFAULT_CYCLE_MS}",
        ]
        return "\n".join(lines) + "\n"
    lines += ["", "[resource]", f"name = {_string(chosen.name)}"]
    lines += _cycle_lines(chosen, files)
    lines += _program_lines(project, chosen, files)
    return "\n".join(lines) + "\n"


def _cycle_lines(chosen: Resource, files: Files) -> list[str]:
    intervals = [t.interval_ms for t in chosen.tasks if t.interval_ms is not None]
    for task in chosen.tasks:
        if task.interval_ms is None:
            files.warnings.append(
                (
                    task.where,
                    ImportCode.TASK,
                    f"task {task.name} has no interval (an event task): its programs run "
                    "in every CPU cycle",
                )
            )
    cycle = max(1, min(intervals)) if intervals else DEFAULT_CYCLE_MS
    limit = RESOURCE_BY_NAME["target_cycle_ms"].high
    assert limit is not None
    if cycle > limit:
        shortest = next(t for t in chosen.tasks if t.interval_ms == min(intervals))
        files.warnings.append(
            (
                shortest.where,
                ImportCode.TASK,
                f"task {shortest.name}: interval {cycle} ms is longer than the longest CPU "
                f"cycle, {limit} ms, which the resource takes instead",
            )
        )
        cycle = limit
    why = "the shortest task interval" if intervals else "no task has an interval"
    lines = [
        f"target_cycle_ms = {cycle}  # {why}",
        'target_cycle_mode = "fixed"',
    ]
    defaults = ResourceConfig(name="")
    if cycle > defaults.watchdog_ms:  # the watchdog must allow the cycle, the safety time
        watchdog = min(2 * cycle, limit)  # twice the watchdog (parameters.md)
        lines += [
            f"watchdog_ms = {watchdog}",
            f"safety_time_ms = {max(defaults.safety_time_ms, 2 * watchdog)}",
        ]
    return lines


def _program_lines(project: PlcProject, chosen: Resource, files: Files) -> list[str]:
    missing = {m.name.upper(): m for m in project.not_imported}
    tasks = {t.name.upper(): t for t in chosen.tasks}
    highest = PROGRAM_BY_NAME["priority"].high
    most = PROGRAM_BY_NAME["program_id"].high
    assert highest is not None and most is not None
    entries: list[str] = []
    number = 0
    for instance in chosen.instances:
        if instance.pou.upper() in missing:
            files.warnings.append(
                (
                    instance.where,
                    ImportCode.INSTANCE_LEFT_OUT,
                    f"program instance {instance.name} left out: its POU {instance.pou} is "
                    f"not imported ({missing[instance.pou.upper()].reason})",
                )
            )
            continue
        if number == most:
            files.warnings.append(
                (
                    instance.where,
                    ImportCode.TOO_MANY_PROGRAMS,
                    f"program instance {instance.name} left out: a resource runs at most "
                    f"{most} programs",
                )
            )
            continue
        task = tasks.get(instance.task.upper())
        priority = task.priority if task is not None else 0
        if priority > highest:
            files.warnings.append(
                (
                    instance.where,
                    ImportCode.TASK,
                    f"program instance {instance.name}: task priority {priority} is "
                    f"lower than padt's lowest, {highest}, which it gets",
                )
            )
            priority = highest
        number += 1
        files.programs = number
        where = f"  # task {task.name}" if task is not None else "  # no task"
        entries += [
            "",
            "[[resource.program]]",
            f"name = {_string(instance.name)}",
            f"pou = {_string(instance.pou)}",
            f"id = {number}",
            f"priority = {priority}{where}",
        ]
    if not entries and chosen.instances:  # none imported: no other PROGRAM may run instead
        return ["program = []  # no program instance could be imported"]
    return entries
