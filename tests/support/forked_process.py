"""A long-running `padt` command (`padt demo`) in a process of its own, forked from a server
that imported its parts once, and handled as a `subprocess.Popen` is: its pid, its stdout
read line by line, signals, `poll` and `wait` with its exit code.

`padt demo` spends about 3.4 s of CPU importing its parts (the REST API 2.5 s, the UI,
Zenoh) before it does anything, and the browser tests start one for each test. The server
(`python -m tests.support.forked_process FD`) imports them once and forks a child per
command, made as tests/support/forked_cli.py makes its children (`become_command`): the
command's arguments, environment and working folder; its stdin, stdout and stderr are files
of the caller's, passed with the request over a Unix socket (stdout a pipe the caller
reads). A command whose environment differs from the server's in what the interpreter reads
as it starts runs in a process of its own instead (`CommandServer.start` says None).

Only the server, their parent, can reap its children. It sends the caller a pidfd with each
child's pid; the caller waits on that, and asks the server to reap the child only once it
has ended, so the server never waits for a running child and no request waits behind
another's wait. Until it is reaped the child is a zombie: its pid names no other process.
When the caller closes its end of the socket (`CommandServer.close`, or its process ends
anyhow), the server kills the children still running, reaps them and ends."""

from __future__ import annotations

import json
import os
import select
import signal
import socket
import subprocess
import sys
import threading
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import IO, Any

from tests.support.forked_cli import REPO, at_start, become_command, end_server, warm_up

# what `padt demo` imports as it starts (padt/demo.py), imported once by the server
_WARM = (
    "padt.demo",
    "padt.demo_plant",
    "runtime.contract.session",
    "runtime.contract.state_folder",
    "runtime.contract.stop_request",
    "backend.api.server",
    "backend.api.service",
    "backend.engineering.backup",
    "backend.engineering.known_resources",
    "backend.engineering.padt_accounts",
    "backend.engineering.project",
    "backend.engineering.project_shelf",
    "backend.engineering.resource_directory",
    "backend.engineering.start_up_freeze",
    "backend.engineering.watch_lists",
    "frontend.app",
    "frontend.ui_context",
    "zenoh",
)
_MESSAGE_MAX = 1 << 20  # a request's arguments and environment, as JSON
# files received, as every file Python opens, are not inherited by a program it executes
_CLOEXEC = socket.MSG_CMSG_CLOEXEC


class CommandServer:
    """The server process, for the long-running commands of a test session."""

    def __init__(self) -> None:
        self._lock = threading.Lock()  # a request and its reply, one at a time
        self._at_start = at_start(os.environ)  # what its children have, whatever they ask
        self._socket, theirs = socket.socketpair(socket.AF_UNIX, socket.SOCK_SEQPACKET)
        with theirs:
            self._process = subprocess.Popen(
                [sys.executable, "-m", "tests.support.forked_process", str(theirs.fileno())],
                stdin=subprocess.DEVNULL,
                stdout=subprocess.DEVNULL,
                cwd=REPO,
                pass_fds=[theirs.fileno()],
            )

    def start(self, args: list[str], env: Mapping[str, str], cwd: Path) -> ForkedCommand | None:
        """`padt ARGS` in a child of the server, its stdout a pipe to read, its stdin and
        stderr this process's; None when `env` differs from the server's in what the
        interpreter reads as it starts, or the server is gone (then the caller starts a
        process of its own)."""
        if at_start(env) != self._at_start:
            return None
        stdout, theirs = os.pipe()
        try:
            reply, pidfds = self._ask(
                {"args": args, "env": dict(env), "cwd": str(cwd)}, [0, theirs, 2]
            )
        except OSError:
            os.close(stdout)
            return None
        finally:
            os.close(theirs)  # the child's alone: the pipe ends with it
        return ForkedCommand(self, args, reply["pid"], pidfds[0], open(stdout, encoding="utf-8"))

    def reap(self, pid: int) -> int:
        """The exit code of the child `pid`, which has ended (its pidfd said so)."""
        reply, _ = self._ask({"reap": pid}, [])
        code: int = reply["returncode"]
        return code

    def close(self) -> None:
        """End the server, and with it the children still running."""
        self._socket.close()
        end_server(self._process)

    def _ask(self, request: dict[str, Any], fds: Sequence[int]) -> tuple[dict[str, Any], list[int]]:
        with self._lock:
            socket.send_fds(self._socket, [json.dumps(request).encode()], fds)
            reply, reply_fds, _, _ = socket.recv_fds(self._socket, _MESSAGE_MAX, 1, _CLOEXEC)
        if not reply:
            raise OSError("the command server ended")
        answer: dict[str, Any] = json.loads(reply)
        return answer, reply_fds


class ForkedCommand:
    """A command forked from the server, handled as `subprocess.Popen(..., stdout=PIPE,
    text=True)` is."""

    def __init__(
        self, server: CommandServer, args: list[str], pid: int, pidfd: int, stdout: IO[str]
    ) -> None:
        self.args = args
        self.pid = pid
        self.stdout = stdout
        self.returncode: int | None = None
        self._server = server
        self._pidfd = pidfd  # readable once the child has ended

    def send_signal(self, sig: int) -> None:
        if self.returncode is None:  # not reaped: the pidfd still names the child
            signal.pidfd_send_signal(self._pidfd, sig)

    def poll(self) -> int | None:
        return self._ended_within(0)

    def wait(self, timeout: float | None = None) -> int:
        code = self._ended_within(timeout)
        if code is None:
            raise subprocess.TimeoutExpired(self.args, timeout or 0)
        return code

    def _ended_within(self, timeout: float | None) -> int | None:
        """Its exit code, once it has ended within `timeout` s (None: however long)."""
        if self.returncode is None:
            ended, _, _ = select.select([self._pidfd], [], [], timeout)
            if ended:
                self.returncode = self._server.reap(self.pid)
                os.close(self._pidfd)
        return self.returncode


# ---- the server's side


def _serve(channel: socket.socket) -> None:
    """A request a message, its reply a message, until the caller closes its end; then the
    children still running are killed and every child reaped."""
    children: set[int] = set()
    try:
        while True:
            message, fds, flags, _ = socket.recv_fds(channel, _MESSAGE_MAX, 3, _CLOEXEC)
            if not message:
                return
            assert not flags & socket.MSG_TRUNC, "a request longer than _MESSAGE_MAX"
            request = json.loads(message)
            if "reap" in request:
                # asked once its pidfd said it has ended: this never waits
                _, status = os.waitpid(request["reap"], 0)
                children.remove(request["reap"])
                reply = {"returncode": os.waitstatus_to_exitcode(status)}
                socket.send_fds(channel, [json.dumps(reply).encode()], [])
                continue
            pid = os.fork()
            if pid == 0:
                streams = (fds[0], fds[1], fds[2])
                become_command(
                    request["args"], request["env"], request["cwd"], streams, [channel.fileno()]
                )
            children.add(pid)
            for fd in fds:  # the child's now: no later child may inherit them
                os.close(fd)
            pidfd = os.pidfd_open(pid)
            socket.send_fds(channel, [json.dumps({"pid": pid}).encode()], [pidfd])
            os.close(pidfd)
    finally:
        for pid in children:
            os.kill(pid, signal.SIGKILL)
            os.waitpid(pid, 0)


def main() -> None:
    channel = socket.socket(fileno=int(sys.argv[1]))
    # a Ctrl-C reaches the whole process group: the session ends the server by closing its
    # end, after its fixtures have stopped their commands (the children take SIGINT again)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    warm_up(_WARM)
    _serve(channel)


if __name__ == "__main__":
    main()
