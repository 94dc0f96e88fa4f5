"""rusty's lit tests: every runnable file through `padt exec`, its output matched against its
`// CHECK:` lines; the expect-error files must be refused. Known failures are listed, each
with its reason, in tests/compiler/corpus/rusty_known_failures.tsv."""

from __future__ import annotations

import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from tests.conftest import REPO
from tests.support.corpus_paths import corpus_dir, known_failures
from tests.support.filecheck import match_output, parse_checks

TIMEOUT_S = 30
REQUIRED_PASS_RATE = 0.90


def run_file(path: Path) -> tuple[bool, str]:
    command = [sys.executable, "-m", "padt.cli", "exec", str(path)]
    try:
        run = subprocess.run(command, capture_output=True, cwd=REPO, timeout=TIMEOUT_S)
    except subprocess.TimeoutExpired:
        return False, f"no result within {TIMEOUT_S} s"
    stderr = run.stderr.decode("utf-8", "replace")
    if "Traceback" in stderr:
        return False, f"traceback: {stderr.strip().splitlines()[-1]}"
    if run.returncode != 0:
        return False, f"exit {run.returncode}: {stderr.strip()[:300]}"
    # STRINGs are bytes: print them as lit does, invalid UTF-8 shown as U+FFFD
    output = run.stdout.decode("utf-8", "replace")
    result = match_output(parse_checks(path.read_text(encoding="utf-8")), output)
    return result.ok, result.message


def refused(path: Path) -> tuple[bool, str]:
    command = [sys.executable, "-m", "padt.cli", "compile", str(path)]
    run = subprocess.run(command, capture_output=True, text=True, cwd=REPO, timeout=TIMEOUT_S)
    if "Traceback" in run.stderr:
        return False, "traceback"
    return run.returncode == 1 and ": error: " in run.stdout, run.stdout[-300:]


def test_rusty_lit_corpus() -> None:
    root = corpus_dir("rusty-lit")
    files = sorted(root.rglob("*.st"))
    runnable = [f for f in files if "expect-error" not in f.parts]
    must_fail = [f for f in files if "expect-error" in f.parts]
    with ThreadPoolExecutor(max_workers=4) as pool:
        results = dict(zip(runnable, pool.map(run_file, runnable), strict=True))
        results.update(zip(must_fail, pool.map(refused, must_fail), strict=True))
    known = known_failures("rusty_known_failures.tsv")
    failing = {str(p.relative_to(root)): why for p, (ok, why) in results.items() if not ok}

    unexplained = {p: why for p, why in failing.items() if p not in known}
    now_passing = sorted(p for p in known if p not in failing)
    passed = sum(1 for p in runnable if results[p][0])
    rate = passed / len(runnable)
    print(f"rusty-lit: {passed}/{len(runnable)} runnable files pass ({rate:.1%})")
    assert not unexplained, "failures missing from the known-failures file:\n" + "\n".join(
        f"{p}\t{why}" for p, why in sorted(unexplained.items())
    )
    assert not now_passing, f"these pass now; remove them from the known failures: {now_passing}"
    assert rate >= REQUIRED_PASS_RATE
