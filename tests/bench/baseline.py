"""Before and after in the same run: a figure of today's code beside the same figure of a
baseline, each measured by `cycle_probe.py` in a process of its own, alternately, the best
of a few rounds each (the machine is shared: the best is the least disturbed).

The baseline is the commit before the cycle work of issue 16, taken from this repository's
history with `git archive`, or what $PADT_BENCH_BASELINE names: a checkout of another
version (a folder) or another commit. The figures issue 34 (native code, variables in
native memory) must keep or better have a baseline of their own, the commit before that
work (`ISSUE_34_COMMIT`). Without git history (a shallow clone) the baseline figures are
left out, with a note.

A figure with a goal rather than a baseline says where it stands with `against_goal`.
"""

from __future__ import annotations

import atexit
import functools
import json
import os
import shutil
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[2]
PROBE = Path(__file__).with_name("cycle_probe.py")
BASELINE_COMMIT = "929e050f999accff3b980eb9de2afea51ee07ed0"  # main before the cycle work
BASELINE_ENV = "PADT_BENCH_BASELINE"
ISSUE_34_COMMIT = "2956fcef2b74f10ce841193e9d87546e50b4918d"  # main before issue 34's work


@dataclass(frozen=True)
class Baseline:
    tree: Path  # the code base, for PYTHONPATH
    name: str  # how the figures call it


@functools.cache
def baseline(commit: str = "") -> Baseline | None:
    """The code base at `commit`; without one, issue 16's baseline or what
    $PADT_BENCH_BASELINE names."""
    given = "" if commit else os.environ.get(BASELINE_ENV, "")
    if given and Path(given).is_dir():
        return Baseline(Path(given).resolve(), given)
    commit = commit or given or BASELINE_COMMIT
    archive = subprocess.run(
        ["git", "-C", str(REPO), "archive", commit, "runtime", "backend"],
        capture_output=True,
        check=False,
    )
    if archive.returncode != 0:
        print(f"  (baseline {commit[:10]} not in this clone's history: no baseline figures)")
        return None
    tree = Path(tempfile.mkdtemp(prefix="padt-baseline-"))
    atexit.register(shutil.rmtree, tree, ignore_errors=True)
    subprocess.run(["tar", "-x", "-C", str(tree)], input=archive.stdout, check=True)
    return Baseline(tree, f"commit {commit[:10]}")


def probe(tree: Path, request: dict[str, Any]) -> dict[str, Any]:
    """`cycle_probe.py` run on the code base at `tree`, in a fresh process."""
    done = subprocess.run(
        [sys.executable, str(PROBE)],
        input=json.dumps(request),
        capture_output=True,
        text=True,
        env={**os.environ, "PYTHONPATH": str(tree)},
        cwd=tree,
        check=False,
    )
    if done.returncode != 0:
        raise RuntimeError(f"cycle probe on {tree} failed:\n{done.stderr[-2000:]}")
    reply: dict[str, Any] = json.loads(done.stdout)
    return reply


@dataclass(frozen=True)
class Compared:
    now: dict[str, Any]  # the best round of today's code
    before: dict[str, Any] | None  # the best round of the baseline, None without one
    name: str  # the baseline's name


Replies = list[dict[str, Any]]


def alternate(request: dict[str, Any], rounds: int, commit: str = "") -> tuple[Replies, Replies]:
    """Today's code and the baseline (`baseline(commit)`), alternately, `rounds` probes
    each: today's replies and the baseline's (none without a baseline)."""
    other = baseline(commit)
    now: Replies = []
    before: Replies = []
    for _ in range(rounds):
        if other is not None:
            before.append(probe(other.tree, request))
        now.append(probe(REPO, request))
    return now, before


def compare(request: dict[str, Any], key: str, rounds: int = 3, commit: str = "") -> Compared:
    """Today's code and the baseline, alternately; per side the round with the smallest
    `key` (a figure of the probe's reply)."""
    now, before = alternate(request, rounds, commit)
    best_now = min(now, key=lambda reply: float(reply[key]))
    best_before = min(before, key=lambda reply: float(reply[key])) if before else None
    other = baseline(commit)
    return Compared(best_now, best_before, other.name if other is not None else "")


def against_goal(value: float, limit: float, goal: str, strict: bool = False) -> str:
    """Where a figure stands against a goal of `value <= limit` (`value < limit` if
    `strict`): the goal, the ratio of the figure to the limit, met or not."""
    met = value < limit if strict else value <= limit
    return f"goal {goal}: {value / limit:.2f}x the goal, {verdict(met)}"


def verdict(met: bool) -> str:
    return "met" if met else "NOT MET"
