"""`padt check-twice`: compile a project in two fresh processes with different hash seeds
and compare every CRC.

Deterministic compilation is what makes a CRC worth anything: the same sources must give
the same code in any process. Set and dict order depend on PYTHONHASHSEED, so two compiles
under different seeds catch an order that leaks into the generated code. The load command
runs this check before it sends a configuration to a resource.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from backend.compiler.diagnostics import Diagnostic

# Fixed seeds, so that a failing check fails again when it is repeated.
SEEDS = ("1", "2")
_REPO = Path(__file__).resolve().parent.parent


@dataclass(frozen=True)
class CompileRun:
    """What one `padt compile --json` process reported."""

    seed: str
    ok: bool
    diagnostics: tuple[str, ...] = ()  # "file:line:col: severity: message [code]"
    configuration: str | None = None  # configuration CRC (None when the compile failed)
    pous: dict[str, str] = field(default_factory=dict)  # POU name -> CRC
    programs: dict[str, str] = field(default_factory=dict)  # user program name -> CRC
    failure: str | None = None  # the process gave no report: why (exit code, stderr)


@dataclass(frozen=True)
class CheckTwiceResult:
    first: CompileRun
    second: CompileRun
    mismatches: tuple[str, ...]  # one line per CRC (or diagnostic list) that differs

    @property
    def compiled(self) -> bool:
        """Both processes compiled the project without error."""
        return all(run.ok and run.failure is None for run in (self.first, self.second))

    @property
    def ok(self) -> bool:
        return self.compiled and not self.mismatches


def check_twice(
    paths: Sequence[Path | str], seeds: tuple[str, str] = SEEDS, resource: str | None = None
) -> CheckTwiceResult:
    """Compile `paths` (a project folder or .st files) in two processes at once; with
    `resource`, compiled for that resource in place of the project's (`for_resource`)."""
    if seeds[0] == seeds[1]:
        raise ValueError("check_twice needs two different hash seeds")
    started = [(_start_compile(paths, seed, resource), seed) for seed in seeds]
    first, second = (_finish_compile(process, seed) for process, seed in started)
    return CheckTwiceResult(first, second, compare(first, second))


def _start_compile(
    paths: Sequence[Path | str], seed: str, resource: str | None
) -> subprocess.Popen[str]:
    python_path = os.pathsep.join(filter(None, (str(_REPO), os.environ.get("PYTHONPATH"))))
    named = ["--as-resource", resource] if resource is not None else []
    return subprocess.Popen(
        [sys.executable, "-m", "padt.cli", "compile", "--json", *named, *map(str, paths)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        # this repository first, so the code checked is the code that runs this check
        env={**os.environ, "PYTHONHASHSEED": seed, "PYTHONPATH": python_path},
    )


def _finish_compile(process: subprocess.Popen[str], seed: str) -> CompileRun:
    stdout, stderr = process.communicate()
    try:
        report = json.loads(stdout)
        crc: dict[str, Any] = report["crc"]
        diagnostics = tuple(_render(d) for d in report["diagnostics"])
        ok = bool(report["ok"])
    except (ValueError, KeyError, TypeError):
        detail = stderr.strip() or stdout.strip() or "no output"
        return CompileRun(seed, False, failure=f"exit code {process.returncode}: {detail}")
    return CompileRun(
        seed,
        ok,
        diagnostics,
        crc.get("configuration"),
        dict(crc.get("pous", {})),
        dict(crc.get("programs", {})),
    )


def _render(diagnostic: dict[str, Any]) -> str:
    return str(Diagnostic(**diagnostic))  # as `padt compile` prints it


def compare(first: CompileRun, second: CompileRun) -> tuple[str, ...]:
    """Every difference between two compiles of the same project, one line each."""
    found: list[str] = []
    if first.configuration != second.configuration:
        found.append(f"configuration CRC: {first.configuration} != {second.configuration}")
    for kind, a, b in (
        ("POU", first.pous, second.pous),
        ("program", first.programs, second.programs),
    ):
        for name in sorted(a.keys() | b.keys()):
            if a.get(name) != b.get(name):
                found.append(f"{kind} {name} CRC: {a.get(name, '-')} != {b.get(name, '-')}")
    if first.diagnostics != second.diagnostics:
        # the same sources must give the same findings too, in the same order
        found.append("diagnostics differ between the two compiles")
    return tuple(found)
