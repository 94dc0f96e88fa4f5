"""Generated code compiled in a child process while cycles run.

`compile()` is one C call that holds the interpreter lock for as long as it runs: 20-30 ms
for the program of 10,000 variables of the reload benchmark, proportionally more for larger
ones. A reload prepared on a worker thread therefore stopped the cycle thread for that
long. Here a child process compiles and sends the code objects back marshalled: waiting
for the pipe releases the lock, and loading them takes about 1/25 of the compile.

The child is started on first use and kept; it ends when the runtime closes the pipe
(also when the runtime dies). It runs at a lower priority than the runtime: preparing a
reload is background work. Should it fail in any way, the code is compiled here as
before, which also raises the error a broken unit deserves. What either side compiles was
printed from forms checked where they were decoded (runtime/contract/code/form_check.py).

Run as `python -m runtime.code.compile_worker` it is that child.
"""

from __future__ import annotations

import contextlib
import gc
import marshal
import os
import struct
import subprocess
import sys
import threading
from pathlib import Path
from types import CodeType
from typing import IO

from runtime.code.code_warmup import warm_up
from runtime.contract.generated_code import GeneratedCodeError, compile_unit

_LENGTH = struct.Struct("<Q")
_CHILD_NICE = 10  # below the runtime's raised priority and below normal programs


def compile_here(units: list[tuple[str, str]]) -> list[CodeType]:
    """(source, file name) pairs compiled in this process, in order, and warmed up;
    GeneratedCodeError for a unit that does not compile."""
    codes = [compile_unit(source, filename) for source, filename in units]
    warm_up(codes)
    return codes


class CompileWorker:
    """The child process and the pipe to it; one request at a time."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._child: subprocess.Popen[bytes] | None = None

    def compile(self, units: list[tuple[str, str]]) -> list[CodeType]:
        """(source, file name) pairs compiled by the child, in order, and warmed up here;
        compiled here on any failure."""
        with self._lock:
            try:
                codes = self._in_child(units)
            except (OSError, ValueError, EOFError, TypeError):
                self._close_child()
                codes = None
        compiled = [code for code in codes or () if code is not None]
        if len(compiled) != len(units):
            return compile_here(units)  # raises what a unit that does not compile raises
        warm_up(compiled)
        return compiled

    def close(self) -> None:
        with self._lock:
            self._close_child()

    def _in_child(self, units: list[tuple[str, str]]) -> list[CodeType | None]:
        child = self._child
        if child is None or child.poll() is not None:
            child = self._child = subprocess.Popen(
                [sys.executable, "-m", "runtime.code.compile_worker"],
                stdin=subprocess.PIPE,
                stdout=subprocess.PIPE,
                env=child_environment(),
                # a group of its own: a Ctrl-C at a terminal (SIGINT to the foreground
                # group) reaches the runtime alone, which ends this child
                process_group=0,
            )
        assert child.stdin is not None and child.stdout is not None
        _send(child.stdin, marshal.dumps(units))
        codes = marshal.loads(_receive(child.stdout))
        if not isinstance(codes, list) or len(codes) != len(units):
            raise ValueError("the compile worker answered something else")
        return [code if isinstance(code, CodeType) else None for code in codes]

    def _close_child(self) -> None:
        child, self._child = self._child, None
        if child is None:
            return
        for pipe in (child.stdin, child.stdout):
            if pipe is not None:
                pipe.close()
        try:
            child.wait(timeout=5)
        except subprocess.TimeoutExpired:
            child.kill()
            child.wait()


def child_environment() -> dict[str, str]:
    """This process's environment, with the folder this package is in first on the
    child's path: it finds `runtime` wherever the runtime was started from."""
    here = str(Path(__file__).resolve().parents[2])
    path = os.environ.get("PYTHONPATH")
    return {**os.environ, "PYTHONPATH": here if not path else f"{here}{os.pathsep}{path}"}


def _send(pipe: IO[bytes], data: bytes) -> None:
    pipe.write(_LENGTH.pack(len(data)) + data)
    pipe.flush()


def _receive(pipe: IO[bytes]) -> bytes:
    head = pipe.read(_LENGTH.size)
    if len(head) != _LENGTH.size:
        raise EOFError("the compile worker ended")
    (length,) = _LENGTH.unpack(head)
    data = pipe.read(length)
    if len(data) != length:
        raise EOFError("the compile worker ended mid-answer")
    return data


def _serve(requests: IO[bytes], answers: IO[bytes]) -> None:
    """Compile every request until the pipe closes; a unit that does not compile is
    answered with None (its error is raised where it is compiled again)."""
    while True:
        try:
            units = marshal.loads(_receive(requests))
        except EOFError:
            return
        codes: list[CodeType | None] = []
        for source, filename in units:
            try:
                codes.append(compile_unit(source, filename))
            except GeneratedCodeError:
                codes.append(None)
        _send(answers, marshal.dumps(codes))


COMPILE_WORKER = CompileWorker()

if __name__ == "__main__":
    with contextlib.suppress(OSError):  # else it stays at the runtime's priority
        os.setpriority(os.PRIO_PROCESS, 0, _CHILD_NICE)
    # code objects hold no reference cycles: their counts free them, and no collection
    # need walk what a compile allocates
    gc.disable()
    _serve(sys.stdin.buffer, sys.stdout.buffer)
