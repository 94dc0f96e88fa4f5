"""The remote devices of one driver on the cycle thread: what they delivered into the
process image, their state changes as events, the inputs of lost ones in `bad`, and what
the status shows of them. Every client driver (Modbus devices, remote OPC UA servers) has
one; each device does its network work on the I/O thread (`run`) and hands over one
immutable `Delivery` at a time.
"""

from __future__ import annotations

import asyncio
from collections.abc import Callable, Iterator, Sequence
from typing import Any, Protocol

from runtime.contract.protocol import DeviceStatus
from runtime.field_io.delivery import Delivery
from runtime.field_io.driver import DriverContext


class MappedPoint(Protocol):
    @property
    def variable(self) -> str: ...
    @property
    def is_input(self) -> bool: ...
    @property
    def input_safe_value(self) -> Any: ...


class NamedDevice(Protocol):
    @property
    def name(self) -> str: ...
    @property
    def points(self) -> Sequence[MappedPoint]: ...


class RemoteDevice(Protocol):
    """What the cycle reads of a device (written on the I/O thread, the delivery before
    the state)."""

    @property
    def device(self) -> NamedDevice: ...

    state: str  # connecting | connected | lost
    delivery: Delivery
    sent: dict[str, Any]  # output values the device took
    last_error: str | None
    requests: int
    failures: int
    round_trip_ms: float

    async def run(self) -> None: ...


_NONE = object()  # no value delivered before

# a device's address as the status shows it: (host or endpoint, port, Modbus unit)
Address = Callable[[Any], tuple[str, int, int]]


class RemoteDevices:
    def __init__(
        self,
        devices: Sequence[RemoteDevice],
        context: DriverContext,
        protocol: str,
        label: str,
        address: Address,
        only_changes: bool = False,
    ) -> None:
        """`label` names a device in events ("Modbus device", "OPC UA server");
        `only_changes`: a delivery stores only the values that differ from those the
        devices delivered before (a subscription of the exchange between resources brings
        a thousand values a message, most of them the same each time: storing them all
        would cost the cycle milliseconds). The first delivery after a (re)bind stores
        all."""
        self.devices = devices
        self._context, self._protocol, self._label, self._address = (
            context,
            protocol,
            label,
            address,
        )
        self._seen: dict[str, tuple[int, str]] = {}  # device -> (delivery seq, state) taken
        self._only_changes = only_changes
        self._given: dict[str, dict[str, Any]] = {}  # device -> the values stored last
        self._tasks: list[asyncio.Task[None]] = []  # the I/O thread's
        self.bad: frozenset[str] = frozenset()  # upper-case paths of inputs of lost devices

    # ---- the I/O thread
    def start(self) -> None:
        self._tasks = [asyncio.create_task(device.run()) for device in self.devices]

    async def stop(self) -> None:
        for task in self._tasks:
            task.cancel()
        await asyncio.gather(*self._tasks, return_exceptions=True)

    # ---- the cycle thread
    def rebind(self) -> None:
        # fresh instances hold initial values: the inputs the devices delivered last go
        # in again at once, not a period later
        self._seen = {name: (0, state) for name, (_, state) in self._seen.items()}
        self._given = {}

    def before_cycle(self) -> None:
        io = self._context.io
        bad: set[str] = set()
        for device in self.devices:
            # a device writes its delivery before its state: read in the other order, a
            # state seen comes with its delivery
            state = device.state
            delivery = device.delivery
            name = device.device.name
            seen = self._seen.get(name, (0, "connecting"))
            if delivery.seq != seen[0]:
                io.set_inputs(self._changes(name, delivery.values))
            if state != seen[1]:
                self._report(device, state, seen[1])
            self._seen[name] = (delivery.seq, state)
            if not delivery.good:
                bad.update(variable.upper() for variable in delivery.values)
        if bad != self.bad:
            self.bad = frozenset(bad)

    def _changes(self, device: str, values: dict[str, Any]) -> dict[str, Any]:
        if not self._only_changes:
            return values
        before = self._given.get(device)
        self._given[device] = values  # a delivery's values are never changed after
        if before is None:
            return values
        return {path: value for path, value in values.items() if before.get(path, _NONE) != value}

    def _report(self, device: RemoteDevice, state: str, before: str) -> None:
        name, recorder = device.device.name, self._context.recorder
        if state == "lost":
            recorder.record(
                "io", f"{self._label} {name} lost: {device.last_error}; its inputs hold "
                "their safe values", long_term=True, device=name,
            )  # fmt: skip
        elif state == "connected":
            again = " again" if before == "lost" else ""
            recorder.record(
                "io", f"{self._label} {name} connected{again}", long_term=bool(again),
                device=name,
            )  # fmt: skip

    def point_values(self) -> Iterator[tuple[str, Any, Any, str]]:
        """(device name, point, value, quality) of every mapped point: an input as
        delivered (good) or its safe value (bad: its device lost), an output as the device
        took it (good) or not taken yet (bad)."""
        for device in self.devices:
            delivery, sent = device.delivery, device.sent
            for point in device.device.points:
                if point.is_input:
                    value = delivery.values.get(point.variable, point.input_safe_value)
                    quality = "good" if delivery.good else "bad"
                else:
                    value = sent.get(point.variable)
                    quality = "good" if point.variable in sent else "bad"
                yield device.device.name, point, value, quality

    def statuses(self) -> list[DeviceStatus]:
        return [self._status(device) for device in self.devices]

    def _status(self, device: RemoteDevice) -> DeviceStatus:
        host, port, unit = self._address(device.device)
        name = device.device.name
        # the state the cycle has taken, with its inputs: a status that says "lost" comes
        # after the safe values are in the process image
        state = self._seen.get(name, (0, "connecting"))[1]
        return DeviceStatus(
            name, host, port, unit, state, device.last_error, device.requests,
            device.failures, round(device.round_trip_ms, 3), self._protocol,
        )  # fmt: skip
