"""The printable documentation of OSCAT (../shared/corpus, 22,000 lines of ST): each
chapter is complete in itself (they repeat shared POUs), so each is its own document, as
`padt docs --each CHAPTER.st... -o DIR` makes them. Target: all of them in under 30 s.

Measured twice in the same run: one process after another (`--jobs 1`, the baseline)
and with a worker per CPU (the default), each with its wall time and its CPU time (the
workers' included), so the ratio says what the cores bring on this machine as loaded now."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import time
from dataclasses import dataclass
from pathlib import Path

from backend.engineering.documentation.batch import Request, default_jobs, document_all
from backend.engineering.documentation.subject import load_subject

OSCAT = Path(__file__).resolve().parents[3] / "shared" / "corpus" / "oscat" / "st"


def oscat_chapters() -> list[Path]:
    return sorted(OSCAT.glob("*.st"))


def page_count(pdf: bytes) -> int:
    """By poppler's pdfinfo (WeasyPrint packs the page objects into compressed streams)."""
    if shutil.which("pdfinfo") is None:
        return 0
    info = subprocess.run(["pdfinfo", "-"], input=pdf, capture_output=True, check=True).stdout
    found = re.search(rb"Pages:\s+(\d+)", info)
    return int(found.group(1)) if found else 0


@dataclass(frozen=True)
class Run:
    jobs: int
    wall_s: float
    cpu_s: float  # this process and its workers
    pdfs: tuple[bytes, ...]
    refused: tuple[str, ...]


def run(chapters: list[Path], jobs: int) -> Run:
    before = os.times()
    started = time.perf_counter()
    outcomes = document_all([Request((chapter,)) for chapter in chapters], jobs)
    wall = time.perf_counter() - started
    after = os.times()
    cpu = sum(after[:4]) - sum(before[:4])  # user + system, own and the waited-for workers'
    return Run(
        jobs,
        wall,
        cpu,
        tuple(o.made.pdf for o in outcomes if o.made is not None),
        tuple(o.request.paths[0].name for o in outcomes if o.made is None),
    )


def html_seconds(chapters: list[Path]) -> float:
    """Compile and HTML alone, one process (the rest of a run is WeasyPrint)."""
    from backend.engineering.documentation.document import document_html
    from backend.engineering.documentation.subject import DocumentError

    started = time.perf_counter()
    for chapter in chapters:
        try:
            document_html(load_subject([chapter]))
        except DocumentError:
            continue
    return time.perf_counter() - started


def main() -> None:
    if not OSCAT.is_dir():
        print(f"documentation of OSCAT: skipped ({OSCAT} is absent)")
        return
    chapters = oscat_chapters()
    lines = sum(len(chapter.read_bytes().splitlines()) for chapter in chapters)
    print(f"load before: {os.getloadavg()[0]:.2f} (1 min average)")
    baseline = run(chapters, 1)
    parallel = run(chapters, default_jobs())
    assert parallel.pdfs == baseline.pdfs, "the jobs changed the bytes"
    pages = sum(page_count(pdf) for pdf in parallel.pdfs)
    html_s = html_seconds(chapters)
    print(
        f"documentation of OSCAT: {lines} lines in {len(chapters)} chapters, "
        f"{len(parallel.pdfs)} documents, {pages} pages; not compiling: "
        f"{', '.join(parallel.refused) or 'none'}; compile + HTML alone {html_s:.1f} s"
    )
    for measured in (baseline, parallel):
        print(
            f"  --jobs {measured.jobs}: wall {measured.wall_s:.1f} s, CPU {measured.cpu_s:.1f} s"
            f" ({1000 * measured.cpu_s / max(pages, 1):.0f} ms CPU a page)"
        )
    print(f"  wall ratio jobs 1 / jobs {parallel.jobs}: {baseline.wall_s / parallel.wall_s:.2f}")
    print(f"load after: {os.getloadavg()[0]:.2f} (1 min average)")


if __name__ == "__main__":
    main()
