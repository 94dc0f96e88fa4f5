"""The PDF of a document's HTML, by WeasyPrint (CSS paged media). The same HTML gives the
same bytes: WeasyPrint writes no clock time when the HTML names the dates (document.py
takes them from the project), and its file identifier is derived from the content."""

from __future__ import annotations

from pathlib import Path


def render_pdf(html: str, base: Path | None = None) -> bytes:
    # imported here: WeasyPrint loads Pango and fonts, which the other commands never need
    from weasyprint import HTML

    data = HTML(string=html, base_url=str(base) if base else None).write_pdf()
    assert isinstance(data, bytes)  # without a target WeasyPrint returns the bytes
    return data
