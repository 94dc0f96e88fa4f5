"""What a document is about: one compiled configuration, from a project folder, loose .st
files, or a backup zip written by `padt load`/`padt reload`.

Everything a section shows comes from here: the project's own description (name,
version, author, date), the artifact (CRCs, parameters, programs, variables, users), the
parsed sources and the compiler's cross-reference. Nothing comes from the clock or the
machine, so the same project gives the same document.
"""

from __future__ import annotations

import os
import tempfile
from dataclasses import dataclass, replace
from pathlib import Path

from backend.compiler import ast
from backend.compiler.cross_reference import VariableUses, cross_reference_of
from backend.compiler.pipeline import parse_project
from backend.engineering.archive_reader import ArchiveRefused, unpack
from backend.engineering.backup import BackupError, restore_backup
from backend.engineering.project import (
    Project,
    ProjectError,
    compile_project,
    load_project,
)
from backend.engineering.sources import PouSource, pou_sources_of
from runtime.contract.artifact import Artifact, load_artifact


class DocumentError(ValueError):
    """The document cannot be made; the message says why (a project that does not
    compile names its first error)."""


@dataclass(frozen=True)
class Subject:
    name: str
    version: str
    author: str
    date: str  # as the project gives it (ISO 8601 when it is a date), or ""
    project: Project
    artifact: Artifact
    units: tuple[ast.SourceUnit, ...]  # the project's own files, parsed
    lines: dict[str, tuple[str, ...]]  # file -> its lines
    pous: dict[str, PouSource]  # the source of each of the project's POUs, by upper name
    uses: tuple[VariableUses, ...]
    # loose files are named by the path they were given as (the CRC covers those names);
    # the document names them without the folder they share, which says nothing about
    # the program and would fill every cell of the cross-reference
    folder: str = ""

    @property
    def crc(self) -> str:
        return self.artifact.crc

    def shown(self, file: str) -> str:
        """A source's name as the document writes it."""
        prefix = os.path.join(self.folder, "") if self.folder else ""
        return file[len(prefix) :] if prefix and file.startswith(prefix) else file


def load_subject(paths: list[Path]) -> Subject:
    """A project folder, loose .st files, or one backup zip."""
    if len(paths) == 1 and paths[0].suffix.lower() == ".zip" and paths[0].is_file():
        return _from_backup(paths[0])
    try:
        project = load_project(paths)
    except (ProjectError, OSError) as exc:
        raise DocumentError(str(exc)) from None
    subject = _subject(project, " ".join(str(p) for p in paths))
    if len(paths) == 1 and paths[0].is_dir():
        return subject
    try:  # none when some are given absolute and some relative
        folder = os.path.commonpath([os.path.dirname(s.name) for s in project.sources])
    except ValueError:
        folder = ""
    return replace(subject, folder=folder)


def _subject(project: Project, origin: str) -> Subject:
    parsed = parse_project(project.sources)  # the listings and the cross-reference read it too
    result = compile_project(project, parsed=parsed)
    if result.artifact is None:
        first = next(d for d in result.diagnostics if d.severity == "error")
        raise DocumentError(f"{origin} does not compile: {first}")
    units, _, user_pous = parsed
    own = {source.name for source in project.sources}
    own_units = tuple(unit for unit in units if unit.file in own)
    return Subject(
        name=project.name,
        version=project.version,
        author=project.author,
        date=project.date,
        project=project,
        artifact=result.artifact,
        units=own_units,
        lines={source.name: tuple(source.text.splitlines()) for source in project.sources},
        pous=pou_sources_of(own_units, project.sources),
        uses=tuple(cross_reference_of(units, user_pous)),
    )


def _from_backup(zip_path: Path) -> Subject:
    """The configuration of a backup, rebuilt from its sources: they must compile to the
    CRC of the artifact it holds, which proves the document shows what was loaded."""
    try:
        artifact_text, files = restore_backup(zip_path)
    except BackupError as exc:
        raise DocumentError(str(exc)) from None
    with tempfile.TemporaryDirectory(prefix="padt-docs-") as folder:
        root = Path(folder)
        try:
            unpack({name: text.encode("utf-8") for name, text in files.items()}, root)
            project = load_project([root])
        except ArchiveRefused as exc:  # restore_backup checked the names: a second guard
            raise DocumentError(f"{zip_path}: {exc}") from None
        except ProjectError as exc:
            raise DocumentError(f"{zip_path}: {exc}".replace(folder, "")) from None
    loaded = load_artifact(artifact_text)  # restore_backup proved it loads
    if "padt.toml" not in files:  # loose files: the artifact names the project
        project = replace(project, name=loaded.project)
    subject = _subject(project, zip_path.name)
    if subject.crc != loaded.crc:
        raise DocumentError(
            f"{zip_path}: its sources compile to CRC {subject.crc}, the backup holds {loaded.crc}"
        )
    return subject
