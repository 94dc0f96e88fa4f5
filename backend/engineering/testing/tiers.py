"""Every test on the Python tier and on the native tier: the same outcome, and after every
cycle the same value in every variable (docs/testing.md, "Both tiers"). The Python tier is
the reference; the native run compares itself with it as it goes."""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from contextlib import nullcontext
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from backend.engineering.testing.coverage.measure import CoverageMeter
from backend.engineering.testing.test_build import UnitTest
from backend.engineering.testing.test_run import Outcome, UnitTestBench, WatchStop, same, shown
from backend.engineering.tiers import Tier
from runtime.code.native.tier import NativeTier
from runtime.contract.artifact import Artifact


@dataclass(frozen=True)
class UnitTestResult:
    case: UnitTest
    outcome: Outcome  # the Python tier's, or what fails the test
    seconds: float
    tiers: tuple[Tier, ...]  # the tiers it ran on

    @property
    def passed(self) -> bool:
        return self.outcome.status == "passed"


class _Disagreement(WatchStop):
    def __init__(self, cycle: int, message: str) -> None:
        super().__init__(message)
        self.cycle, self.message = cycle, message


def _comparer(
    reference: list[dict[str, Any]], types: dict[str, str]
) -> Callable[[int, dict[str, Any]], None]:
    def compare(cycle: int, values: dict[str, Any]) -> None:
        if cycle > len(reference):
            raise _Disagreement(cycle, f"the native tier ran cycle {cycle}, Python did not")
        expected = reference[cycle - 1]
        for path, value in expected.items():
            found = values.get(path)
            if not same(value, found) or type(value) is not type(found):
                kind = types.get(path, "")
                raise _Disagreement(
                    cycle,
                    f"the tiers disagree after cycle {cycle}: {path} is "
                    f"{shown(value, kind)} on Python, {shown(found, kind)} on native",
                )

    return compare


def _keeper(cycles: list[dict[str, Any]]) -> Callable[[int, dict[str, Any]], None]:
    def keep(cycle: int, values: dict[str, Any]) -> None:
        cycles.append(values)

    return keep


@dataclass
class Benches:
    """A test bench per tier asked for, made once: `-j`'s workers fork with them in place."""

    python: UnitTestBench | None
    native: UnitTestBench | None
    types: dict[str, str]  # every variable's type, to show a disagreement's values


def benches(
    artifact: Artifact,
    tiers: tuple[Tier, ...],
    native: NativeTier | None,
    project: Path | None = None,
) -> Benches:
    """`native` None (or no C compiler): Python only, also where native alone was asked
    for (the tests run as `padt runtime` would run the bodies there)."""
    on_native = "native" in tiers and native is not None and native.available
    on_python = "python" in tiers or not on_native
    python = UnitTestBench(artifact, None, project) if on_python else None
    compiled = UnitTestBench(artifact, native, project) if on_native else None
    types = {}
    if python is not None:
        types = {v.path: v.type for v in python.resource.variables.infos()}
    return Benches(python, compiled, types)


def run_tests(
    artifact: Artifact,
    cases: tuple[UnitTest, ...],
    tiers: tuple[Tier, ...],
    native: NativeTier | None,
    timer: Callable[[], float] = time.perf_counter,
    project: Path | None = None,
    coverage: CoverageMeter | None = None,
) -> Iterator[UnitTestResult]:
    """Each test's result as it ends, on benches made for them."""
    made = benches(artifact, tiers, native, project)
    return run_on(made, cases, timer, coverage)


def run_on(
    made: Benches,
    cases: tuple[UnitTest, ...],
    timer: Callable[[], float] = time.perf_counter,
    coverage: CoverageMeter | None = None,
) -> Iterator[UnitTestResult]:
    """Each test's result as it ends. `coverage` counts the lines the Python tier runs (C
    bodies cannot be traced)."""
    python, compiled = made.python, made.native
    for case in cases:
        began = timer()
        ran: list[Tier] = []
        outcome: Outcome | None = None
        cycles: list[dict[str, Any]] = []
        if python is not None:
            with coverage.measuring(python.image) if coverage is not None else nullcontext():
                outcome = python.run(case, _keeper(cycles))
            ran.append("python")
        if compiled is not None:
            watch = _comparer(cycles, made.types) if python is not None else None
            try:
                native_outcome = compiled.run(case, watch)
            except _Disagreement as disagreement:
                native_outcome = Outcome("failed", disagreement.message, cycles=disagreement.cycle)
            ran.append("native")
            outcome = _joined(outcome, native_outcome)
        assert outcome is not None
        yield UnitTestResult(case, outcome, timer() - began, tuple(ran))


def _joined(python: Outcome | None, native: Outcome) -> Outcome:
    """One outcome for both tiers: the disagreement, or the Python tier's when both ended
    alike."""
    if python is None:
        return native
    if native.status == "failed" and native.message.startswith("the tiers disagree"):
        return native
    if (python.status, python.message, python.cycles) != (
        native.status,
        native.message,
        native.cycles,
    ):
        return Outcome(
            "failed",
            f"the tiers end differently: Python {_ended(python)}; native {_ended(native)}",
            python.place or native.place,
        )
    return python


def _ended(outcome: Outcome) -> str:
    text = f"{outcome.status} after {outcome.cycles} cycles"
    return f"{text} ({outcome.message})" if outcome.message else text
