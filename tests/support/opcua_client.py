"""An OPC UA client nobody here wrote, for the OPC UA server tests: node-opcua under node
(`tests/support/opcua_client.cjs`, installed by `scripts/install-opcua-client.sh` into
`.tools/opcua-client/`), and not asyncua, the library the server is built with. Without node
or the install a test skips, except in CI, where it must be there.

`run_plan` hands the script one plan and returns its one result; the plan and result formats
are described at the top of opcua_client.cjs."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
from collections.abc import Iterator
from typing import Any

import pytest

from tests.conftest import REPO

CLIENT = REPO / "tests" / "support" / "opcua_client.cjs"
TOOLS = REPO / ".tools" / "opcua-client"
INSTALLED = TOOLS / "node_modules" / "node-opcua"


def installed() -> bool:
    """Whether node and node-opcua are there to run the client."""
    return shutil.which("node") is not None and INSTALLED.is_dir()


def node_or_skip() -> str:
    """The node command; skips (fails in CI) when node or node-opcua is missing."""
    node = shutil.which("node")
    missing = (
        "node is not installed"
        if node is None
        else f"node-opcua is not installed in {TOOLS}"
        if not INSTALLED.is_dir()
        else ""
    )
    if missing:
        message = f"{missing}: run scripts/install-opcua-client.sh (make test does)"
        if os.environ.get("CI") == "true":
            pytest.fail(f"{message} (CI never skips the OPC UA interoperability tests)")
        pytest.skip(message)
    assert node is not None
    return node


def run_plan(plan: dict[str, Any], timeout_s: float = 60) -> dict[str, Any]:
    """Runs the plan's steps in one node-opcua session and returns the script's result:
    `{"client", "security", "results": [one per step], "timings"}`, or `{"error",
    "message"}` when no session was made. HOME is the plan's pki directory for the run, so
    that node-opcua writes nowhere else."""
    command = [node_or_skip(), str(CLIENT)]
    env = dict(os.environ, HOME=str(plan["pki"])) if plan.get("pki") else None
    run = subprocess.run(
        command,
        input=json.dumps(plan),
        capture_output=True,
        text=True,
        timeout=timeout_s,
        cwd=TOOLS,
        env=env,
        check=False,
    )
    assert run.returncode == 0, run.stderr
    found: dict[str, Any] = json.loads(run.stdout)
    return found


def browsed(tree: dict[str, Any]) -> Iterator[dict[str, Any]]:
    """The nodes of a browse step's tree (`result["browse"]`), itself first, depth first."""
    yield tree
    for child in tree.get("children", []):
        yield from browsed(child)
