"""The project model: a folder with `padt.toml` (resource, programs) and `.st` sources.

The TOML format is documented in docs/project-format.md.
"""

from __future__ import annotations

import itertools
import shutil
import tomllib
from dataclasses import dataclass, field, replace
from importlib import resources
from pathlib import Path
from typing import Any

from backend.compiler.limits import MAX_FILE_BYTES, MAX_PROJECT_FILES, MiB
from backend.compiler.pipeline import CompileResult, Parsed, compile_sources
from backend.compiler.source import SourceFile, read_sources
from backend.compiler.test_functions import TEST_FOLDER, is_test_file
from backend.compiler.toml_lines import key_lines
from runtime.contract.artifact import ProgramConfig, ResourceConfig, UserAccount
from runtime.contract.parameters import (
    PROGRAM_BY_NAME,
    RESOURCE_BY_NAME,
    ParameterError,
    ParameterSpec,
    resource_consistency,
)

PROJECT_FILE = "padt.toml"


class ProjectError(ValueError):
    """The project cannot be read; the message says where and why."""


@dataclass(frozen=True)
class Project:
    name: str
    version: str
    resource: ResourceConfig | None  # None: from the sources' CONFIGURATION, or a default
    programs: list[ProgramConfig] | None  # None: every PROGRAM runs, in source order
    sources: list[SourceFile]
    safe_values: dict[str, Any] = field(default_factory=dict)  # output -> its safe value
    users: list[UserAccount] = field(default_factory=list)  # PES accounts ([[resource.user]])
    modbus: Any = None  # the [modbus] table as read; the compiler checks it
    opcua: Any = None  # the [opcua] table as read (None: none); the compiler checks it
    exchange: Any = None  # the [exchange] table as read (None: none); the compiler checks it
    config_lines: dict[str, int] = field(default_factory=dict)  # where each setting is
    author: str = ""  # [project] author and date: for the cover of the documentation
    date: str = ""


def user_entry(account: UserAccount) -> str:
    """A `[[resource.user]]` entry of padt.toml for an account (its hash only)."""
    return (
        f'[[resource.user]]\nname = "{account.name}"\nlevel = "{account.level}"\n'
        f'password_hash = "{account.password_hash}"\n'
    )


def demo_project_path() -> Path:
    return Path(str(resources.files("backend").joinpath("projects", "demo")))


def load_project(paths: list[Path]) -> Project:
    """A project folder, or loose .st files (then with a default resource)."""
    if len(paths) == 1 and paths[0].is_dir():
        return _load_folder(paths[0])
    for path in paths:
        if not path.is_file():
            raise ProjectError(f"{path}: no such file")
    sources = read_sources([(path, str(path)) for path in paths])
    name = paths[0].stem if paths else "project"
    return Project(name, "", None, None, sources)


def for_resource(project: Project, name: str | None) -> Project:
    """The project compiled for resource `name` in place of its `[resource] name` (the
    fleet load: one project, several resources, each its own configuration and CRC); the
    project itself when `name` is None. ProjectError for a project without a `[resource]`
    (loose .st files): there is no configuration to name."""
    if name is None:
        return project
    if project.resource is None:
        raise ProjectError(
            f"{project.name}: the project names no resource (no padt.toml with [resource]); "
            f"it cannot be compiled for resource {name}"
        )
    return replace(project, resource=replace(project.resource, name=name))


def project_sources(folder: Path) -> list[SourceFile]:
    """The .st files of a project folder, named by their path in it; not those of its
    `test/` folder, which only `padt test` compiles (docs/testing.md)."""
    # a folder with more files than a project may have is refused by the compiler: its
    # walk stops one file after the limit
    st_files = (p for p in folder.rglob("*.st") if not is_test_file(_name_in(folder, p)))
    chosen = sorted(itertools.islice(st_files, MAX_PROJECT_FILES + 1))
    return read_sources([(p, str(p.relative_to(folder))) for p in chosen])


def copy_template_sources(source: Path, target: Path) -> None:
    """The .st files of a template's folder (the demo's too) and its tests, the .st files
    below its `test/` folder, copied into the folder `target`: tests travel with the
    project (docs/testing.md)."""
    tests = source / TEST_FOLDER.rstrip("/")
    chosen = sorted(source.glob("*.st"))
    if tests.is_dir():
        chosen += sorted(tests.rglob("*.st"))
    for path in chosen:
        copy = target / path.relative_to(source)
        copy.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(path, copy)


