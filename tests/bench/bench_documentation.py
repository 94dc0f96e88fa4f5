"""The printable documentation of OSCAT (../shared/corpus, 22,000 lines of ST): each
chapter is complete in itself (they repeat shared POUs), so each is its own document, as
`padt docs CHAPTER.st -o DIR` makes it. Target: all of them in under 30 s."""

from __future__ import annotations

import re
import shutil
import subprocess
import time
from pathlib import Path

from backend.engineering.documentation.document import document_html
from backend.engineering.documentation.pdf import render_pdf
from backend.engineering.documentation.subject import DocumentError, load_subject

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


def main() -> None:
    if not OSCAT.is_dir():
        print(f"documentation of OSCAT: skipped ({OSCAT} is absent)")
        return
    lines = pages = 0
    html_s = pdf_s = 0.0
    refused = []
    cpu_started = time.process_time()
    for chapter in oscat_chapters():
        started = time.perf_counter()
        try:
            subject = load_subject([chapter])
        except DocumentError:
            refused.append(chapter.name)  # the chapter that does not compile
            continue
        html = document_html(subject)
        made = time.perf_counter()
        pdf = render_pdf(html)
        html_s += made - started
        pdf_s += time.perf_counter() - made
        lines += sum(len(text) for text in subject.lines.values())
        pages += page_count(pdf)
    cpu = time.process_time() - cpu_started  # a shared machine's wall clock says little
    print(
        f"documentation of OSCAT: {lines} lines, {pages} pages, {html_s + pdf_s:.1f} s "
        f"(compile + HTML {html_s:.1f} s, PDF {pdf_s:.1f} s; CPU {cpu:.1f} s); "
        f"not compiling: {', '.join(refused) or 'none'}"
    )


if __name__ == "__main__":
    main()
