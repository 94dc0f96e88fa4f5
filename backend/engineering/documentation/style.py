"""The style sheet of the document: A4 pages (CSS paged media) with the project name and
the configuration CRC at the top of every page and "page N of M" at the bottom."""

from __future__ import annotations

import re

_PLAIN = re.compile(r"[A-Za-z0-9 _.,:;()#%+=@!?-]")


def css_string(text: str) -> str:
    """A CSS string literal of any text: a project name may hold quotes, backslashes or
    `</style>`, so all but plain characters are written as CSS escapes."""
    escaped = "".join(ch if _PLAIN.match(ch) else f"\\{ord(ch):x} " for ch in text)
    return f'"{escaped}"'


def style(project: str, crc: str) -> str:
    # the CRC first: a name may hold the word CRC, and what one replace puts in, the next
    # must not touch (the CRC text holds no PROJECT)
    page = _PAGE.replace("CRC", css_string(f"CRC {crc}")).replace("PROJECT", css_string(project))
    return page + _BODY


_PAGE = """
@page {
  size: A4;
  margin: 20mm 14mm 18mm 16mm;
  @top-left { content: PROJECT; font: bold 8.5pt "DejaVu Sans"; color: #333; }
  @top-right { content: "Configuration " CRC; font: 8.5pt "DejaVu Sans Mono"; color: #333; }
  @bottom-left { content: PROJECT " · " CRC; font: 7.5pt "DejaVu Sans"; color: #666; }
  @bottom-right {
    content: "page " counter(page) " of " counter(pages); font: 8.5pt "DejaVu Sans";
  }
}
"""

_BODY = """
html { font-family: "DejaVu Sans", sans-serif; font-size: 9pt; color: #111; }
h1 { font-size: 15pt; margin: 0 0 8pt; border-bottom: 1.5pt solid #333; padding-bottom: 2pt; }
h2 { font-size: 11.5pt; margin: 12pt 0 4pt; }
h3 { font-size: 10pt; margin: 10pt 0 4pt; }
section.part, section.contents { break-before: page; }
h1, h2, h3 { break-after: avoid; }
code { font-family: "DejaVu Sans Mono", monospace; font-size: 8pt; }
table { border-collapse: collapse; width: 100%; margin: 2pt 0 6pt; }
th, td { border: 0.5pt solid #999; padding: 1.5pt 3pt; text-align: left; vertical-align: top;
  overflow-wrap: break-word; }
table.system { table-layout: fixed; }
table.system th:nth-child(1) { width: 27%; }
table.system th:nth-child(2) { width: 9%; }
table.system th:nth-child(3) { width: 14%; }
table.system th:nth-child(5) { width: 16%; }
th { background: #e8ecf0; font-weight: bold; }
thead { display: table-header-group; }
tr { break-inside: avoid; }
p.facts { color: #444; margin: 0 0 4pt; break-after: avoid; }
p.none, p.note { color: #555; font-style: italic; }
p.warning { color: #a00; font-weight: bold; }
.cover { text-align: left; }
.cover .kind { margin-top: 50mm; font-size: 12pt; color: #555; }
.cover h1.title { font-size: 26pt; border: none; margin: 4pt 0 16pt; }
.cover table.facts { width: auto; }
.cover table.facts th { width: 45mm; }
.contents ul { list-style: none; padding: 0; margin: 0; width: 125mm; }
.contents li { margin: 1pt 0; }
.contents li.toc2 { margin-left: 8mm; font-size: 8.5pt; }
.contents a { color: #111; text-decoration: none; }
.contents a::after { content: leader("....") target-counter(attr(href), page); }
pre.listing, pre.grid { font-family: "DejaVu Sans Mono", monospace; font-size: 7pt;
  line-height: 1.2; margin: 4pt 0 8pt; white-space: pre; }
pre.grid b.head { display: block; font-weight: bold; border-bottom: 0.6pt solid #333;
  margin-bottom: 1pt; break-after: avoid; }
.added { background: #e3f6e3; }
.removed { background: #fbe3e3; }
.k { color: #0b3c9c; font-weight: bold; }
.c { color: #2f7d32; font-style: italic; }
.s { color: #a3401a; }
.chart { break-inside: avoid; margin: 4pt 0 8pt; }
.caption { font-weight: bold; margin: 0 0 2pt; }
svg.sfc { width: 100%; height: auto; }
"""
