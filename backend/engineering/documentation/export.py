"""The documentation service: the document of a project (optionally compared with a
previous version) as HTML and PDF, in memory or written to a folder. The CLI, the REST API
and the UI each call one function of this module."""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

from backend.engineering.backup import safe_name
from backend.engineering.documentation.document import document_html
from backend.engineering.documentation.pdf import render_pdf
from backend.engineering.documentation.subject import DocumentError, load_subject
from backend.engineering.sources import find_sources

__all__ = [
    "Document",
    "DocumentError",
    "backups_of",
    "document",
    "running_version",
    "version_path",
    "write_document",
]
_BACKUP_NAME = re.compile(r"^[A-Za-z0-9_][A-Za-z0-9_.-]{0,200}\.zip$")


@dataclass(frozen=True)
class Document:
    name: str  # the file name without extension: the project's name, made safe
    project: str
    crc: str
    html: str
    pdf: bytes


def document(paths: list[Path], compare: Path | None = None) -> Document:
    """The document of a project folder, .st files or a backup zip; `compare`: a previous
    version (a folder or a backup zip) to compare with."""
    subject = load_subject(paths)
    previous = load_subject([compare]) if compare is not None else None
    html = document_html(subject, previous)
    return Document(safe_name(subject.name), subject.name, subject.crc, html, render_pdf(html))


def write_document(made: Document, folder: Path) -> tuple[Path, Path]:
    """`folder/<project>.html` and `folder/<project>.pdf`."""
    try:
        folder.mkdir(parents=True, exist_ok=True)
        html_path = folder / f"{made.name}.html"
        pdf_path = folder / f"{made.name}.pdf"
        html_path.write_text(made.html, encoding="utf-8")
        pdf_path.write_bytes(made.pdf)
    except OSError as exc:
        raise DocumentError(f"cannot write the document in {folder}: {exc}") from None
    return html_path, pdf_path


def version_path(name: str, projects: Mapping[str, Path], backup_dir: Path) -> Path:
    """A version named by a caller (the REST API, the UI): a project the PADT serves, or a
    backup zip in the backup folder by its bare file name; never any other path."""
    if name in projects:
        return projects[name]
    if not _BACKUP_NAME.match(name):
        raise DocumentError(f"'{name}' is neither a project nor a backup file name")
    path = backup_dir / name
    if not path.is_file():
        raise DocumentError(f"there is no backup '{name}'")
    return path


def backups_of(backup_dir: Path, project: str | None = None) -> list[str]:
    """The backup file names in the folder, newest first (the name ends in the UTC time of
    the load), those of `project` only when it is given."""
    try:
        names = [p.name for p in backup_dir.iterdir() if _BACKUP_NAME.match(p.name)]
    except OSError:
        return []
    if project is not None:
        names = [n for n in names if n.startswith(safe_name(project) + "_")]
    return sorted(names, key=lambda n: (n.rsplit("_", 1)[-1], n), reverse=True)


def running_version(crc: str, projects: Mapping[str, Path], backup_dir: Path) -> Path | None:
    """Where the configuration `crc` a resource runs can be documented from: its newest
    backup (written when it was loaded), else a project the PADT knows that compiles to
    it (as the Code screen finds it); None when neither exists."""
    crc = crc.upper()
    for name in backups_of(backup_dir):
        if f"_{crc}_" in name:
            return backup_dir / name
    found = find_sources(crc, projects)
    return projects[found.project] if found is not None else None
