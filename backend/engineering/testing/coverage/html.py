"""Coverage as static HTML pages: an index of the files and POUs with their figures, and a
page per file with its source shaded: green a statement that ran, red one that did not,
yellow one whose branches were not all taken (those are named beside it)."""

from __future__ import annotations

import re
from html import escape
from pathlib import Path

from backend.engineering.testing.coverage.model import Branch, Coverage, Figures, FileCoverage
from backend.engineering.testing.coverage.summary import percent

STYLE = """
body { font-family: system-ui, sans-serif; margin: 24px; color: #1d1d1f; max-width: 1340px; }
h1 { font-size: 22px; margin: 0 0 4px; }
p.figures { margin: 0 0 16px; color: #444; }
table.index { border-collapse: collapse; min-width: 760px; }
table.index th, table.index td { padding: 6px 14px; border-bottom: 1px solid #ddd; }
table.index th { text-align: left; background: #f2f2f4; }
table.index th.number { text-align: right; }
table.index td.number { text-align: right; font-variant-numeric: tabular-nums; }
table.index tr.file td { font-weight: 600; background: #fafafa; }
table.index tr.total td { font-weight: 700; border-top: 2px solid #999; }
table.index td.pou { padding-left: 32px; }
.legend span { display: inline-block; padding: 2px 10px; margin-right: 8px; border-radius: 3px; }
table.source { border-collapse: collapse; width: 100%; table-layout: fixed; }
table.source td { padding: 0 8px; vertical-align: top; font-size: 13px; line-height: 1.5; }
table.source th { padding: 4px 8px; font-size: 12px; color: #555; text-align: left;
  border-bottom: 1px solid #ccc; }
table.source th.number { text-align: right; }
table.source td.number, table.source td.hits {
  text-align: right; color: #777; font-family: ui-monospace, monospace;
  font-variant-numeric: tabular-nums;
}
table.source col.number { width: 56px; }
table.source col.hits { width: 64px; }
table.source col.ways { width: 380px; }
table.source td.code { font-family: ui-monospace, monospace; white-space: pre-wrap;
  overflow-wrap: anywhere; }
table.source td.ways { font-size: 12px; color: #5a4500; }
.run { background: #d9f2dc; }
.missed { background: #f8d4d4; }
.partial { background: #fbefc0; }
a { color: #0b57d0; }
"""


def write_html(coverage: Coverage, folder: Path, project: str) -> list[Path]:
    """The index and a page per file in `folder` (made if need be); the pages written."""
    folder.mkdir(parents=True, exist_ok=True)
    names = page_names(coverage)
    written = [folder / "index.html"]
    written[0].write_text(index_page(coverage, names, project), encoding="utf-8")
    for file in coverage.files:
        path = folder / names[file.file]
        path.write_text(file_page(file, project), encoding="utf-8")
        written.append(path)
    return written


def page_names(coverage: Coverage) -> dict[str, str]:
    """Each file's page, named by its path (`test/a.st` -> `test_a.st.html`), kept apart
    when two paths come out alike."""
    names: dict[str, str] = {}
    taken: set[str] = set()
    for file in coverage.files:
        base = re.sub(r"[^A-Za-z0-9._-]", "_", file.file)
        name, number = f"{base}.html", 1
        while name in taken or name == "index.html":
            number += 1
            name = f"{base}-{number}.html"
        taken.add(name)
        names[file.file] = name
    return names


def _page(title: str, body: str) -> str:
    return (
        '<!DOCTYPE html>\n<html lang="en">\n<head>\n<meta charset="utf-8">\n'
        f"<title>{escape(title)}</title>\n<style>{STYLE}</style>\n</head>\n"
        f"<body>\n{body}\n</body>\n</html>\n"
    )


def _figures_text(figures: Figures) -> str:
    return (
        f"statements {figures.statements_covered}/{figures.statements}, "
        f"branches {figures.branches_covered}/{figures.branches}, {percent(figures)} covered"
    )


def _cells(figures: Figures) -> str:
    return (
        f'<td class="number">{figures.statements_covered}/{figures.statements}</td>'
        f'<td class="number">{figures.branches_covered}/{figures.branches}</td>'
        f'<td class="number">{percent(figures)}</td>'
    )


def index_page(coverage: Coverage, names: dict[str, str], project: str) -> str:
    rows = []
    for file in coverage.files:
        page = escape(names[file.file], quote=True)
        rows.append(
            f'<tr class="file"><td><a href="{page}">{escape(file.file)}</a></td><td></td>'
            f"{_cells(file.figures)}</tr>"
        )
        for pou in file.pous:
            anchor = f"#L{pou.lines[0][0]}" if pou.lines else ""
            rows.append(
                f'<tr><td class="pou"><a href="{page}{anchor}">{escape(pou.name)}</a></td>'
                f"<td>{escape(pou.kind)}</td>{_cells(pou.figures)}</tr>"
            )
    rows.append(f'<tr class="total"><td>Total</td><td></td>{_cells(coverage.figures)}</tr>')
    body = (
        f"<h1>Coverage of {escape(project)}</h1>\n"
        f'<p class="figures">{_figures_text(coverage.figures)}, measured on the Python tier</p>\n'
        '<table class="index">\n<tr><th>File / POU</th><th>Kind</th>'
        '<th class="number">Statements</th><th class="number">Branches</th>'
        '<th class="number">Cover</th></tr>\n' + "\n".join(rows) + "\n</table>"
    )
    return _page(f"Coverage of {project}", body)


def _shade(hits: int | None, ways: list[Branch]) -> str:
    if hits is None:
        return ""
    if hits == 0:
        return "missed"
    return "partial" if any(way.taken == 0 for way in ways) else "run"


def _ways_text(ways: list[Branch]) -> str:
    if not ways:
        return ""
    taken = sum(way.taken > 0 for way in ways)
    missed = [way.label for way in ways if way.taken == 0]
    text = f"{taken}/{len(ways)} branches taken"
    return f"{text}; never: {', '.join(missed)}" if missed else text


def file_page(file: FileCoverage, project: str) -> str:
    lines = file.lines
    branches = file.branches_by_line()
    rows = []
    for number, text in enumerate(file.text.splitlines(), start=1):
        hits = lines.get(number)
        ways = branches.get(number, [])
        shade = _shade(hits, ways)
        row_class = f' class="{shade}"' if shade else ""
        rows.append(
            f'<tr id="L{number}"{row_class}><td class="number">{number}</td>'
            f'<td class="hits">{"" if hits is None else hits}</td>'
            f'<td class="code">{escape(text)}</td>'
            f'<td class="ways">{escape(_ways_text(ways))}</td></tr>'
        )
    body = (
        f'<p><a href="index.html">Coverage of {escape(project)}</a></p>\n'
        f"<h1>{escape(file.file)}</h1>\n"
        f'<p class="figures">{_figures_text(file.figures)}</p>\n'
        '<p class="legend"><span class="run">ran</span><span class="missed">never ran</span>'
        '<span class="partial">a branch never taken</span></p>\n'
        '<table class="source">\n<colgroup><col class="number"><col class="hits"><col>'
        '<col class="ways"></colgroup>\n<tr><th class="number">Line</th>'
        '<th class="number">Runs</th><th>Source</th><th>Branches</th></tr>\n'
        + "\n".join(rows)
        + "\n</table>"
    )
    return _page(f"{file.file}: coverage", body)
