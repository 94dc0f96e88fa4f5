"""The document as one HTML text: cover, contents, the sections in order, and with a
previous version the comparison. The PDF is rendered from exactly this text."""

from __future__ import annotations

import re

from backend.engineering.documentation.comparison import comparison_section
from backend.engineering.documentation.contents import contents
from backend.engineering.documentation.cover import cover
from backend.engineering.documentation.data_types import data_type_section
from backend.engineering.documentation.interfaces import interface_section
from backend.engineering.documentation.logic import logic_section
from backend.engineering.documentation.markup import Section, escape
from backend.engineering.documentation.resource import resource_section
from backend.engineering.documentation.signals import signal_section
from backend.engineering.documentation.style import style
from backend.engineering.documentation.subject import Subject
from backend.engineering.documentation.xref import xref_section

_ISO_DATE = re.compile(r"^\d{4}-\d{2}-\d{2}(T\d{2}:\d{2}(:\d{2})?(Z|[+-]\d{2}:\d{2})?)?$")


def document_html(subject: Subject, previous: Subject | None = None) -> str:
    sections: list[Section] = [
        resource_section(subject),
        data_type_section(subject),
        signal_section(subject),
        interface_section(subject),
        logic_section(subject),
        xref_section(subject),
    ]
    if previous is not None:
        sections.append(comparison_section(subject, previous))
    headings = [h for section in sections for h in section.headings]
    title = f"{subject.name} {subject.version}".strip()
    meta = [f'<meta name="author" content="{escape(subject.author)}">'] if subject.author else []
    if _ISO_DATE.match(subject.date):  # the PDF's dates come from the project, never the clock
        meta.append(f'<meta name="dcterms.created" content="{escape(subject.date)}">')
        meta.append(f'<meta name="dcterms.modified" content="{escape(subject.date)}">')
    meta.append('<meta name="generator" content="padt docs">')
    return (
        "<!DOCTYPE html>\n"
        '<html lang="en"><head><meta charset="utf-8">'
        f"<title>{escape(title)}</title>{''.join(meta)}"
        f"<style>{style(subject.name, subject.crc)}</style></head><body>\n"
        + cover(subject, previous)
        + "\n"
        + contents(headings)
        + "\n"
        + "\n".join(section.html for section in sections)
        + "\n</body></html>\n"
    )
