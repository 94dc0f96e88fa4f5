"""Modbus TCP as a field I/O driver: the served image and the polled devices of one
`[modbus]` configuration, between the cycle and the I/O thread.

Before a cycle the inputs the devices delivered go into the process image
(`ProcessImage.set_inputs`) and the writes of Modbus clients into their variables; after it
the served points and the output image go to the server as one immutable snapshot. Neither
side waits for the other or holds a lock: every hand-over is one reference assignment or a
queue. State changes of a device (lost, connected) and of the server become events here, on
the cycle thread.
"""

from __future__ import annotations

import logging
import queue
from dataclasses import dataclass
from typing import Any

from runtime.contract.artifact import Artifact
from runtime.contract.modbus import Device, ModbusConfig, Point
from runtime.contract.protocol import IoPoint, IoStatus, ServerStatus
from runtime.contract.refusal import Refusal
from runtime.field_io.driver import DriverContext, DriverKind, FieldDriver
from runtime.field_io.modbus.image_reader import ImageReader, is_output
from runtime.field_io.modbus.image_server import ImageServer, ImageStore, ServedImage
from runtime.field_io.modbus.poller import DevicePoller
from runtime.field_io.modbus.request_meter import REQUESTS_PER_SECOND, RequestMeter
from runtime.field_io.remote_devices import RemoteDevices
from runtime.field_io.server_and_devices import ServerAndDevices


@dataclass(frozen=True)
class ModbusOptions:
    """What the runtime's command line sets: the served image's port instead of the
    configured one (0: any free one), and the requests it answers per second."""

    port: int | None = None
    requests_per_second: int = REQUESTS_PER_SECOND


def modbus_kind(options: ModbusOptions) -> DriverKind:
    def make(config: ModbusConfig, context: DriverContext) -> FieldDriver | None:
        if not config.serve and not config.devices:
            return None
        return ModbusDriver(config, context, options)

    return DriverKind("modbus", _config_of, make)


def _config_of(artifact: Artifact | None) -> ModbusConfig:
    return artifact.modbus if artifact is not None else ModbusConfig()


class ModbusDriver(ServerAndDevices):
    def __init__(
        self, config: ModbusConfig, context: DriverContext, options: ModbusOptions
    ) -> None:
        # a lost device would log a failed connection every period: what goes wrong on the
        # bus is reported as events and in the status instead
        logging.getLogger("pymodbus").setLevel(logging.CRITICAL)
        self.config, self._context = config, context
        self.server: ImageServer | None = None
        if config.serve:
            port = options.port if options.port is not None else config.port
            # outputs first, then the others: each group is read with one call per cycle
            points = sorted(config.served, key=lambda p: not is_output(p))
            meter = RequestMeter(options.requests_per_second)
            self.server = ImageServer(ImageStore(tuple(points)), config.host, port, meter)
        outputs = lambda: context.io.outputs  # noqa: E731  # replaced, never changed
        self.pollers = [DevicePoller(device, outputs) for device in config.devices]
        devices = RemoteDevices(self.pollers, context, "modbus", "Modbus device", _device_address)
        super().__init__(self.server, devices)
        self._floods = 0  # the floods of requests the meter held back, reported
        self._applied = 0  # the last client write taken
        self._server_reported = False
        self._reader = ImageReader((), context.variables)  # until `rebind`

    # ---- the cycle thread
    def _rebind_server(self) -> None:
        assert self.server is not None
        self._reader = ImageReader(self.server.store.points, self._context.variables)

    def before_cycle(self) -> None:
        if self.server is not None:
            self._take_writes(self.server.store)
            self._report_server()
            if self.server.meter.floods != self._floods:
                self._report_flood(self.server.meter)
        self._devices.before_cycle()

    def after_cycle(self) -> None:
        if self.server is None:
            return
        context = self._context
        values = self._reader.values(context.io.outputs, context.variables.globals)
        self.server.store.show(ServedImage(values, self._applied))

    def _take_writes(self, store: ImageStore) -> None:
        variables = self._context.variables
        while True:
            try:
                write = store.writes.get_nowait()
            except queue.Empty:
                return
            self._applied = write.seq
            bound = variables.find(write.variable)
            if bound is None:
                continue
            try:
                variables.store(bound, variables.checked(bound, write.value))
            except Refusal:  # a value its type cannot hold (the server checked the range)
                continue

    def _report_server(self) -> None:
        server = self.server
        if server is None or self._server_reported or not (server.port or server.error):
            return
        self._server_reported = True
        recorder = self._context.recorder
        if server.error is not None:
            recorder.record("io", f"Modbus server: {server.error}", long_term=True)
        else:
            recorder.record(
                "io", f"Modbus server listening on {server.host}:{server.port}", long_term=False
            )

    def _report_flood(self, meter: RequestMeter) -> None:
        """Once per flood (requests past the meter's rate after a quiet spell)."""
        self._floods = meter.floods
        self._context.recorder.record(
            "io",
            f"Modbus server: requests come faster than {meter.rate} a second; they are "
            "answered at that rate",
            long_term=False,
        )

    # ---- what the status and the `io` command show (cycle thread)
    def status(self) -> IoStatus:
        server = None
        if self.server is not None:
            counts = self.server.store.counts
            server = ServerStatus(
                self.server.host, self.server.port, self.server.port != 0, self.server.error,
                counts.requests, counts.exceptions, counts.writes,
            )  # fmt: skip
        devices = self._devices.statuses()
        return IoStatus(server, devices, [server] if server is not None else [])

    def points(self) -> list[IoPoint]:
        points: list[IoPoint] = []
        if self.server is not None:
            safe = not self._context.running()
            image = self.server.store.image
            for point, value in zip(self.server.store.points, image.values, strict=True):
                quality = "safe" if is_output(point) and safe else "good"
                points.append(_io_point("server", point, value, quality))
        for device, point, value, quality in self._devices.point_values():
            points.append(_io_point(device, point, value, quality))
        return points


def _device_address(device: Device) -> tuple[str, int, int]:
    return device.host, device.port, device.unit_id


def _io_point(source: str, point: Point, value: Any, quality: str) -> IoPoint:
    return IoPoint(
        source, point.variable, point.location, point.type, point.area, point.address,
        point.writable, value, quality, "modbus", f"{point.area} {point.address}",
    )  # fmt: skip
