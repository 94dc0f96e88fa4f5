"""The third-party client of docs/architecture.md, run as written (only the endpoint, the
resource, the user and the password put in): it logs in by challenge and response with
nothing but eclipse-zenoh and the standard library, checks the resource's proof, and sends
a signed request."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

from tests.conftest import REPO
from tests.runtime.test_hostile_clients import PASSWORD, RESOURCE, target


def documented_client() -> str:
    text = (REPO / "docs" / "architecture.md").read_text()
    section = text.split("A third-party client needs nothing of this project")[1]
    found = re.search(r"```python\n(.*?)```", section, re.DOTALL)
    assert found is not None
    return found.group(1)


def test_the_documented_client_logs_in_and_reads_the_status(
    tmp_path: Path, zenoh_endpoint: str
) -> None:
    code = documented_client()
    settings = 'ENDPOINT, RESOURCE, USER, PASSWORD = "tcp/127.0.0.1:7447", "Tank1", "op", "..."'
    assert settings in code
    code = code.replace(
        settings,
        f"ENDPOINT, RESOURCE, USER, PASSWORD = {zenoh_endpoint!r}, {RESOURCE!r}, "
        f"'reader', {PASSWORD!r}",
    )
    with target(tmp_path, zenoh_endpoint):
        run = subprocess.run(
            [sys.executable, "-c", code], cwd=REPO, capture_output=True, text=True, timeout=60
        )
    assert run.returncode == 0, run.stderr
    assert run.stdout.strip() == "RUN"
