"""What one browser knows of the forcing of its selected resource: the force table
(`GetForcing`) and the forcing parameters (`GetParameters`), asked from a thread of its own
(never from Zenoh's callback thread, never from the refresher). It asks about once a second
while forcing runs (the pushed status says so), every few seconds otherwise (force values
may be prepared by others), at once after this browser's own forcing commands, and not at
all while no resource is selected or the user is not logged in to it."""

from __future__ import annotations

import logging
import threading
import time
from dataclasses import dataclass

from backend.engineering.resource_client import ResourceClient, ResourceUnreachable
from runtime.contract import protocol as p
from runtime.contract.refusal import Refusal

FAST_S = 1.0  # while forcing runs: the remaining time and the forced values
SLOW_S = 5.0  # otherwise: force values prepared by other users show up in time
TICK_S = 0.2
log = logging.getLogger("padt.ui")


@dataclass(frozen=True)
class Target:
    """The resource the browser looks at, as the refresher last saw it."""

    resource: str
    client: ResourceClient
    crc: str | None
    forcing: bool  # the status says forcing runs somewhere


@dataclass(frozen=True)
class ForcingSnapshot:
    resource: str
    state: p.ForcingState | None  # None until the first answer
    fetched: float  # time.monotonic() of the answer: the remaining times count down from it
    parameters: p.ParametersReply | None
    error: str = ""  # why the last question got no answer

    def remaining_s(self, level: str, now: float) -> float | None:
        """Seconds left at a started level ("global" or a program); None without a limit."""
        if self.state is None:
            return None
        left = self.state.remaining_ms.get(level)
        return None if left is None else max(0.0, left / 1000 - (now - self.fetched))


class ForcingFeed:
    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._target: Target | None = None
        self._snapshot: ForcingSnapshot | None = None
        self._parameters: tuple[str, str | None, p.ParametersReply] | None = None
        self._wake = threading.Event()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="forcing-feed", daemon=True)
        self._thread.start()

    # ---- from the refresher and the GUI's callbacks
    def follow(self, target: Target | None) -> None:
        """The resource to watch (None: none selected, or not logged in to it)."""
        with self._lock:
            before = self._target
            self._target = target
            if target is None or (before is not None and before.resource != target.resource):
                self._snapshot = None  # never show one resource's forcing for another
            changed = (
                before is None
                or target is None
                or (before.forcing, before.crc) != (target.forcing, target.crc)
            )
        if changed and target is not None:
            self._wake.set()

    def nudge(self) -> None:
        """Ask again now (after a forcing command of this browser)."""
        self._wake.set()

    def snapshot(self) -> ForcingSnapshot | None:
        with self._lock:
            return self._snapshot

    def close(self) -> None:
        self._stop.set()
        self._wake.set()

    # ---- its own thread
    def _run(self) -> None:
        last = 0.0
        while not self._stop.is_set():
            woken = self._wake.wait(TICK_S)
            self._wake.clear()
            with self._lock:
                target, shown = self._target, self._snapshot
            if target is None or self._stop.is_set():
                continue
            now = time.monotonic()
            due = now - last >= (FAST_S if target.forcing else SLOW_S)
            if woken or due or shown is None:
                last = now
                self._poll(target)

    def _poll(self, target: Target) -> None:
        try:
            parameters = self._parameters_of(target)
            state = target.client.ask(p.GetForcing()).forcing
            snapshot = ForcingSnapshot(target.resource, state, time.monotonic(), parameters)
        except (Refusal, ResourceUnreachable) as exc:
            log.info("forcing of %s: %s", target.resource, exc)
            with self._lock:
                kept = self._snapshot
            snapshot = ForcingSnapshot(
                target.resource,
                kept.state if kept is not None else None,
                kept.fetched if kept is not None else time.monotonic(),
                kept.parameters if kept is not None else None,
                str(exc),
            )
        with self._lock:
            if self._target is not None and self._target.resource == target.resource:
                self._snapshot = snapshot

    def _parameters_of(self, target: Target) -> p.ParametersReply:
        """The forcing parameters change only with the configuration: asked again when
        the CRC changes."""
        known = self._parameters
        if known is not None and known[:2] == (target.resource, target.crc):
            return known[2]
        reply = target.client.ask(p.GetParameters())
        self._parameters = (target.resource, target.crc, reply)
        return reply
