"""The logic: the source of every POU with its line numbers as in the file, highlighted,
long lines wrapped; an SFC chart, an FBD or an LD body also drawn as a diagram."""

from __future__ import annotations

import re

from backend.compiler.graphics.model import GraphicBody
from backend.engineering.documentation.graphic_chart import graphic_charts
from backend.engineering.documentation.interfaces import project_interfaces, project_pous
from backend.engineering.documentation.markup import Section, anchor, code, escape, heading
from backend.engineering.documentation.sfc_chart import chart_svg
from backend.engineering.documentation.st_highlight import listing
from backend.engineering.documentation.subject import Subject


def logic_section(subject: Subject) -> Section:
    title, entry = heading(1, "Logic", "logic")
    parts, headings = [title], [entry]
    sources = subject.pous
    crcs = {p.name.upper(): p.crc for p in subject.artifact.pous}
    for file, pou in project_pous(subject):
        source = sources.get(pou.name.upper())
        if source is None:
            continue
        sub, sub_entry = heading(2, f"{pou.kind} {pou.name}", anchor("logic", pou.name))
        headings.append(sub_entry)
        crc = crcs.get(pou.name.upper())
        lines = f"lines {source.first_line} to {source.last_line}"
        facts = f"{escape(subject.shown(file))}, {lines}" + (f" · CRC {code(crc)}" if crc else "")
        chart = ""
        if pou.sfc is not None and pou.sfc.steps:
            svg = chart_svg(pou.sfc, subject.lines.get(file, ()))
            caption = f'<p class="caption">SFC chart of {escape(pou.name)}</p>'
            chart = f'<div class="chart">{caption}{svg}</div>'
        if isinstance(pou.graphic, GraphicBody):
            chart = _graphic(pou.graphic, pou.name)
        for action in pou.sfc.actions if pou.sfc is not None else ():
            if isinstance(action.graphic, GraphicBody):
                chart += _graphic(action.graphic, f"action {action.name} of {pou.name}")
        parts.append(
            f'<div class="pou">{sub}<p class="facts">{facts}</p>{chart}'
            f"{listing(source.lines, source.first_line)}</div>"
        )
    for file, interface in project_interfaces(subject):
        sub, sub_entry = heading(2, f"INTERFACE {interface.name}", anchor("logic", interface.name))
        headings.append(sub_entry)
        text = subject.lines.get(file, ())
        first, last = interface.pos.line, _end_line(text, interface.pos.line, "END_INTERFACE")
        facts = f"{escape(subject.shown(file))}, lines {first} to {last}"
        parts.append(
            f'<div class="pou">{sub}<p class="facts">{facts}</p>'
            f"{listing(text[first - 1 : last], first)}</div>"
        )
    return Section('<section class="part">' + "".join(parts) + "</section>", tuple(headings))


def _graphic(body: GraphicBody, name: str) -> str:
    """The drawing of an FBD or LD body, a part to a page when it is larger than one."""
    svgs = graphic_charts(body)
    charts = []
    for number, svg in enumerate(svgs, 1):
        part = f", part {number} of {len(svgs)}" if len(svgs) > 1 else ""
        caption = f'<p class="caption">{body.language} body of {escape(name)}{part}</p>'
        charts.append(f'<div class="chart">{caption}{svg}</div>')
    return "".join(charts)


def _end_line(lines: tuple[str, ...], first: int, keyword: str) -> int:
    """The line of `keyword` (END_INTERFACE) at or after `first`; the file's end when none."""
    end = re.compile(rf"\b{keyword}\b", re.IGNORECASE)
    return next((n for n in range(first, len(lines) + 1) if end.search(lines[n - 1])), len(lines))
