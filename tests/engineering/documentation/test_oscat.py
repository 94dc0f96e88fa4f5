"""OSCAT (../shared/corpus, 22 chapters, 21,800 lines) documented: each chapter that
compiles is its own document, and every page of each carries its name, its CRC and
"page N of M". Made as `padt docs --each` makes them, a worker per CPU. Slow (about half
a minute of CPU); the time is measured by tests/bench/bench_documentation.py."""

from __future__ import annotations

import pytest

from backend.engineering.documentation.batch import Request, default_jobs, document_all
from tests.compiler.test_corpus_iec import KNOWN, name_of, st_files
from tests.engineering.documentation.test_document import pages
from tests.support.corpus_paths import corpus_dir

pytestmark = pytest.mark.slow


def test_every_oscat_chapter_documented(tmp_path) -> None:
    chapters = st_files(corpus_dir("oscat/st"))
    documented = 0
    for outcome in document_all([Request((chapter,)) for chapter in chapters], default_jobs()):
        chapter, made = outcome.request.paths[0], outcome.made
        if made is None:
            assert name_of(chapter) in KNOWN, outcome.error  # only the known faulty chapter
            continue
        pdf = tmp_path / f"{made.name}.pdf"
        pdf.write_bytes(made.pdf)
        texts = pages(pdf)
        for number, text in enumerate(texts, 1):
            assert made.project in text and f"CRC {made.crc}" in text, (chapter, number)
            assert f"page {number} of {len(texts)}" in text, (chapter, number)
        documented += 1
    assert documented == len(chapters) - 1
