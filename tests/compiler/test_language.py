"""Language features end to end: every tests/compiler/language/*.st runs through `padt exec`, its
output matched against its `// CHECK:` lines (and `// EXIT: n` for the expected exit code).
Each command is a process of its own, forked from one that imported the command line once
(tests/support/forked_cli.py); they run together, once for the module."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from tests.conftest import REPO
from tests.support.filecheck import match_output, parse_checks
from tests.support.forked_cli import Finished, run_commands

FILES = sorted((REPO / "tests" / "compiler" / "language").glob("*.st"))
EXIT = re.compile(r"//\s*EXIT:\s*(\d+)")


@pytest.fixture(scope="module")
def runs() -> dict[Path, Finished]:
    """`padt exec FILE` of every file."""
    finished = run_commands([["exec", str(path)] for path in FILES], timeout_s=60)
    return dict(zip(FILES, finished, strict=True))


@pytest.mark.parametrize("path", FILES, ids=[p.stem for p in FILES])
def test_language_file(path: Path, runs: dict[Path, Finished]) -> None:
    text = path.read_text(encoding="utf-8")
    wanted_exit = int(m.group(1)) if (m := EXIT.search(text)) else 0
    run = runs[path]
    assert run.returncode is not None, "no result within 60 s"
    stderr = run.stderr.decode("utf-8", "replace")
    assert "Traceback" not in stderr, stderr
    assert run.returncode == wanted_exit, stderr
    result = match_output(parse_checks(text), run.stdout.decode("utf-8", "replace"))
    assert result.ok, result.message
