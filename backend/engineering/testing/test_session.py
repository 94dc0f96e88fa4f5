"""A whole `padt test` run: the tests of a build on the tiers asked for, in this process or
spread over worker processes (`-j N`), the results in the order of the tests."""

from __future__ import annotations

import multiprocessing
from collections.abc import Iterator
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path

from backend.engineering.testing.coverage.measure import CoverageMeter, LineHits
from backend.engineering.testing.test_build import UnitTest
from backend.engineering.testing.tiers import (
    Benches,
    UnitTestResult,
    benches,
    run_on,
    run_tests,
)
from backend.engineering.tiers import Tier, native_cache, native_tier
from runtime.code.native.tier import NativeTier
from runtime.contract.artifact import Artifact


def run_session(
    artifact: Artifact,
    cases: tuple[UnitTest, ...],
    tiers: tuple[Tier, ...],
    jobs: int = 1,
    cache: Path | None = None,
    project: Path | None = None,
    coverage: CoverageMeter | None = None,
) -> Iterator[UnitTestResult]:
    """The results as the tests end (with `jobs` > 1: a worker's share at a time);
    `coverage` gets the lines run, a worker's added to it when its share ends."""
    folder = cache or native_cache()
    if jobs <= 1 or len(cases) < 2:
        native = _native(tiers, folder)
        yield from run_tests(artifact, cases, tiers, native, project=project, coverage=coverage)
        return
    shares = [cases[i::jobs] for i in range(min(jobs, len(cases)))]
    # the benches are made here, once: the workers fork with them (and the compiled
    # artifact, the imported compiler, the native tier's bound modules) in place
    global _BENCHES
    _BENCHES = benches(artifact, tiers, _native(tiers, folder), project)
    context = multiprocessing.get_context("fork")
    try:
        with ProcessPoolExecutor(len(shares), mp_context=context) as pool:
            files = coverage.files if coverage is not None else None
            futures = [pool.submit(_run_share, share, files) for share in shares]
            for future in as_completed(futures):
                results, hits = future.result()
                if coverage is not None and hits is not None:
                    coverage.hits.merge(hits)
                yield from results
    finally:
        _BENCHES = None


# the benches `-j`'s workers inherit when they fork
_BENCHES: Benches | None = None


def _native(tiers: tuple[Tier, ...], cache: Path) -> NativeTier | None:
    return native_tier(cache) if "native" in tiers else None


def _run_share(
    cases: tuple[UnitTest, ...], files: frozenset[str] | None
) -> tuple[list[UnitTestResult], LineHits | None]:
    """A worker's share: its results, and the lines it ran when it measures coverage."""
    assert _BENCHES is not None, "a worker forks from run_session"
    meter = CoverageMeter(files) if files is not None else None
    return list(run_on(_BENCHES, cases, coverage=meter)), meter.hits if meter is not None else None
