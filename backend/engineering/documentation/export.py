"""The documentation service: the document of a project (optionally compared with a
previous version) as HTML and PDF, in memory or written to a folder. The CLI, the REST API
and the UI each call one function of this module."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from backend.engineering.backup import safe_name
from backend.engineering.documentation.document import document_html
from backend.engineering.documentation.pdf import render_pdf
from backend.engineering.documentation.subject import DocumentError, Subject, load_subject

__all__ = ["Document", "DocumentError", "document", "document_of", "write_document"]


@dataclass(frozen=True)
class Document:
    name: str  # the file name without extension: the project's name, made safe
    project: str
    crc: str
    html: str
    pdf: bytes


def document_of(subject: Subject, previous: Subject | None = None) -> Document:
    html = document_html(subject, previous)
    return Document(safe_name(subject.name), subject.name, subject.crc, html, render_pdf(html))


def document(paths: list[Path], compare: Path | None = None) -> Document:
    """The document of a project folder, .st files or a backup zip; `compare`: a previous
    version (a folder or a backup zip) to compare with."""
    subject = load_subject(paths)
    previous = load_subject([compare]) if compare is not None else None
    return document_of(subject, previous)


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
