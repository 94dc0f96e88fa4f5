"""Field I/O: the exchange between the CPU cycle and the field I/O drivers.

Before a cycle (`before_cycle`, on the cycle thread) each driver puts what the field
delivered and what its clients wrote into the process image and the variables; after it
(`after_cycle`) each takes the values the field sees as one snapshot. The drivers' network
work runs on one I/O thread (`io_thread.py`); neither side waits for the other.

It follows the loaded configuration: a load or reload that changes a driver's section of the
configuration (`[modbus]`) stops that driver and starts one made from the new section; one
that keeps it only binds the variables anew.
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Callable
from typing import Any

from runtime.code.instances import BoundVariable
from runtime.contract.artifact import Artifact, UserAccount
from runtime.contract.protocol import DeviceStatus, IoPoint, IoStatus
from runtime.event_recorder import EventRecorder
from runtime.field_io.driver import DriverContext, FieldDriver
from runtime.field_io.drivers import driver_kinds
from runtime.field_io.io_thread import IoThread
from runtime.field_io.modbus.driver import ModbusDriver, ModbusOptions
from runtime.field_io.modbus.image_server import ImageServer
from runtime.field_io.modbus.poller import DevicePoller
from runtime.field_io.modbus.request_meter import REQUESTS_PER_SECOND
from runtime.field_io.opcua.kind import OpcuaOptions
from runtime.field_io.peer_exchange.kind import ExchangeOptions
from runtime.process_image import ProcessImage
from runtime.variables import Variables

log = logging.getLogger(__name__)


class FieldIo:
    def __init__(
        self,
        artifact: Callable[[], Artifact | None],
        variables: Variables,
        io: ProcessImage,
        recorder: EventRecorder,
        running: Callable[[], bool],
        modbus_port: int | None = None,
        modbus_rate: int = REQUESTS_PER_SECOND,
        *,
        resource: str = "resource",
        accounts: Callable[[], tuple[UserAccount, ...]] = tuple,
        write: Callable[[str, Any, str], None] | None = None,
        opcua: OpcuaOptions | None = None,
        exchange: ExchangeOptions | None = None,
    ) -> None:
        """The resource's parts it works with: the loaded configuration (`artifact`), its
        variables, process image and event recorder, and whether it runs; `modbus_port`
        overrides the configured port of the served Modbus image (0: any free one), which
        answers at most `modbus_rate` requests a second (all clients together). A server
        that logs users in takes the resource's `accounts`, and carries a client's write
        out with `write` (the online write: `runtime/online_writes.py`). `exchange`: the
        Zenoh session and key the exchange with other resources uses (none: it exchanges
        nothing)."""
        self._loaded = artifact
        self._context = DriverContext(variables, io, recorder, running, resource, accounts, write)
        self._kinds = driver_kinds(
            ModbusOptions(modbus_port, modbus_rate),
            opcua or OpcuaOptions(),
            exchange or ExchangeOptions(),
        )
        self._configs: list[Any] = [kind.config_of(None) for kind in self._kinds]
        self._drivers: list[FieldDriver | None] = [None for _ in self._kinds]  # by kind
        self._active: tuple[FieldDriver, ...] = ()  # the drivers made, in their order
        self._artifact: Artifact | None = None
        self._bound_of: list[BoundVariable] | None = None
        self._thread: IoThread | None = None
        self._switching: asyncio.Lock | None = None  # only the I/O thread's
        self.bad: frozenset[str] = frozenset()  # upper-case paths of inputs held safe

    # ---- the cycle thread
    def before_cycle(self) -> None:
        self.follow_configuration()
        bad: frozenset[str] = frozenset()
        for driver in self._active:
            driver.before_cycle()
            bad = driver.bad if not bad else bad | driver.bad
        if bad != self.bad:
            self.bad = bad

    def after_cycle(self) -> None:
        for driver in self._active:
            driver.after_cycle()

    def follow_configuration(self) -> None:
        """Serve and poll as the loaded configuration says. The first time a driver is
        made, this starts the I/O thread, which takes the calling thread's scheduling: the
        cycle driver calls it in the ordinary class after what may have changed the
        configuration, so that `before_cycle` (its cycle real-time) finds nothing to do."""
        artifact = self._loaded()
        if artifact is not self._artifact:
            self._artifact = artifact
            for index, kind in enumerate(self._kinds):
                config = kind.config_of(artifact)
                if config != self._configs[index]:
                    self._replace(index, config)
        bound = self._context.variables.bound
        if bound is not self._bound_of:  # a load, reload, cold start or program restart
            self._bound_of = bound
            for driver in self._active:
                driver.rebind()

    def _replace(self, index: int, config: Any) -> None:
        """The driver made from `config` in place of the one that ran: the old one stops,
        then the new one starts, on the I/O thread (the cycle does not wait for either)."""
        old = self._drivers[index]
        new = self._kinds[index].make(config, self._context)
        self._drivers[index], self._configs[index] = new, config
        self._active = tuple(driver for driver in self._drivers if driver is not None)
        self._bound_of = None  # the new driver binds the variables below
        if self._thread is None and new is not None:
            self._thread = IoThread()
        if self._thread is not None:
            self._thread.submit(self._switch(old, new))

    async def _switch(self, old: FieldDriver | None, new: FieldDriver | None) -> None:
        """On the I/O thread, one switch after the other: what ran stops (its port is free
        again) before what is new starts."""
        if self._switching is None:
            self._switching = asyncio.Lock()
        async with self._switching:
            if old is not None:
                await old.stop()
            if new is not None:
                await new.start()

    # ---- what the status and the `io` command show (cycle thread)
    def status(self) -> IoStatus | None:
        statuses = [driver.status() for driver in self._active]
        if not statuses:
            return None
        servers = [server for s in statuses for server in s.servers]
        devices: list[DeviceStatus] = [d for s in statuses for d in s.devices]
        modbus = next((s for s in servers if s.protocol == "modbus"), None)
        return IoStatus(modbus, devices, servers)

    def points(self) -> list[IoPoint]:
        return [point for driver in self._active for point in driver.points()]

    # ---- the Modbus driver's parts, which tests and benches look at
    @property
    def server(self) -> ImageServer | None:
        modbus = self._modbus()
        return modbus.server if modbus is not None else None

    @property
    def pollers(self) -> list[DevicePoller]:
        modbus = self._modbus()
        return modbus.pollers if modbus is not None else []

    def _modbus(self) -> ModbusDriver | None:
        return next((d for d in self._active if isinstance(d, ModbusDriver)), None)

    def close(self) -> None:
        if self._thread is None:
            return
        try:
            self._thread.run(self._stop_all())
        except Exception:  # shutting down: what is left goes with the process
            log.exception("field I/O shutdown")
        self._thread.close()

    async def _stop_all(self) -> None:
        for driver in self._active:
            await self._switch(driver, None)
