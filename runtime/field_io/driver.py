"""The interface of a field I/O driver: what the exchange (`exchange.py`) asks of each.

A driver serves the resource's variables to the field (a server) or reaches remote devices
(a client), or both, for one protocol. Its network work runs as coroutines on the I/O
thread (`io_thread.py`); everything else is called on the cycle thread, between cycles, and
must never wait: what the field delivered and what clients wrote comes in through
`before_cycle` (a snapshot taken with one reference read, or a queue), and the cycle's
values go out through `after_cycle` (one immutable snapshot handed over). A driver reports
what happens on the bus as events through the recorder it was given, and marks the inputs
it cannot deliver (its device lost) in `bad`: they then hold their safe values.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Protocol

from runtime.contract.artifact import Artifact, UserAccount
from runtime.contract.protocol import IoPoint, IoStatus
from runtime.event_recorder import EventRecorder
from runtime.process_image import ProcessImage
from runtime.variables import Variables


@dataclass(frozen=True)
class DriverContext:
    """The parts of the resource a driver works with."""

    variables: Variables
    io: ProcessImage
    recorder: EventRecorder
    running: Callable[[], bool]  # whether the resource runs (outputs are safe otherwise)
    resource: str = "resource"  # its name
    # its accounts now, for a server that logs users in
    accounts: Callable[[], tuple[UserAccount, ...]] = tuple
    # a client's write of a variable (path, value, user) as an online write, with its
    # checks and event (cycle thread); Refusal when it is refused
    write: Callable[[str, Any, str], None] | None = None


class FieldDriver(Protocol):
    """One protocol's field I/O, made by its `DriverKind` for one configuration."""

    @property
    def bad(self) -> frozenset[str]:
        """The upper-case paths of inputs whose values are safe ones (their source lost)."""
        ...

    def before_cycle(self) -> None:
        """Cycle thread, before a cycle: deliveries into the process image, client writes
        into their variables, state changes as events."""

    def after_cycle(self) -> None:
        """Cycle thread, after a cycle: the values the field sees, as one snapshot."""

    def rebind(self) -> None:
        """Cycle thread: the variables were bound anew (a load, reload or cold start); the
        last deliveries go in again at the next `before_cycle`."""

    def status(self) -> IoStatus:
        """What the resource's status shows of it."""
        ...

    def points(self) -> list[IoPoint]:
        """Every point it maps, with what is on the wire now."""
        ...

    async def start(self) -> None:
        """I/O thread: listen and connect (failures are reported, never raised)."""

    async def stop(self) -> None:
        """I/O thread: stop; its ports are free when this returns."""


@dataclass(frozen=True)
class DriverKind:
    """A driver as the exchange knows it: its section of the configuration (the driver is
    made anew when that changes) and how to make it (None: the section uses nothing)."""

    name: str
    config_of: Callable[[Artifact | None], Any]
    make: Callable[[Any, DriverContext], FieldDriver | None]
