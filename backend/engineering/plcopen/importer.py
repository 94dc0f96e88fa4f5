"""The service behind `padt import FILE.xml -o DIR`: a PLCopen TC6 XML file into a padt
project folder.

Everything is read and every file made in memory first: a file that cannot be imported
leaves DIR untouched. FBD and LD bodies are written in their text form (docs/project-
format.md). POUs in IL, or with a drawing that cannot be read, are not imported; the rest
of the project is still written, and those POUs are named in errors and at the top of
padt.toml. docs/plcopen-import.md is the user's description.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from backend.compiler.diagnostics import Diagnostic
from backend.compiler.test_functions import is_test_file
from backend.engineering.plcopen.issues import ImportCode, ImportFailed, Where, diagnostic
from backend.engineering.plcopen.model import Dropped, NotImported, PlcProject
from backend.engineering.plcopen.project_files import project_files
from backend.engineering.plcopen.reader import read_project
from backend.engineering.plcopen.xml_tree import MAX_XML_BYTES, parse_xml
from backend.engineering.project import PROJECT_FILE

# what a P0006 error adds when it names a POU with a part in IL
IL_DEPRECATED = "IL is deprecated in IEC 61131-3 edition 3, and padt does not compile it"


class FolderRefused(Exception):
    """DIR cannot take the project (not empty without force, or a file)."""


@dataclass
class ImportResult:
    diagnostics: list[Diagnostic] = field(default_factory=list)
    written: list[str] = field(default_factory=list)  # relative paths, sorted
    not_imported: list[NotImported] = field(default_factory=list)
    dropped: list[Dropped] = field(default_factory=list)
    summary: str = ""  # what was imported, in numbers

    @property
    def complete(self) -> bool:
        return not self.not_imported and not self.dropped


def read_plcopen(xml: Path) -> PlcProject:
    """The model of the file; ImportFailed when it cannot be imported at all."""
    try:
        with xml.open("rb") as handle:
            data = handle.read(MAX_XML_BYTES + 1)
    except OSError as exc:
        raise ImportFailed(
            Where(1, 1), ImportCode.UNREADABLE, f"cannot read the file: {exc.strerror}"
        ) from None
    project = read_project(parse_xml(data))
    seen: dict[str, str] = {}
    declared = [(t.name, t.where) for t in project.types]
    declared += [(p.name, p.where) for p in project.pous]
    declared += [(i.name, i.where) for i in project.interfaces]
    declared += [(m.name, m.where) for m in project.not_imported]
    for name, where in declared:
        if name.upper() in seen:
            raise ImportFailed(
                where, ImportCode.DUPLICATE, f"{name} is declared twice (also {seen[name.upper()]})"
            )
        seen[name.upper()] = f"line {where.line}"
    return project


def import_plcopen(xml: Path, folder: Path, force: bool = False) -> ImportResult:
    """Import `xml` into `folder`. ImportFailed (nothing written) for a file that cannot be
    imported, FolderRefused for a folder that cannot take it."""
    display = str(xml)
    project = read_plcopen(xml)
    files = project_files(project, xml.name)
    interfaces = f"{_count(len(project.interfaces), 'interface')}, " if project.interfaces else ""
    summary = (
        f"{_count(len(project.pous), 'POU')}, {interfaces}"
        f"{_count(len(project.types), 'data type')}, "
        f"{_count(files.global_variables, 'global variable')}, {_count(files.programs, 'program')}"
    )
    result = ImportResult(
        [], sorted(files.contents), project.not_imported, project.dropped, summary
    )
    result.diagnostics += [
        diagnostic(
            display,
            missing.problem,
            ImportCode.DRAWING,
            f"{missing.name} not imported: {missing.reason}",
        )
        for missing in project.not_imported
        if missing.problem is not None
    ]
    refused = [m for m in project.not_imported if m.problem is None]
    if refused:
        listed = ", ".join(f"{m.name} ({m.reason})" for m in refused)
        result.diagnostics.append(
            diagnostic(
                display,
                refused[0].where,
                ImportCode.NOT_IMPORTED,
                f"{_count(len(refused), 'POU')} not imported: {listed}{_why(refused)}",
            )
        )
    result.diagnostics += [
        diagnostic(
            display,
            dropped.where,
            ImportCode.PARTS_NOT_IMPORTED,
            f"{dropped.owner} is imported without its CODESYS {dropped.what} (a structure "
            "extends no other in padt)",
        )
        for dropped in project.dropped
    ]
    result.diagnostics += [diagnostic(display, w, c, m) for w, c, m in files.warnings]
    result.diagnostics += [
        diagnostic(display, where, ImportCode.CONFIGURATION_PART, what)
        for where, what in project.left_out
    ]
    result.diagnostics.sort(key=lambda d: (d.line, d.col))
    _prepare(folder, force)
    for name, text in files.contents.items():
        (folder / name).write_text(text, encoding="utf-8", newline="\n")
    return result


def _why(refused: list[NotImported]) -> str:
    in_il = any(m.reason == "IL" or m.reason.endswith(" in IL") for m in refused)
    return f"; {IL_DEPRECATED}" if in_il else ""


def _count(count: int, thing: str) -> str:
    return f"{count} {thing}" if count == 1 else f"{count} {thing}s"


def _prepare(folder: Path, force: bool) -> None:
    """An empty or new folder; with force, a project folder (one with a padt.toml) whose
    padt.toml and .st files go, anything else in it staying, its tests too (below test/:
    the user's, which no XML brings). A folder without padt.toml is never emptied:
    `-o ~ --force` must not delete a home folder's .st files."""
    if folder.exists() and not folder.is_dir():
        raise FolderRefused(f"{folder} is a file, not a folder")
    if folder.is_dir() and any(folder.iterdir()):
        if not force:
            raise FolderRefused(
                f"{folder} is not empty: choose a new folder, or --force to replace the "
                "project in it (its padt.toml and .st files)"
            )
        if not (folder / PROJECT_FILE).is_file():
            raise FolderRefused(
                f"{folder} is not empty and holds no {PROJECT_FILE}: --force replaces only a "
                "project folder"
            )
        sources = (p for p in folder.rglob("*.st") if not _is_test(folder, p))
        for old in [*sorted(sources), folder / PROJECT_FILE]:
            if old.is_file() or old.is_symlink():
                old.unlink()
    folder.mkdir(parents=True, exist_ok=True)


def _is_test(folder: Path, path: Path) -> bool:
    return is_test_file(path.relative_to(folder).as_posix())
