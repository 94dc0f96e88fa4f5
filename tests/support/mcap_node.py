"""An MCAP reader nobody here wrote, for the recording tests: the TypeScript `@mcap/core`
under node (`tests/support/mcap_reader.cjs`, installed by `scripts/install-mcap-reader.sh`
into `.tools/mcap-reader/`). Without node or the install a test skips, except in CI, where
it must be there."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
from pathlib import Path
from typing import Any

import pytest

from tests.conftest import REPO

READER = REPO / "tests" / "support" / "mcap_reader.cjs"
INSTALLED = REPO / ".tools" / "mcap-reader" / "node_modules" / "@mcap" / "core"


def node_or_skip() -> str:
    """The node command; skips (fails in CI) when node or @mcap/core is missing."""
    node = shutil.which("node")
    missing = (
        "node is not installed"
        if node is None
        else f"@mcap/core is not installed in {INSTALLED.parent.parent.parent}"
        if not INSTALLED.is_dir()
        else ""
    )
    if missing:
        message = f"{missing}: run scripts/install-mcap-reader.sh (make test does)"
        if os.environ.get("CI") == "true":
            pytest.fail(f"{message} (CI never skips the MCAP interoperability tests)")
        pytest.skip(message)
    assert node is not None
    return node


def read_with_node(path: Path, every_message: bool = False) -> dict[str, Any]:
    """What `@mcap/core`'s stream reader finds in the file (see mcap_reader.cjs); with
    `every_message`, each channel's messages in `all`."""
    command = [node_or_skip(), str(READER), str(path)] + (["--all"] if every_message else [])
    run = subprocess.run(command, capture_output=True, text=True, timeout=300, check=False)
    assert run.returncode == 0, run.stderr
    found: dict[str, Any] = json.loads(run.stdout)
    return found
