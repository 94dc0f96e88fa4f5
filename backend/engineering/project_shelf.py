"""The projects a PADT knows, by name, each a folder: the ones it was given (`--project`)
and the ones in its folder for projects (`--projects-dir`), where new projects are made
from the templates in backend/projects/templates (and the demo tank, backend/projects/demo).

The shelf is a mapping name -> folder for the screens and routes that only look a project
up; it also holds what every edit of a project needs: the PADT's audit log, and one lock
so that checking a file's base hash and replacing the file are one step for all users.
"""

from __future__ import annotations

import os
import shutil
import threading
import time
import unicodedata
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

import tomlkit

from backend.engineering.padt_audit_log import PadtAuditLog
from backend.engineering.project import PROJECT_FILE, copy_template_sources, demo_project_path
from backend.engineering.project_access import WRITE, Editor, require
from runtime.contract.refusal import Refusal

MAX_PROJECT_NAME = 64
RESOURCE_NAME_CHARS = frozenset("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-")


@dataclass(frozen=True)
class Template:
    name: str
    title: str
    folder: Path


def templates() -> list[Template]:
    """The templates a new project starts from, in the order a user is offered them."""
    own = Path(str(resources.files("backend").joinpath("projects", "templates")))
    return [
        Template("empty", "Empty: one resource running an empty PROGRAM Main", own / "empty"),
        Template(
            "tank", "The demo tank: a level kept between two marks, Modbus I/O", demo_project_path()
        ),
        Template(
            "sequence", "A step sequence in SFC: fill, heat, drain a vessel", own / "sequence"
        ),
        Template(
            "conveyor",
            "A conveyor drive drawn in LD and FBD: interlock, run timer, temperature alarm",
            own / "conveyor",
        ),
    ]


def project_name_problem(name: str) -> str | None:
    """Why `name` cannot name a project (it is its folder's name), or None."""
    if not name or name != name.strip():
        return "a project name must not be empty nor start or end with a space"
    if len(name) > MAX_PROJECT_NAME:
        return f"a project name has at most {MAX_PROJECT_NAME} characters"
    if name in (".", "..") or name.startswith("."):
        return "a project name must not start with '.'"
    bad = sorted({c for c in name if c in '/\\:*?"<>|=' or unicodedata.category(c)[0] == "C"})
    if bad:
        shown = ", ".join(repr(c) for c in bad)
        return f"a project name must not hold {shown} (it is a folder's name)"
    return None


class ProjectShelf(Mapping[str, Path]):
    def __init__(
        self,
        given: Mapping[str, Path] | None = None,
        new_dir: Path | None = None,
        audit: PadtAuditLog | None = None,
        template_folders: Mapping[str, Path] | None = None,
    ) -> None:
        """`given`: projects by name (`--project`); `new_dir`: the folder for new projects,
        listed now (each sub-folder holding padt.toml or .st files is a project named after
        it) and made when missing; `audit`: where edits are recorded (without one, the
        projects can be read but not changed: every change must be audited)."""
        self.new_dir = new_dir
        self.audit = audit
        self.template_folders = dict(template_folders or {})
        self.lock = threading.RLock()  # a file's base-hash check and its replacement: one step
        self._given = dict(given or {})
        self._projects: dict[str, Path] = {}
        if new_dir is not None:
            new_dir.mkdir(parents=True, exist_ok=True)
        self.refresh()

    def refresh(self) -> None:
        """List the folder for projects again: projects another tool made there appear."""
        found = dict(self._given)
        if self.new_dir is not None and self.new_dir.is_dir():
            for entry in sorted(self.new_dir.iterdir()):
                if entry.name in found or project_name_problem(entry.name) is not None:
                    continue
                if entry.is_dir() and not entry.is_symlink() and _holds_a_project(entry):
                    found[entry.name] = entry
        with self.lock:
            self._projects = dict(sorted(found.items()))

    def __getitem__(self, name: str) -> Path:
        with self.lock:
            return self._projects[name]

    def __iter__(self) -> Iterator[str]:
        with self.lock:
            return iter(list(self._projects))

    def __len__(self) -> int:
        with self.lock:
            return len(self._projects)

    def folder(self, name: str) -> Path:
        """The folder of project `name`; refused (`unknown_project`) when there is none."""
        with self.lock:
            found = self._projects.get(name)
        if found is None:
            raise Refusal("unknown_project", f"there is no project '{name}'")
        return found

    def audit_log(self) -> PadtAuditLog:
        """The audit log every change is recorded in; refused when this PADT keeps none."""
        if self.audit is None:
            raise Refusal("forbidden", "this PADT keeps no audit log: its projects are read-only")
        return self.audit

    def new_project(
        self, name: str, template: str, editor: Editor, resource: str | None = None
    ) -> Path:
        """A new project `name` in the folder for projects, copied from `template`, its
        [project] name set to `name` (and its resource's name to `resource` when given).
        Refused with the reason for a bad or taken name, an unknown template, no folder for
        projects, or a level below read-write."""
        require(editor, WRITE)
        audit = self.audit_log()
        if self.new_dir is None:
            raise Refusal("forbidden", "this PADT has no folder for new projects (--projects-dir)")
        with self.lock:
            self.refresh()
            if name.casefold() in {n.casefold() for n in self._projects}:
                raise Refusal("exists", f"there is a project '{name}' already")
            target = make_project(
                self.new_dir, name, template, resource, self.template_folders.get(template)
            )
            try:
                audit.record(editor.user, name, "new-project", f"template:{template}", "", "")
            except OSError as exc:  # a project the log does not know of is not left behind
                shutil.rmtree(target, ignore_errors=True)
                raise Refusal(
                    "audit", f"the audit log cannot be written ({exc.strerror}): no project made"
                ) from None
            self.refresh()
        return target


