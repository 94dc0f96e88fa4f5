"""The table of contents, with the page of each heading (CSS `target-counter`, filled in
when the PDF is laid out; the HTML shows the links)."""

from __future__ import annotations

from collections.abc import Iterable

from backend.engineering.documentation.markup import Heading, escape


def contents(headings: Iterable[Heading]) -> str:
    items = "".join(
        f'<li class="toc{h.level}"><a href="#{h.anchor}">{escape(h.title)}</a></li>'
        for h in headings
    )
    return f'<section class="contents"><h1 class="toc">Contents</h1><ul>{items}</ul></section>'
