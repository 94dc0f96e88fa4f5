"""Workspace benchmark: opening OSCAT's project (22 files, 800 POUs) in the browser's tree,
step by step as the workspace does it: the tree read by the service (cold: nothing parsed
in this process; again: every file known), drawn as HTML, and that HTML laid out by
headless Chromium (the time until the page has placed it, and its size on the wire).

Run with `python -m tests.bench.bench_workspace`. It prints figures and asserts nothing
about time (machines are shared and noisy).
"""

from __future__ import annotations

import shutil
import statistics
import tempfile
import time
from pathlib import Path

from backend.engineering.project_access import Editor
from backend.engineering.project_shelf import ProjectShelf
from backend.engineering.project_tree import project_tree
from frontend.project_tree_view import Entry, render
from tests.support.browser import chromium

REPO = Path(__file__).resolve().parents[2]
OSCAT = REPO.parent / "shared" / "corpus" / "oscat" / "st"
EDITOR = Editor("bench", "read-only")
RUNS = 10


def _ms(samples: list[float]) -> str:
    ordered = sorted(samples)
    p95 = ordered[max(0, round(len(ordered) * 0.95) - 1)]
    return f"p50 {statistics.median(ordered) * 1e3:.1f} ms, p95 {p95 * 1e3:.1f} ms"


def main() -> None:
    if not OSCAT.is_dir():
        print(f"OSCAT in the browser's tree: skipped ({OSCAT} is absent)")
        return
    with tempfile.TemporaryDirectory() as base:
        shutil.copytree(OSCAT, Path(base) / "oscat")
        shelf = ProjectShelf({"oscat": Path(base) / "oscat"})
        start = time.perf_counter()
        tree = project_tree(shelf, "oscat", EDITOR)
        cold = time.perf_counter() - start
        reads, draws = [], []
        for _ in range(RUNS):
            start = time.perf_counter()
            tree = project_tree(shelf, "oscat", EDITOR)
            reads.append(time.perf_counter() - start)
            chosen = Entry("file", tree.pous[0].name, tree.pous[0].file, tree.pous[0].line)
            start = time.perf_counter()
            page_html = render(tree, chosen)
            draws.append(time.perf_counter() - start)
        layouts = []
        with chromium() as browser:
            page = browser.new_page(viewport={"width": 1400, "height": 900})
            page.set_content('<div id="tree" style="width:280px"></div>')
            for _ in range(RUNS):
                layouts.append(
                    page.evaluate(
                        """html => {
                        const t0 = performance.now();
                        const box = document.getElementById('tree');
                        box.innerHTML = html;
                        box.getBoundingClientRect();  // forces the layout
                        return (performance.now() - t0) / 1000;
                    }""",
                        page_html,
                    )
                )
    print(
        f"OSCAT in the browser's tree ({len(tree.files)} files, {len(tree.pous)} POUs, "
        f"{len(tree.types)} types): read cold {cold * 1e3:.0f} ms, again {_ms(reads)}; "
        f"drawn as HTML {_ms(draws)} ({len(page_html) / 1024:.0f} KiB); "
        f"laid out in Chromium {_ms(layouts)}"
    )


if __name__ == "__main__":
    main()