def make_project(
    parent: Path,
    name: str,
    template: str,
    resource: str | None = None,
    folder: Path | None = None,
) -> Path:
    """The new project folder `parent/name` from `template`, its [project] name set to
    `name` (and its resource's name to `resource` when given), made whole or not at all.
    Refused with the reason: a name that is no folder name, a folder that exists, an
    unknown template, a resource name that is no key of Zenoh. `folder`: where this PADT
    keeps the template's files, when not with the others (the demo's tank: its running
    copy, with its accounts and its plant's port)."""
    problem = project_name_problem(name)
    if problem is not None:
        raise Refusal("bad_value", problem)
    chosen = next((t for t in templates() if t.name == template), None)
    if chosen is None:
        known = ", ".join(t.name for t in templates())
        raise Refusal("bad_value", f"there is no template '{template}' (there are: {known})")
    if resource is not None and resource_name_problem(resource) is not None:
        raise Refusal("bad_value", str(resource_name_problem(resource)))
    target = parent / name
    if os.path.lexists(target):
        raise Refusal("exists", f"there is a project '{name}' already")
    staging = parent / f".new-{name}"
    shutil.rmtree(staging, ignore_errors=True)
    try:
        parent.mkdir(parents=True, exist_ok=True)
        _copy_template(folder or chosen.folder, staging, name, resource)
        os.rename(staging, target)
    except OSError as exc:
        shutil.rmtree(staging, ignore_errors=True)
        raise Refusal("project", f"project '{name}' could not be made: {exc}") from None
    return target


def _holds_a_project(folder: Path) -> bool:
    return (folder / PROJECT_FILE).is_file() or any(folder.glob("*.st"))


def resource_name_problem(name: str) -> str | None:
    """Why `name` cannot name a resource (a plain key chunk of Zenoh), or None."""
    if (
        0 < len(name) <= 64
        and (name[0].isascii() and (name[0].isalpha() or name[0] == "_"))
        and all(c in RESOURCE_NAME_CHARS for c in name)
    ):
        return None
    return (
        f"'{name[:64]}' cannot name a resource: a letter or _, then letters, digits, _ or - "
        "(at most 64)"
    )


def _copy_template(source: Path, target: Path, name: str, resource: str | None) -> None:
    """The template's padt.toml, .st files and tests (nothing else: a template is a
    project)."""
    target.mkdir(parents=True)
    copy_template_sources(source, target)
    document = tomlkit.parse((source / PROJECT_FILE).read_text(encoding="utf-8"))
    project = document.get("project")
    if isinstance(project, dict):
        project["name"] = name
    if resource is not None:
        res = document.get("resource")
        if isinstance(res, dict):
            res["name"] = resource
    (target / PROJECT_FILE).write_text(tomlkit.dumps(document), encoding="utf-8")


def shelf_of(
    given: Mapping[str, Path],
    projects_dir: Path | None,
    audit_log: Path,
    template_folders: Mapping[str, Path] | None = None,
) -> ProjectShelf:
    """The shelf of `padt ui`, `padt api` and `padt demo`: the projects given, those in
    `projects_dir`, and the audit log at `audit_log` (wall-clock time)."""
    return ProjectShelf(
        given, projects_dir, PadtAuditLog(audit_log, time.time_ns), template_folders
    )
