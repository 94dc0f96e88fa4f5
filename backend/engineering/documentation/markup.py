"""The small pieces of HTML every section is made of. Every text from a project goes
through `escape`: a project file is never trusted to be harmless markup."""

from __future__ import annotations

import html
import re
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

_ANCHOR_UNSAFE = re.compile(r"[^A-Za-z0-9_-]+")


def escape(text: object) -> str:
    return html.escape(str(text), quote=True)


def anchor(*parts: str) -> str:
    """An id for an element: the same parts give the same id (links in the contents and
    the cross-reference point at it)."""
    return "-".join(_ANCHOR_UNSAFE.sub("_", part).strip("_").lower() or "_" for part in parts)


@dataclass(frozen=True)
class Heading:
    """An entry of the table of contents: its level (1 or 2), title and anchor."""

    level: int
    title: str
    anchor: str


@dataclass(frozen=True)
class Section:
    """A part of the document: its HTML and the headings it contributes to the contents."""

    html: str
    headings: tuple[Heading, ...]


def heading(level: int, title: str, anchor_id: str) -> tuple[str, Heading]:
    tag = f"h{level}"
    return f'<{tag} id="{anchor_id}">{escape(title)}</{tag}>', Heading(level, title, anchor_id)


def table(columns: Sequence[str], rows: Iterable[Sequence[str]], css_class: str = "") -> str:
    """A table whose cells are already HTML (escape text before)."""
    head = "".join(f"<th>{escape(c)}</th>" for c in columns)
    body = "".join("<tr>" + "".join(f"<td>{cell}</td>" for cell in row) + "</tr>" for row in rows)
    if not body:
        return '<p class="none">none</p>'
    klass = f' class="{css_class}"' if css_class else ""
    return f"<table{klass}><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>"


def code(text: object) -> str:
    return f"<code>{escape(text)}</code>"
