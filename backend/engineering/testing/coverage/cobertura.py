"""Coverage as Cobertura XML, in the form coverage.py writes it (the form CI systems and
pycobertura read): `coverage` > `packages` > a `package` per folder > `classes` > a
`class` per POU, its `filename` the ST file's path in the project > `lines` > `line`."""

from __future__ import annotations

import posixpath
import xml.etree.ElementTree as ET
from collections.abc import Callable
from pathlib import Path

from backend.engineering.testing.coverage.model import Branch, Coverage, Figures, PouCoverage

# milliseconds since the epoch, as coverage.py's `timestamp`; tests pass a fixed one
Clock = Callable[[], int]


def cobertura_xml(coverage: Coverage, source: Path, version: str, now: Clock) -> bytes:
    """`source`: the project folder, the file paths are relative to it."""
    figures = coverage.figures
    root = ET.Element("coverage", _rates(figures))
    root.set("lines-covered", str(figures.statements_covered))
    root.set("lines-valid", str(figures.statements))
    root.set("branches-covered", str(figures.branches_covered))
    root.set("branches-valid", str(figures.branches))
    root.set("complexity", "0")
    root.set("version", version)
    root.set("timestamp", str(now()))
    ET.SubElement(ET.SubElement(root, "sources"), "source").text = str(source)
    packages = ET.SubElement(root, "packages")
    by_folder: dict[str, list[PouCoverage]] = {}
    for file in coverage.files:
        by_folder.setdefault(posixpath.dirname(file.file), []).extend(file.pous)
    for folder, pous in sorted(by_folder.items()):
        total = sum((pou.figures for pou in pous), Figures(0, 0, 0, 0))
        package = ET.SubElement(packages, "package", name=folder.replace("/", ".") or ".")
        package.attrib.update({**_rates(total), "complexity": "0"})
        classes = ET.SubElement(package, "classes")
        for pou in pous:
            classes.append(_class(pou))
    ET.indent(root)
    text: bytes = ET.tostring(root, encoding="utf-8", xml_declaration=True)
    return text + b"\n"


def _rates(figures: Figures) -> dict[str, str]:
    return {
        "line-rate": _rate(figures.line_rate),
        "branch-rate": _rate(figures.branch_rate),
    }


def _rate(value: float) -> str:
    return f"{value:.4g}"


def _class(pou: PouCoverage) -> ET.Element:
    element = ET.Element("class", name=pou.name, filename=pou.file)
    element.attrib.update({**_rates(pou.figures), "complexity": "0"})
    ET.SubElement(element, "methods")
    lines = ET.SubElement(element, "lines")
    by_line: dict[int, list[Branch]] = {}
    for branch in pou.branches:
        by_line.setdefault(branch.line, []).append(branch)
    for number, hits in pou.lines:
        line = ET.SubElement(lines, "line", number=str(number), hits=str(hits))
        ways = by_line.get(number)
        if ways:
            taken = sum(way.taken > 0 for way in ways)
            line.set("branch", "true")
            line.set("condition-coverage", f"{100 * taken // len(ways)}% ({taken}/{len(ways)})")
    return element
