"""The small pieces of HTML every section is made of. Every text from a project goes
through `escape`: a project file is never trusted to be harmless markup."""

from __future__ import annotations

import html
import re
import textwrap
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


GRID_COLUMNS = 118  # characters on a line of a grid (7 pt DejaVu Sans Mono on A4)


def grid(columns: Sequence[tuple[str, int]], rows: Iterable[Sequence[str]]) -> str:
    """A long table as preformatted text: (title, width in characters) per column, the
    last taking the rest of the line; cells of plain text wrap inside their column. Laid
    out many times faster than an HTML table of the same rows, which matters for the
    cross-reference of a library of 20,000 lines."""
    widths = [width for _, width in columns[:-1]]
    widths.append(GRID_COLUMNS - sum(widths) - 2 * (len(columns) - 1))
    lines = []
    for row in rows:
        cells = [
            textwrap.wrap(text, width, break_on_hyphens=False) or [""]
            for text, width in zip(row, widths, strict=True)
        ]
        for index in range(max(len(cell) for cell in cells)):
            parts = [cell[index] if index < len(cell) else "" for cell in cells]
            line = "  ".join(part.ljust(width) for part, width in zip(parts, widths, strict=True))
            lines.append(escape(line.rstrip()))
    if not lines:
        return '<p class="none">none</p>'
    head = "  ".join(title.ljust(width) for (title, _), width in zip(columns, widths, strict=True))
    head_line = f'<b class="head">{escape(head.rstrip())}</b>'  # a block: underlined
    return f'<pre class="grid">{head_line}' + "\n".join(lines) + "</pre>"
