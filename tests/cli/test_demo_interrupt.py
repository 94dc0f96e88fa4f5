"""Ctrl-C on `padt demo` ends it in order. The terminal sends SIGINT to its whole foreground
process group, children included: the demo's runtime and the runtime's workers (the
compile worker a reload starts, the native build worker) must not each print a
`KeyboardInterrupt` traceback; the demo ends them. Here the demo runs in a process group
of its own, as under a terminal, and the group gets the SIGINT."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import httpx

from backend.engineering.project import compile_project, load_project
from backend.engineering.resource_client import ResourceClient
from tests.conftest import REPO, free_port, padt
from tests.support.runtime_process import client_session, router, store_artifact

API_LINE = re.compile(r"padt demo: REST API (http://\S+)/docs")
PASSWORD_LINE = re.compile(r"administrator 'admin', password (\S+)")


def _reload_a_change(api: str, password: str, project: Path) -> None:
    """A real reload through the REST API, which has the runtime's compile worker (a child
    process of the runtime) compile the new code."""
    http = httpx.Client(base_url=api, timeout=180)
    token = http.post("/api/login", json={"user": "admin", "password": password}).json()["token"]
    http.headers["Authorization"] = f"Bearer {token}"
    account = {"user": "admin", "password": password}
    deadline = time.monotonic() + 60
    while http.post("/api/resources/Tank1/login", json=account).status_code != 200:
        assert time.monotonic() < deadline, "the demo resource did not come online"
        time.sleep(0.2)
    source = project / "tank.st"
    source.write_text(
        source.read_text().replace("highLevel : INT := 800;", "highLevel : INT := 790;")
    )
    preview = http.post("/api/resources/Tank1/reload/preview", json={"project": "demo"})
    assert preview.status_code == 200, preview.text
    crc = preview.json()["plan"]["old_crc"]
    done = http.post("/api/resources/Tank1/reload", json={"project": "demo", "expected_crc": crc})
    assert done.status_code == 200, done.text


def test_ctrl_c_ends_the_demo_without_a_traceback(tmp_path: Path) -> None:
    command = [sys.executable, "-m", "padt.cli", "demo", "--state-dir", str(tmp_path)]
    command += ["--port", str(free_port()), "--zenoh-port", str(free_port())]
    command += ["--api-port", "0", "--modbus-port", str(free_port())]
    command += ["--opcua-port", str(free_port())]  # its server ends in order too
    demo = subprocess.Popen(
        command,
        cwd=REPO,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,  # the children's tracebacks go to the terminal's stderr
        text=True,
        start_new_session=True,  # its own process group, as a terminal's foreground job
    )
    assert demo.stdout is not None
    lines: list[str] = []
    api = password = None
    try:
        for line in demo.stdout:
            lines.append(line)
            api = api or (m[1] if (m := API_LINE.search(line)) else None)
            password = password or (m[1] if (m := PASSWORD_LINE.search(line)) else None)
            if "padt demo: open" in line:
                break
        assert api is not None and password is not None, "".join(lines)
        # the rest of the output is read on, so that a full pipe never holds anyone up
        reader = threading.Thread(target=lambda: lines.extend(demo.stdout or ()), daemon=True)
        reader.start()
        _reload_a_change(api, password, tmp_path / "project")
        children = _descendants(demo.pid)
        assert len(children) >= 2, children  # the runtime and its compile worker at least
        os.killpg(demo.pid, signal.SIGINT)  # Ctrl-C
        assert demo.wait(timeout=60) == 0, "".join(lines)
        reader.join(timeout=30)
    finally:
        if demo.poll() is None:
            os.killpg(demo.pid, signal.SIGKILL)
            demo.wait()
    output = "".join(lines)
    assert "Traceback" not in output, output
    assert "KeyboardInterrupt" not in output, output
    # and nothing it started is left behind
    deadline = time.monotonic() + 30
    while any(_alive(pid) for pid in children):
        assert time.monotonic() < deadline, "a process of the demo outlived it"
        time.sleep(0.2)


def _descendants(root: int) -> list[int]:
    """The processes started by `root`, and by them, and so on (from /proc)."""
    parents: dict[int, int] = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                stat = (entry / "stat").read_text()
            except OSError:
                continue  # ended meanwhile
            parents[int(entry.name)] = int(stat.rsplit(")", 1)[1].split()[1])
    found, todo = [], [root]
    while todo:
        parent = todo.pop()
        children = [pid for pid, ppid in parents.items() if ppid == parent]
        found += children
        todo += children
    return found


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"  # a zombie has ended; its parent has not collected it yet


PROJECT = """PROGRAM Main
VAR n : DINT; step : DINT := {step}; END_VAR
n := n + step;
END_PROGRAM
"""


def _write_project(folder: Path, step: int) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "padt.toml").write_text(
        '[project]\nname = "p"\n\n[resource]\nname = "Cell"\ntarget_cycle_ms = 20\n'
        'autostart = "cold"\nsafety_operation = false\n\n'
        '[[resource.program]]\nname = "Main"\nid = 1\n'
    )
    (folder / "main.st").write_text(PROJECT.format(step=step))
    return folder


def test_ctrl_c_ends_a_runtime_and_its_compile_worker_without_a_traceback(tmp_path: Path) -> None:
    """`padt runtime` at a terminal: the SIGINT goes to the runtime and, were it in the
    same group, to the compile worker a reload started."""
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    project = _write_project(tmp_path / "project", 1)
    state = tmp_path / "state"
    artifact = compile_project(load_project([project])).artifact
    assert artifact is not None
    store_artifact(state, artifact)
    with router(endpoint), client_session(endpoint) as session:
        command = [sys.executable, "-m", "padt.cli", "runtime", "--resource", "Cell"]
        command += ["--state-dir", str(state), "--zenoh", endpoint]
        runtime = subprocess.Popen(
            command,
            cwd=REPO,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
            start_new_session=True,
        )
        lines: list[str] = []
        reader = threading.Thread(target=lambda: lines.extend(runtime.stdout or ()), daemon=True)
        reader.start()
        try:
            ResourceClient(session, "Cell").wait_until_answering(60)
            _write_project(project, 2)
            reloaded = padt(
                "reload", str(project), "--resource", "Cell", "--zenoh", endpoint, "--yes",
                "--backup-dir", str(tmp_path / "backups"),
            )  # fmt: skip
            assert reloaded.returncode == 0, reloaded.stdout + reloaded.stderr
            children = _descendants(runtime.pid)
            assert children, "the reload started no compile worker"
            os.killpg(runtime.pid, signal.SIGINT)  # Ctrl-C
            assert runtime.wait(timeout=60) == 0, "".join(lines)
            reader.join(timeout=30)
        finally:
            if runtime.poll() is None:
                os.killpg(runtime.pid, signal.SIGKILL)
                runtime.wait()
    output = "".join(lines)
    assert "Traceback" not in output and "KeyboardInterrupt" not in output, output
    deadline = time.monotonic() + 30
    while any(_alive(pid) for pid in children):
        assert time.monotonic() < deadline, "the compile worker outlived the runtime"
        time.sleep(0.2)