def _name_in(folder: Path, path: Path) -> str:
    return path.relative_to(folder).as_posix()


def _load_folder(folder: Path) -> Project:
    sources = project_sources(folder)
    config_path = folder / PROJECT_FILE
    if not config_path.exists():
        return Project(folder.name, "", None, None, sources)
    if config_path.stat().st_size > MAX_FILE_BYTES:
        raise ProjectError(f"{config_path}: larger than {MAX_FILE_BYTES // MiB} MiB")
    try:
        text = config_path.read_text(encoding="utf-8")
    except UnicodeDecodeError as exc:
        raise ProjectError(f"{config_path}: {exc}") from None
    return configured_project(text, sources, str(config_path))


def configured_project(text: str, sources: list[SourceFile], where: str) -> Project:
    """The project that the text of its padt.toml configures over `sources`; `where`
    names the file in the messages."""
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ProjectError(f"{where}: {exc}") from None
    except RecursionError:  # tomllib recurses into nested arrays and tables
        raise ProjectError(f"{where}: values nested too deep") from None
    project = _project_from_toml(data, sources, where)
    return replace(project, config_lines=key_lines(text))


def _project_from_toml(data: dict[str, Any], sources: list[SourceFile], where: str) -> Project:
    meta = data.get("project", {})
    res = data.get("resource")
    if not isinstance(res, dict) or not isinstance(res.get("name"), str):
        raise ProjectError(f"{where}: [resource] with a name is required")
    settings = {k: v for k, v in res.items() if k not in ("name", "program", "safe_values", "user")}
    users = []
    for entry in res.get("user", []):
        try:
            users.append(
                UserAccount(str(entry["name"]), str(entry["level"]), str(entry["password_hash"]))
            )
        except (KeyError, TypeError) as exc:
            raise ProjectError(
                f"{where}: [[resource.user]] needs name, level and password_hash ({exc})"
            ) from None
    safe_values = res.get("safe_values", {})
    if not isinstance(safe_values, dict):
        raise ProjectError(f"{where}: [resource.safe_values] must be a table")
    resource = ResourceConfig(
        name=res["name"], **_parameters(settings, RESOURCE_BY_NAME, f"{where}: [resource]")
    )
    problems = resource_consistency(resource.__dict__)
    if problems:
        raise ProjectError(f"{where}: [resource] {problems[0]}")
    programs = None
    if "program" in res:
        programs = []
        for entry in res["program"]:
            if not isinstance(entry.get("name"), str) or "id" not in entry:
                raise ProjectError(f"{where}: [[resource.program]] needs a name and an id")
            settings = {k: v for k, v in entry.items() if k not in ("name", "pou", "id")}
            settings["program_id"] = entry["id"]
            context = f"{where}: program {entry['name']}"
            programs.append(
                ProgramConfig(
                    name=entry["name"],
                    pou=str(entry.get("pou", entry["name"])),
                    **_parameters(settings, PROGRAM_BY_NAME, context),
                )
            )
    return Project(
        str(meta.get("name", "project")),
        str(meta.get("version", "")),
        resource,
        programs,
        sources,
        safe_values,
        users,
        modbus=data.get("modbus"),
        opcua=data.get("opcua"),
        exchange=data.get("exchange"),
        author=str(meta.get("author", "")),
        date=str(meta.get("date", "")),
    )


def _parameters(
    settings: dict[str, Any], specs: dict[str, ParameterSpec], where: str
) -> dict[str, Any]:
    """Settings checked against their parameter table; an unknown name is an error (a typo
    must not silently leave a parameter at its default)."""
    checked = {}
    for name, value in sorted(settings.items()):
        spec = specs.get(name)
        if spec is None:
            raise ProjectError(f"{where}: unknown parameter '{name}'")
        try:
            checked[name] = spec.check(value)
        except ParameterError as exc:
            raise ProjectError(f"{where}: {exc}") from None
    return checked


def compile_project(
    project: Project, config_file: str = PROJECT_FILE, parsed: Parsed | None = None
) -> CompileResult:
    """`parsed`: the project's sources parsed already (`parse_project`), not parsed again."""
    return compile_sources(
        project.sources,
        project=project.name,
        resource=project.resource,
        programs=project.programs,
        config_file=config_file,
        safe_values=project.safe_values,
        users=project.users,
        modbus=project.modbus,
        config_lines=project.config_lines,
        opcua=project.opcua,
        parsed=parsed,
        exchange=project.exchange,
    )
