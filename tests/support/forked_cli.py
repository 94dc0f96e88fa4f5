"""`padt` commands, each in a process of its own, without paying each time for the
interpreter's start and the imports (0.5-1 s a command, more on a loaded machine).

A server process (`python -m tests.support.forked_cli`) imports the command line and its
parts once, parses the standard library of ST once, and then forks a child per command.
The child is what `python -m padt.cli ARGS` would be: the command's environment (the
server's own replaced) and working folder, stdin from /dev/null, stdout and stderr to files
of its own, `padt.cli.main(ARGS)`, an uncaught exception printed as the interpreter prints
it, and the interpreter's exit (non-daemon threads joined, atexit functions run, streams
flushed) with the command's exit code. A child past its timeout is killed.

What a fresh interpreter reads only as it starts (PYTHONHASHSEED and the other PYTHON*
variables, the locale) a forked child cannot take: a command whose environment differs
from the server's there runs in a process of its own from the start (`run_command` says
None). `run_commands` runs a batch, several at once;
`run_command` one, through a server kept for the whole test session (`padt` of
tests/conftest.py). A long-running command (`padt demo`) is forked from a server of its own
by tests/support/forked_process.py, as its child is made here (`become_command`)."""

from __future__ import annotations

import atexit
import base64
import contextlib
import json
import os
import select
import signal
import subprocess
import sys
import tempfile
import threading
import time
import traceback
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any, NoReturn

REPO = Path(__file__).resolve().parent.parent.parent
# environment variables a forked child cannot honour: read by the interpreter as it starts
_AT_START = ("PYTHON", "LANG", "LC_")
# what the commands import when they run, imported once by the server
_WARM = (
    "padt.online",
    "padt.online_test",
    "padt.recording",
    "padt.operation",
    "padt.configuration",
    "padt.new_project",
    "backend.engineering.project",
    "backend.engineering.resource_client",
    "backend.engineering.check_twice",
    "backend.engineering.backup",
    "backend.engineering.simulation",
    "backend.engineering.run_once",
    "backend.engineering.known_resources",
    "runtime.contract.session",
    "zenoh",
)


@dataclass(frozen=True)
class Finished:
    """What `subprocess.run` would give: exit code (None: killed at its timeout), output."""

    returncode: int | None
    stdout: bytes
    stderr: bytes


def at_start(env: Mapping[str, str]) -> dict[str, str]:
    """The variables of `env` that the interpreter reads as it starts."""
    return {name: value for name, value in env.items() if name.startswith(_AT_START)}


def run_commands(commands: list[list[str]], timeout_s: float, workers: int = 4) -> list[Finished]:
    """Each command's outcome, in order; `workers` children run at once; the environment
    and working folder are the caller's and the repository."""
    request = {"commands": commands, "timeout_s": timeout_s, "workers": workers}
    server = subprocess.run(
        [sys.executable, "-m", "tests.support.forked_cli", "batch"],
        input=json.dumps(request).encode(),
        capture_output=True,
        cwd=REPO,
        timeout=60 + timeout_s * len(commands) / workers,
        check=False,
    )
    assert server.returncode == 0, server.stderr.decode("utf-8", "replace")
    return [_finished(row) for row in json.loads(server.stdout)]


class _Server:
    """One server process for commands one at a time."""

    def __init__(self) -> None:
        self.lock = threading.Lock()
        self.at_start = at_start(os.environ)  # what its children have, whatever they ask
        self.process = subprocess.Popen(
            [sys.executable, "-m", "tests.support.forked_cli", "serve"],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            cwd=REPO,
        )

    def run(self, args: list[str], env: Mapping[str, str], cwd: Path, timeout_s: float) -> Finished:
        assert self.process.stdin is not None and self.process.stdout is not None
        request = {"args": args, "env": dict(env), "cwd": str(cwd), "timeout_s": timeout_s}
        self.process.stdin.write(json.dumps(request).encode() + b"\n")
        self.process.stdin.flush()
        line = self.process.stdout.readline()
        if not line:
            raise OSError("the command server ended")
        return _finished(json.loads(line))

    def close(self) -> None:
        if self.process.stdin is not None:
            with contextlib.suppress(OSError):
                self.process.stdin.close()
        end_server(self.process)


def end_server(process: subprocess.Popen[bytes]) -> None:
    """Wait for a server told to end (its requests' end closed); killed if it hangs."""
    try:
        process.wait(timeout=10)
    except subprocess.TimeoutExpired:
        process.kill()
        process.wait()


_server: _Server | None = None
_starting = threading.Lock()


def run_command(
    args: list[str], env: Mapping[str, str], cwd: Path, timeout_s: float
) -> Finished | None:
    """`padt ARGS` in a child of the session's server; None when the server is busy with
    another thread's command or gone (then the caller starts a process of its own)."""
    global _server
    with _starting:
        if _server is None:
            _server = _Server()
            atexit.register(_server.close)
        server = _server
    if at_start(env) != server.at_start or not server.lock.acquire(blocking=False):
        return None
    try:
        return server.run(args, env, cwd, timeout_s)
    except OSError:
        return None
    except BaseException:  # a test's timeout, Ctrl-C: its reply would answer the next one
        with _starting:
            if _server is server:
                _server = None
        server.process.kill()
        raise
    finally:
        server.lock.release()


def _finished(row: dict[str, Any]) -> Finished:
    return Finished(
        row["returncode"], base64.b64decode(row["stdout"]), base64.b64decode(row["stderr"])
    )


# ---- the server's side


