"""The printable documentation of OSCAT (../shared/corpus, 22,000 lines of ST): each
chapter is complete in itself (they repeat shared POUs), so each is its own document, as
`padt docs --each CHAPTER.st... -o DIR` makes them. Target: all of them in under 30 s.

Measured twice in the same run, each with its wall time and its CPU time (the workers'
included): the baseline, one chapter after another in this process with the cycle
collector on (as `padt docs` made them before `--jobs`, but with today's compile), and
`padt docs --each` as it makes them now (a worker per CPU, the collector off while a
document is made). The ratio says what that brings on this machine as loaded now (a
shared machine: the load is printed before and after)."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import time
from dataclasses import dataclass
from pathlib import Path

from backend.engineering.documentation.batch import (
    Outcome,
    Request,
    default_jobs,
    document_all,
)
from backend.engineering.documentation.document import document_html
from backend.engineering.documentation.export import DocumentError, document
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


def baseline(requests: list[Request]) -> list[Outcome]:
    """As `padt docs` made them before `--jobs`."""
    outcomes = []
    for request in requests:
        try:
            outcomes.append(Outcome(request, document(list(request.paths))))
        except DocumentError as exc:
            outcomes.append(Outcome(request, None, str(exc)))
    return outcomes


def run(chapters: list[Path], jobs: int) -> Run:
    """jobs 0: the baseline."""
    before = os.times()
    started = time.perf_counter()
    requests = [Request((chapter,)) for chapter in chapters]
    outcomes = document_all(requests, jobs) if jobs else baseline(requests)
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
    before = run(chapters, 0)
    parallel = run(chapters, default_jobs())
    assert parallel.pdfs == before.pdfs, "the jobs changed the bytes"
    pages = sum(page_count(pdf) for pdf in parallel.pdfs)
    html_s = html_seconds(chapters)
    print(
        f"documentation of OSCAT: {lines} lines in {len(chapters)} chapters, "
        f"{len(parallel.pdfs)} documents, {pages} pages; not compiling: "
        f"{', '.join(parallel.refused) or 'none'}; compile + HTML alone {html_s:.1f} s"
    )
    for measured in (before, parallel):
        label = f"--jobs {measured.jobs}" if measured.jobs else "baseline"
        print(
            f"  {label}: wall {measured.wall_s:.1f} s, CPU {measured.cpu_s:.1f} s"
            f" ({1000 * measured.cpu_s / max(pages, 1):.0f} ms CPU a page)"
        )
    print(f"  wall ratio baseline / --jobs {parallel.jobs}: {before.wall_s / parallel.wall_s:.2f}")
    print(f"load after: {os.getloadavg()[0]:.2f} (1 min average)")


if __name__ == "__main__":
    main()
