"""A debugging client of one resource (docs/debugging.md), shared by `padt debug`,
`padt dap`, the REST API and the browser: the debug commands, a keep-alive that tells the
resource the client is still there (else the program continues by itself after the
resource's timeout), and the stops it learns of from the resource's status publications.

Breakpoints name files as the artifact does: relative to the project folder, with `/`
(`source_name`)."""

from __future__ import annotations

import threading
from collections.abc import Callable
from pathlib import Path

import zenoh

from backend.engineering.resource_client import ResourceClient, ResourceUnreachable
from runtime.contract import protocol as p
from runtime.contract.protocol import ProgramState
from runtime.contract.refusal import Refusal

KEEP_ALIVE_S = 2.0


def source_name(project_folder: Path, path: Path) -> str:
    """The name the artifact gives a source file of the project."""
    return path.resolve().relative_to(project_folder.resolve()).as_posix()


class DebugSession:
    """Thread-safe: stop callbacks come on a Zenoh thread, commands from the caller's."""

    def __init__(self, client: ResourceClient, keep_alive_s: float = KEEP_ALIVE_S) -> None:
        self.client = client
        self._keep_alive_s = keep_alive_s
        self._closed = threading.Event()
        self._threads: list[threading.Thread] = []
        self._lock = threading.Lock()
        self._stopped = threading.Condition(self._lock)
        self._in_bkpt: set[str] = set()  # programs the last status showed in BKPT
        self._stops = 0  # stops seen so far: `wait_for_stop` waits for the next
        self._callbacks: list[Callable[[p.DebugPause], None]] = []

    # ---- life

    def start(self) -> p.DebugState:
        """Follow the resource's status and keep the session alive; the state now. A
        refusal (a user below read-write) leaves nothing running."""
        state = self.state(keep=True)
        self.client.on_status(self._status)
        for work, name in ((self._keep_alive, "padt-debug"), (self._tell, "padt-debug-stops")):
            thread = threading.Thread(target=work, name=name, daemon=True)
            thread.start()
            self._threads.append(thread)
        return state

    def close(self) -> None:
        """Stop the keep-alive; the breakpoints stay until `clear_all` or the resource's
        timeout."""
        with self._stopped:
            self._closed.set()
            self._stopped.notify_all()
        for thread in self._threads:
            thread.join(5)

    def _keep_alive(self) -> None:
        while not self._closed.wait(self._keep_alive_s):
            try:
                self.state(keep=True)
            except (Refusal, ResourceUnreachable, zenoh.ZError):
                continue  # a missed keep-alive: the next one may reach it

    # ---- commands

    def state(self, keep: bool = False) -> p.DebugState:
        return self.client.ask(p.DebugGet(keep=keep)).debug

    def set_breakpoints(self, file: str, specs: list[p.BreakpointSpec]) -> p.DebugState:
        return self.client.ask(p.DebugSet(file, specs)).debug

    def clear_all(self) -> p.DebugState:
        return self.client.ask(p.DebugClear()).debug

    def continue_(self, program: str) -> p.DebugState:
        return self.client.ask(p.DebugContinue(program)).debug

    def step(self, program: str, kind: p.DebugStepKind = "over") -> p.DebugState:
        return self.client.ask(p.DebugStep(program, kind)).debug

    def run_to(self, program: str, file: str, line: int) -> p.DebugState:
        return self.client.ask(p.DebugRunTo(program, file, line)).debug

    def stack(self, program: str) -> list[p.DebugFrame]:
        return self.client.ask(p.DebugStack(program)).frames

    def variables(self, program: str, frame: int = 0, path: str = "") -> list[p.DebugVariable]:
        return self.client.ask(p.DebugVariables(program, frame, path)).variables

    def set_timeout(self, seconds: int) -> p.DebugState:
        return self.client.ask(p.DebugOptions(seconds)).debug

    # ---- stops

    def on_stop(self, callback: Callable[[p.DebugPause], None]) -> None:
        """`callback(pause)` each time a program enters BKPT (a breakpoint; a step's end
        is the reply of the step itself)."""
        with self._lock:
            self._callbacks.append(callback)

    def wait_for_stop(self, timeout_s: float) -> p.DebugPause | None:
        """The pause of the next program to enter BKPT from now, or None after
        `timeout_s`."""
        with self._stopped:
            seen = self._stops
            if not self._stopped.wait_for(lambda: self._stops > seen, timeout_s):
                return None
        return self.state().paused

    def _status(self, status: p.Status) -> None:
        """On a Zenoh thread: only note the stop (a query from here could block Zenoh)."""
        now = {x.name for x in status.programs if x.state == ProgramState.BKPT}
        with self._stopped:
            entered = now - self._in_bkpt
            self._in_bkpt = now
            if entered:
                self._stops += 1
                self._stopped.notify_all()

    def _tell(self) -> None:
        """On a thread of its own: each stop to the `on_stop` callbacks."""
        told = 0
        while True:
            with self._stopped:
                while self._stops <= told and not self._closed.is_set():
                    self._stopped.wait()
                if self._closed.is_set():
                    return
                told, callbacks = self._stops, list(self._callbacks)
            if not callbacks:
                continue
            try:
                pause = self.state().paused
            except (Refusal, ResourceUnreachable):
                continue
            if pause is not None:
                for callback in callbacks:
                    callback(pause)
