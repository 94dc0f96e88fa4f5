"""A bench's client in a process of its own (`python -m <module> --client ARGS...`), so that
its CPU is not the measured process's: it prints JSON lines, which come through a reader
thread, and reads words on its standard input; the end of that input ends it."""

from __future__ import annotations

import json
import os
import queue
import subprocess
import sys
import threading
from contextlib import suppress
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[2]


class ClientProcess:
    def __init__(self, module: str, *args: str) -> None:
        # the client at normal priority, as a client beside the runtime is: back from the
        # runtime's raised priority, which a child process inherits
        back = ["nice", "-n", str(-os.getpriority(os.PRIO_PROCESS, 0))]
        command = [*back, sys.executable, "-m", module, "--client", *args]
        self.process = subprocess.Popen(
            command, cwd=REPO, stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True
        )
        self._lines: queue.Queue[dict[str, Any] | None] = queue.Queue()
        threading.Thread(target=self._read, name="bench-client-reader", daemon=True).start()

    def _read(self) -> None:
        assert self.process.stdout is not None
        for line in self.process.stdout:
            if line.startswith("{"):
                self._lines.put(json.loads(line))
        self._lines.put(None)

    def receive(self, timeout_s: float) -> dict[str, Any]:
        try:
            message = self._lines.get(timeout=timeout_s)
        except queue.Empty:
            raise RuntimeError(f"the client said nothing for {timeout_s:g} s") from None
        if message is None:
            raise RuntimeError(f"the client ended (exit code {self.process.wait()})")
        return message

    def tell(self, word: str) -> None:
        assert self.process.stdin is not None
        self.process.stdin.write(f"{word}\n")
        self.process.stdin.flush()

    def ask(self, word: str, timeout_s: float = 30) -> dict[str, Any]:
        """`word` told, and the client's answer."""
        self.tell(word)
        return self.receive(timeout_s)

    def close(self, timeout_s: float = 15) -> None:
        assert self.process.stdin is not None
        with suppress(BrokenPipeError):  # end of input: the client ends
            self.process.stdin.close()
        try:
            self.process.wait(timeout=timeout_s)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait()
