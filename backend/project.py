"""The project model: a folder with `padt.toml` (resource, programs) and `.st` sources.

The TOML format is documented in docs/project-format.md.
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any

from backend.compiler.pipeline import CompileResult, compile_sources
from backend.compiler.source import SourceFile, read_source
from runtime.artifact import ProgramConfig, ResourceConfig

PROJECT_FILE = "padt.toml"
AUTOSTART_MODES = ("off", "cold", "warm")


class ProjectError(ValueError):
    """The project cannot be read; the message says where and why."""


@dataclass(frozen=True)
class Project:
    name: str
    version: str
    resource: ResourceConfig | None  # None: from the sources' CONFIGURATION, or a default
    programs: list[ProgramConfig] | None  # None: every PROGRAM runs, in source order
    sources: list[SourceFile]


def demo_project_path() -> Path:
    return Path(str(resources.files("backend").joinpath("projects", "demo")))


def load_project(paths: list[Path]) -> Project:
    """A project folder, or loose .st files (then with a default resource)."""
    if len(paths) == 1 and paths[0].is_dir():
        return _load_folder(paths[0])
    sources = []
    for path in paths:
        if not path.is_file():
            raise ProjectError(f"{path}: no such file")
        sources.append(read_source(path))
    name = paths[0].stem if paths else "project"
    return Project(name, "", None, None, sources)


def _load_folder(folder: Path) -> Project:
    st_files = sorted(folder.rglob("*.st"))
    sources = [read_source(p, str(p.relative_to(folder))) for p in st_files]
    config_path = folder / PROJECT_FILE
    if not config_path.exists():
        return Project(folder.name, "", None, None, sources)
    try:
        data = tomllib.loads(config_path.read_text(encoding="utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise ProjectError(f"{config_path}: {exc}") from None
    return _project_from_toml(data, sources, str(config_path))


def _project_from_toml(data: dict[str, Any], sources: list[SourceFile], where: str) -> Project:
    meta = data.get("project", {})
    res = data.get("resource")
    if not isinstance(res, dict) or not isinstance(res.get("name"), str):
        raise ProjectError(f"{where}: [resource] with a name is required")
    autostart = res.get("autostart", "off")
    if autostart not in AUTOSTART_MODES:
        raise ProjectError(f"{where}: autostart must be one of {', '.join(AUTOSTART_MODES)}")
    cycle_ms = res.get("cycle_ms", 100)
    if not isinstance(cycle_ms, int) or not 1 <= cycle_ms <= 7500:
        raise ProjectError(f"{where}: cycle_ms must be an integer from 1 to 7500")
    watchdog_ms = res.get("watchdog_ms", 200)
    if not isinstance(watchdog_ms, int) or not 6 <= watchdog_ms <= 7500:
        raise ProjectError(f"{where}: watchdog_ms must be an integer from 6 to 7500")
    resource = ResourceConfig(
        name=res["name"], cycle_ms=cycle_ms, autostart=autostart, watchdog_ms=watchdog_ms
    )
    programs = None
    if "program" in res:
        programs = []
        for entry in res["program"]:
            try:
                programs.append(
                    ProgramConfig(
                        name=str(entry["name"]),
                        pou=str(entry.get("pou", entry["name"])),
                        program_id=int(entry["id"]),
                        priority=int(entry.get("priority", 0)),
                    )
                )
            except (KeyError, TypeError, ValueError) as exc:
                raise ProjectError(f"{where}: [[resource.program]] needs {exc}") from None
    return Project(
        str(meta.get("name", "project")), str(meta.get("version", "")), resource, programs, sources
    )


def compile_project(project: Project, config_file: str = PROJECT_FILE) -> CompileResult:
    return compile_sources(
        project.sources,
        project=project.name,
        resource=project.resource,
        programs=project.programs,
        config_file=config_file,
    )
