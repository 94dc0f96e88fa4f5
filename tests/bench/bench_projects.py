"""Project-editing benchmarks: opening OSCAT's project (22 files, 800 POUs) in the tree,
cold (this process has parsed nothing) and again, and after one file changed; a save
(the file and its audit entry each synced to the disk); the editor's poll for a file
changed on disk; a check of padt.toml's settings as a form types (a compile of the demo).

Run with `python -m tests.bench.bench_projects`. It prints figures and asserts nothing
about time (machines are shared and noisy).
"""

from __future__ import annotations

import shutil
import statistics
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

from backend.engineering.padt_audit_log import PadtAuditLog
from backend.engineering.project_access import Editor
from backend.engineering.project_files import changed_on_disk, read_file, save_file
from backend.engineering.project_settings import read_settings, settings_problems
from backend.engineering.project_shelf import ProjectShelf
from backend.engineering.project_tree import project_tree

REPO = Path(__file__).resolve().parents[2]
OSCAT = REPO.parent / "shared" / "corpus" / "oscat" / "st"
EDITOR = Editor("bench", "read-write")
RUNS = 40


def _ms(samples: list[float]) -> str:
    ordered = sorted(samples)
    p95 = ordered[max(0, round(len(ordered) * 0.95) - 1)]
    return f"p50 {statistics.median(ordered) * 1e3:.1f} ms, p95 {p95 * 1e3:.1f} ms"


def _timed(action: Callable[[], object]) -> float:
    start = time.perf_counter()
    action()
    return time.perf_counter() - start


def main() -> None:
    with tempfile.TemporaryDirectory() as base:
        shelf = ProjectShelf(
            {}, Path(base) / "projects", PadtAuditLog(Path(base) / "audit.jsonl", time.time_ns)
        )
        if OSCAT.is_dir():
            shutil.copytree(OSCAT, Path(base) / "projects" / "oscat")
            shelf.refresh()
            cold = _timed(lambda: project_tree(shelf, "oscat", EDITOR))
            warm = [_timed(lambda: project_tree(shelf, "oscat", EDITOR)) for _ in range(10)]
            tree = project_tree(shelf, "oscat", EDITOR)
            chapter = "BASIC_3.33-12_Time_and_Date.st"
            opened = read_file(shelf, "oscat", chapter, EDITOR)
            save_file(shelf, "oscat", chapter, opened.text + "\n", opened.hash, EDITOR)
            changed = _timed(lambda: project_tree(shelf, "oscat", EDITOR))
            print(
                f"project tree, OSCAT ({len(tree.files)} files, {len(tree.pous)} POUs): "
                f"cold {cold * 1e3:.0f} ms, again {_ms(warm)}, "
                f"after one file changed {changed * 1e3:.0f} ms"
            )
        else:
            print(f"project tree, OSCAT: skipped ({OSCAT} is absent)")
        shelf.new_project("tank", "tank", EDITOR)
        opened = read_file(shelf, "tank", "tank.st", EDITOR)
        known = opened.hash
        saves, polls = [], []
        for n in range(RUNS):
            start = time.perf_counter()
            known = save_file(
                shelf, "tank", "tank.st", f"{opened.text}(* {n} *)\n", known, EDITOR
            ).hash
            saves.append(time.perf_counter() - start)
            start = time.perf_counter()
            changed_on_disk(shelf, "tank", "tank.st", known, EDITOR)
            polls.append(time.perf_counter() - start)
        print(f"save of tank.st with its audit entry: {_ms(saves)}")
        print(f"poll for a change on disk: {_ms(polls)}")
        draft = read_settings(shelf, "tank", EDITOR).settings
        draft.parameters["target_cycle_ms"] = 50
        checks = [
            _timed(lambda: settings_problems(shelf, "tank", draft, EDITOR)) for _ in range(10)
        ]
        print(f"settings check of a draft (the demo compiled with it): {_ms(checks)}")


if __name__ == "__main__":
    main()
