"""The coverage of a build's tests, as `padt test` and the Tests screen measure it: a meter
for the build's project and library files, and the coverage it measured."""

from __future__ import annotations

from backend.engineering.testing.coverage.measure import CoverageMeter, measured_files
from backend.engineering.testing.coverage.model import Coverage, coverage_of
from backend.engineering.testing.test_build import UnitTestBuild


def meter_for(build: UnitTestBuild) -> CoverageMeter:
    return CoverageMeter(measured_files(source.name for source in build.project.sources))


def coverage_measured(build: UnitTestBuild, meter: CoverageMeter) -> Coverage:
    assert build.artifact is not None, "only a build that compiled ran tests"
    return coverage_of(build.artifact, build.syntax, build.project.sources, meter.files, meter.hits)