def warm_up(modules: tuple[str, ...]) -> None:
    """In a server: import the command line and `modules` (one missing, renamed by later
    work, is simply left to the children), parse the standard library of ST; with no
    thread started, so that a forked child inherits no lock held by another thread."""
    import importlib

    from backend.compiler.pipeline import compile_sources
    from backend.compiler.source import SourceFile
    from padt import cli

    cli.build_parser()  # imports what every command's parser needs
    for module in modules:
        with contextlib.suppress(ImportError):
            importlib.import_module(module)
    # the standard library parsed once, here, instead of in every child
    compile_sources([SourceFile("warm.st", "FUNCTION f : INT f := 1; END_FUNCTION")], programs=[])
    # OpenBLAS (under numpy, which the UI imports) starts its threads as it loads and stops
    # them before every fork (pthread_atfork): a first fork stops them before they are counted
    if (pid := os.fork()) == 0:
        os._exit(0)
    os.waitpid(pid, 0)
    threads = len(os.listdir("/proc/self/task"))
    assert threads == 1, f"{threads} threads in the server: a child could inherit a held lock"
    sys.stdout.flush()
    sys.stderr.flush()


def _fork(
    args: list[str], env: Mapping[str, str] | None, cwd: str | None
) -> tuple[int, IO[bytes], IO[bytes]]:
    """A child running `padt ARGS`: its pid and the files of its stdout and stderr."""
    out, err = tempfile.TemporaryFile(), tempfile.TemporaryFile()  # noqa: SIM115 - closed once read
    nothing = os.open(os.devnull, os.O_RDONLY)
    pid = os.fork()
    if pid == 0:
        become_command(args, env, cwd, (nothing, out.fileno(), err.fileno()), _REPLIES)
    os.close(nothing)
    return pid, out, err


def become_command(
    args: list[str],
    env: Mapping[str, str] | None,
    cwd: str | None,
    streams: tuple[int, int, int],
    server_fds: Iterable[int],
) -> NoReturn:
    """In a child forked from a server: be `python -m padt.cli ARGS` with `streams` as its
    stdin, stdout and stderr and none of the server's own files (`server_fds`, and the
    streams' other numbers); `env` (None: the server's) in place of the server's
    environment; never returns."""
    code = 1
    try:
        for fd in server_fds:
            os.close(fd)
        for target, fd in enumerate(streams):
            os.dup2(fd, target)
        for fd in set(streams) - {0, 1, 2}:
            os.close(fd)
        signal.signal(signal.SIGINT, signal.default_int_handler)
        if env is not None:
            os.environ.clear()
            os.environ.update(env)
            tempfile.tempdir = None  # chosen anew from TMPDIR and the others
        if cwd is not None:
            os.chdir(cwd)
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
        # the interpreter's exit: threads joined, atexit functions run, streams flushed
        with contextlib.suppress(BaseException):
            getattr(threading, "_shutdown", lambda: None)()
        with contextlib.suppress(BaseException):
            getattr(atexit, "_run_exitfuncs", lambda: None)()
        for stream in (sys.stdout, sys.stderr):
            with contextlib.suppress(BaseException):  # the command closed it: nothing to say
                stream.flush()
        os._exit(code)


def _wait(pid: int, timeout_s: float) -> int | None:
    """The child's exit code; None when it had to be killed at its timeout."""
    waker = os.pidfd_open(pid)
    try:
        ready, _, _ = select.select([waker], [], [], timeout_s)
    finally:
        os.close(waker)
    if not ready:
        os.kill(pid, signal.SIGKILL)
        os.waitpid(pid, 0)
        return None
    _, status = os.waitpid(pid, 0)
    return os.waitstatus_to_exitcode(status)


def _result(code: int | None, out: IO[bytes], err: IO[bytes]) -> dict[str, object]:
    streams = []
    for file in (out, err):
        file.seek(0)
        streams.append(base64.b64encode(file.read()).decode())
        file.close()
    return {"returncode": code, "stdout": streams[0], "stderr": streams[1]}


_REPLIES: list[int] = []  # the server's pipe for its replies: no child holds it


def _serve() -> None:
    """One request a line on stdin, one result a line on stdout, until stdin ends."""
    replies = os.fdopen(os.dup(1), "w")
    _REPLIES.append(replies.fileno())
    for line in sys.stdin:
        request = json.loads(line)
        pid, out, err = _fork(request["args"], request["env"], request["cwd"])
        code = _wait(pid, request["timeout_s"])
        replies.write(json.dumps(_result(code, out, err)) + "\n")
        replies.flush()


def _batch() -> None:
    """Every command of the request, `workers` at once; their results as one list."""
    request = json.loads(sys.stdin.read())
    commands: list[list[str]] = request["commands"]
    timeout_s: float = request["timeout_s"]
    results: list[dict[str, object]] = [{} for _ in commands]
    waiting = list(enumerate(commands))
    running: dict[int, tuple[int, int, IO[bytes], IO[bytes]]] = {}  # pidfd: index, pid, files
    deadlines: dict[int, float] = {}
    while waiting or running:
        while waiting and len(running) < request["workers"]:
            index, args = waiting.pop(0)
            pid, out, err = _fork(args, None, None)
            waker = os.pidfd_open(pid)
            running[waker] = (index, pid, out, err)
            deadlines[waker] = time.monotonic() + timeout_s
        first = min(deadlines.values())
        ready, _, _ = select.select(list(running), [], [], max(0.0, first - time.monotonic()))
        for waker in list(running):
            if waker not in ready and deadlines[waker] > time.monotonic():
                continue
            index, pid, out, err = running.pop(waker)
            del deadlines[waker]
            os.close(waker)
            code = _wait(pid, 0)
            results[index] = _result(code, out, err)
    sys.stdout.write(json.dumps(results))


def main() -> None:
    warm_up(_WARM)
    if sys.argv[1:] == ["serve"]:
        _serve()
    else:
        _batch()


if __name__ == "__main__":
    main()
