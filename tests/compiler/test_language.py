"""Language features end to end: every tests/compiler/language/*.st runs through `padt exec`, its
output matched against its `// CHECK:` lines (and `// EXIT: n` for the expected exit code)."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

from tests.conftest import REPO
from tests.support.filecheck import match_output, parse_checks

FILES = sorted((REPO / "tests" / "compiler" / "language").glob("*.st"))
EXIT = re.compile(r"//\s*EXIT:\s*(\d+)")


@pytest.mark.parametrize("path", FILES, ids=[p.stem for p in FILES])
def test_language_file(path: Path) -> None:
    text = path.read_text(encoding="utf-8")
    wanted_exit = int(m.group(1)) if (m := EXIT.search(text)) else 0
    command = [sys.executable, "-m", "padt.cli", "exec", str(path)]
    run = subprocess.run(command, capture_output=True, cwd=REPO, timeout=60)
    stderr = run.stderr.decode("utf-8", "replace")
    assert "Traceback" not in stderr, stderr
    assert run.returncode == wanted_exit, stderr
    result = match_output(parse_checks(text), run.stdout.decode("utf-8", "replace"))
    assert result.ok, result.message
