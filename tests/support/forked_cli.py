"""Many `padt` commands, each in a process of its own, without paying each time for the
interpreter's start and the imports (about a second a command on a loaded machine).

`run_commands` starts one server process (`python -m tests.support.forked_cli`), which
imports the command line and its parts once and then forks a child per command: the child
runs `padt.cli.main(args)` as `python -m padt.cli ARGS` would, its stdout and stderr going
to files of its own, an uncaught exception printed as the interpreter prints it, its exit
code the command's. A child past its timeout is killed. Children that run at once share
nothing but the parent's state from before the first fork."""

from __future__ import annotations

import base64
import contextlib
import json
import os
import signal
import subprocess
import sys
import tempfile
import time
import traceback
from dataclasses import dataclass
from pathlib import Path
from typing import IO

REPO = Path(__file__).resolve().parent.parent.parent


@dataclass(frozen=True)
class Finished:
    """What `subprocess.run` would give: exit code (None: killed at its timeout), output."""

    returncode: int | None
    stdout: bytes
    stderr: bytes


def run_commands(commands: list[list[str]], timeout_s: float, workers: int = 4) -> list[Finished]:
    """Each command's outcome, in order; `workers` children run at once."""
    request = json.dumps({"commands": commands, "timeout_s": timeout_s, "workers": workers})
    server = subprocess.run(
        [sys.executable, "-m", "tests.support.forked_cli"],
        input=request.encode(),
        capture_output=True,
        cwd=REPO,
        timeout=60 + timeout_s * len(commands) / workers,
        check=False,
    )
    assert server.returncode == 0, server.stderr.decode("utf-8", "replace")
    rows = json.loads(server.stdout)
    return [
        Finished(
            row["returncode"], base64.b64decode(row["stdout"]), base64.b64decode(row["stderr"])
        )
        for row in rows
    ]


def _child(args: list[str], out: int, err: int) -> None:
    """In the forked child: be `python -m padt.cli ARGS` with stdout and stderr to files."""
    os.dup2(os.open(os.devnull, os.O_RDONLY), 0)
    os.dup2(out, 1)
    os.dup2(err, 2)
    signal.signal(signal.SIGINT, signal.default_int_handler)
    code = 1
    try:
        from padt import cli

        sys.argv = [str(REPO / "padt" / "cli.py"), *args]
        code = cli.main(args)
    except SystemExit as exit_:  # argparse, or a command that exits: as the interpreter does
        if exit_.code is None or isinstance(exit_.code, int):
            code = exit_.code or 0
        else:
            print(exit_.code, file=sys.stderr)
    except BaseException:  # as the interpreter reports an uncaught exception
        traceback.print_exc()
        code = 1
    finally:
        for stream in (sys.stdout, sys.stderr):
            with contextlib.suppress(Exception):  # the command closed it: nothing more to say
                stream.flush()
        os._exit(code)


def _serve(commands: list[list[str]], timeout_s: float, workers: int) -> list[dict[str, object]]:
    from backend.compiler.pipeline import compile_sources
    from backend.compiler.source import SourceFile
    from backend.engineering import run_once  # noqa: F401 - imported once, for every child
    from padt import cli

    cli.build_parser()  # imports what every command's parser needs
    # the standard library parsed once, here, instead of in every child
    compile_sources([SourceFile("warm.st", "FUNCTION f : INT f := 1; END_FUNCTION")], programs=[])
    sys.stdout.flush()
    sys.stderr.flush()
    results: list[dict[str, object]] = [{} for _ in commands]
    running: dict[int, tuple[int, float, IO[bytes], IO[bytes]]] = {}  # pid: index, start, files
    waiting = list(enumerate(commands))
    while waiting or running:
        while waiting and len(running) < workers:
            index, args = waiting.pop(0)
            out, err = tempfile.TemporaryFile(), tempfile.TemporaryFile()  # noqa: SIM115 - closed once read
            pid = os.fork()
            if pid == 0:
                _child(args, out.fileno(), err.fileno())
            running[pid] = (index, time.monotonic(), out, err)
        pid, status = os.waitpid(-1, os.WNOHANG)
        if pid == 0:
            now = time.monotonic()
            for child, (_, started, _, _) in running.items():
                if now - started > timeout_s:
                    os.kill(child, signal.SIGKILL)
            time.sleep(0.002)
            continue
        index, started, *files = running.pop(pid)
        killed = os.WIFSIGNALED(status) and time.monotonic() - started > timeout_s
        code = None if killed else os.waitstatus_to_exitcode(status)
        streams = []
        for file in files:
            file.seek(0)
            streams.append(base64.b64encode(file.read()).decode())
            file.close()
        results[index] = {"returncode": code, "stdout": streams[0], "stderr": streams[1]}
    return results


def main() -> None:
    request = json.loads(sys.stdin.read())
    results = _serve(request["commands"], request["timeout_s"], request["workers"])
    sys.stdout.write(json.dumps(results))


if __name__ == "__main__":
    main()
