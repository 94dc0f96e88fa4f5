"""A whole `padt test` run: the tests of a build on the tiers asked for, in this process or
spread over worker processes (`-j N`), the results in the order of the tests."""

from __future__ import annotations

import multiprocessing
import os
from collections.abc import Iterator
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path

from backend.engineering.testing.coverage.measure import CoverageMeter, LineHits
from backend.engineering.testing.test_build import UnitTest
from backend.engineering.testing.tiers import Tier, UnitTestResult, run_tests
from runtime.contract.artifact import Artifact
from runtime.native.tier import NativeTier


def native_cache() -> Path:
    """Where `padt test` keeps the native tier's compiled modules between runs."""
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "padt" / "native"


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
    # fork: a worker starts with the compiled artifact and the imported compiler in place
    context = multiprocessing.get_context("fork")
    with ProcessPoolExecutor(len(shares), mp_context=context) as pool:
        files = coverage.files if coverage is not None else None
        futures = [
            pool.submit(_run_share, artifact, share, tiers, folder, project, files)
            for share in shares
        ]
        for future in as_completed(futures):
            results, hits = future.result()
            if coverage is not None and hits is not None:
                coverage.hits.merge(hits)
            yield from results


def _native(tiers: tuple[Tier, ...], cache: Path) -> NativeTier | None:
    if "native" not in tiers:
        return None
    cache.mkdir(parents=True, exist_ok=True)
    return NativeTier(cache)


def _run_share(
    artifact: Artifact,
    cases: tuple[UnitTest, ...],
    tiers: tuple[Tier, ...],
    cache: Path,
    project: Path | None,
    files: frozenset[str] | None,
) -> tuple[list[UnitTestResult], LineHits | None]:
    """A worker's share: its results, and the lines it ran when it measures coverage."""
    meter = CoverageMeter(files) if files is not None else None
    native = _native(tiers, cache)
    results = list(run_tests(artifact, cases, tiers, native, project=project, coverage=meter))
    return results, meter.hits if meter is not None else None
