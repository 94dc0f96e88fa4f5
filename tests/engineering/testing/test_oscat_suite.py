"""The example suite of OSCAT tests (docs/examples/oscat-tests: 94 tests of OSCAT BASIC 3.33
functions against independently computed values) passes with `padt test`, the library
built from ../shared/corpus as the example's README says."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from tests.conftest import REPO, padt
from tests.support.corpus_paths import corpus_dir

EXAMPLE = REPO / "docs" / "examples" / "oscat-tests"


def oscat_library(tmp_path: Path) -> Path:
    library = tmp_path / "oscat_basic_3.33.st"
    made = subprocess.run(
        [
            sys.executable,
            str(EXAMPLE / "oscat_library.py"),
            str(corpus_dir("oscat/st")),
            str(library),
        ],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert made.returncode == 0, made.stderr
    return library


def run_suite(tmp_path: Path, *options: str) -> subprocess.CompletedProcess[str]:
    library = oscat_library(tmp_path)
    env = {"XDG_CACHE_HOME": str(tmp_path / "cache")}
    return padt("test", str(EXAMPLE), "--library", str(library), *options, env=env, timeout=900)


def test_the_oscat_suite_passes_on_the_python_tier(tmp_path: Path) -> None:
    run = run_suite(tmp_path, "--tier", "python")
    assert run.returncode == 0, run.stdout + run.stderr
    last = run.stdout.splitlines()[-1]
    assert last.startswith("94 passed of 94 tests (python)"), last


@pytest.mark.slow  # the native tier compiles OSCAT's 449 POUs to C first: a minute here
def test_the_oscat_suite_passes_on_both_tiers(tmp_path: Path) -> None:
    run = run_suite(tmp_path)
    assert run.returncode == 0, run.stdout + run.stderr
    assert run.stdout.splitlines()[-1].startswith("94 passed of 94 tests (native and python)")
