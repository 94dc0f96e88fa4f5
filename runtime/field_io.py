"""Field I/O over Modbus TCP: the exchange between the CPU cycle and the Modbus thread.

Before a cycle (`before_cycle`, on the cycle thread) the inputs the devices delivered go
into the process image (`ProcessImage.set_inputs`) and the writes of Modbus clients into
their variables; after it (`after_cycle`) the served points and the output image go to the
Modbus thread as one immutable snapshot. Neither side waits for the other or holds a lock:
every hand-over is one reference assignment or a queue. State changes of a device (lost,
connected) and of the server become events here, on the cycle thread.

It follows the loaded configuration: a load or reload that changes the `modbus` settings
restarts the server and the pollers; one that keeps them only binds the variables anew.
"""

from __future__ import annotations

import asyncio
import logging
import operator
import queue
from collections.abc import Callable
from typing import Any

from runtime.contract.artifact import Artifact
from runtime.contract.modbus import ModbusConfig, Point
from runtime.contract.protocol import DeviceStatus, IoPoint, IoStatus, ModbusServerStatus
from runtime.contract.refusal import Refusal
from runtime.event_recorder import EventRecorder
from runtime.instances import BoundVariable
from runtime.modbus_client import DevicePoller
from runtime.modbus_loop import ModbusLoop
from runtime.modbus_meter import REQUESTS_PER_SECOND, RequestMeter
from runtime.modbus_server import ImageServer, ImageStore, ServedImage
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
        port: int | None = None,
        requests_per_second: int = REQUESTS_PER_SECOND,
    ) -> None:
        """The resource's parts it works with: the loaded configuration (`artifact`), its
        variables, process image and event recorder, and whether it runs; `port` overrides
        the configured port of the served image (0: any free one); the served image answers
        at most `requests_per_second` (all clients together)."""
        self._loaded, self._variables, self._io = artifact, variables, io
        self._recorder, self._running_now = recorder, running
        self._port = port
        self._requests_per_second = requests_per_second
        self._floods = 0  # the floods of requests the meter held back, reported
        self._loop: ModbusLoop | None = None
        self._artifact: Artifact | None = None
        self.config = ModbusConfig()
        self.server: ImageServer | None = None
        self.pollers: list[DevicePoller] = []
        # what runs on the Modbus thread (only that thread touches these three)
        self._running: tuple[ImageServer | None, list[asyncio.Task[None]]] = (None, [])
        self._switching: asyncio.Lock | None = None
        self._reader = ImageReader((), self._variables)
        self._bound_of: list[BoundVariable] | None = None
        self._applied = 0  # the last client write taken
        self._seen: dict[str, tuple[int, str]] = {}  # device -> (delivery seq, state) taken
        self._server_reported = False
        self.bad: frozenset[str] = frozenset()  # upper-case paths of inputs of lost devices

    # ---- the cycle thread
    def before_cycle(self) -> None:
        self.follow_configuration()
        if self.server is not None:
            self._take_writes(self.server.store)
            self._report_server()
            if self.server.meter.floods != self._floods:
                self._report_flood(self.server.meter)
        io = self._io
        bad: set[str] = set()
        for poller in self.pollers:
            # the poller writes its delivery before its state: read in the other order, a
            # state seen comes with its delivery
            state = poller.state
            delivery = poller.delivery
            seen = self._seen.get(poller.device.name, (0, "connecting"))
            if delivery.seq != seen[0]:
                io.set_inputs(delivery.values)
            if state != seen[1]:
                self._report_device(poller, state, seen[1])
            self._seen[poller.device.name] = (delivery.seq, state)
            if not delivery.good:
                bad.update(name.upper() for name in delivery.values)
        if bad != self.bad:
            self.bad = frozenset(bad)

    def after_cycle(self) -> None:
        if self.server is None:
            return
        values = self._reader.values(self._io.outputs, self._variables.globals)
        self.server.store.show(ServedImage(values, self._applied))

    def _take_writes(self, store: ImageStore) -> None:
        variables = self._variables
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

    def follow_configuration(self) -> None:
        """Serve and poll as the loaded configuration says. The first time it serves or
        polls, this starts the Modbus thread, which takes the calling thread's scheduling:
        the cycle driver calls it in the ordinary class after what may have changed the
        configuration, so that `before_cycle` (its cycle real-time) finds nothing to do."""
        artifact = self._loaded()
        if artifact is not self._artifact:
            self._artifact = artifact
            config = artifact.modbus if artifact is not None else ModbusConfig()
            if config != self.config:
                self._restart(config)
        bound = self._variables.bound
        if bound is not self._bound_of:  # a load, reload, cold start or program restart
            self._bound_of = bound
            # fresh instances hold initial values: the inputs the devices delivered last go
            # in again at once, not a poll period later
            self._seen = {name: (0, state) for name, (_, state) in self._seen.items()}
            if self.server is not None:
                self._reader = ImageReader(self.server.store.points, self._variables)

    def _restart(self, config: ModbusConfig) -> None:
        """Stop what serves and polls now, then start what `config` says, on the Modbus
        thread (the cycle does not wait for either)."""
        self.config, self.server, self.pollers = config, None, []
        self._seen, self._server_reported, self.bad = {}, False, frozenset()
        self._floods = 0
        self._bound_of = None
        if config.serve:
            port = self._port if self._port is not None else config.port
            # outputs first, then the others: each group is read with one call per cycle
            points = sorted(config.served, key=lambda p: not _is_output(p))
            meter = RequestMeter(self._requests_per_second)
            self.server = ImageServer(ImageStore(tuple(points)), config.host, port, meter)
        outputs = lambda: self._io.outputs  # noqa: E731  # replaced, never changed
        self.pollers = [DevicePoller(device, outputs) for device in config.devices]
        if self._loop is None and (self.server is not None or self.pollers):
            self._loop = ModbusLoop()
        if self._loop is not None:
            self._loop.submit(self._switch(self.server, self.pollers))

    async def _switch(self, server: ImageServer | None, pollers: list[DevicePoller]) -> None:
        """On the Modbus thread, one switch after the other: what ran stops (its port is
        free again) before what is new starts."""
        if self._switching is None:
            self._switching = asyncio.Lock()
        async with self._switching:
            old_server, old_tasks = self._running
            for task in old_tasks:
                task.cancel()
            await asyncio.gather(*old_tasks, return_exceptions=True)
            if old_server is not None:
                await old_server.stop()
            if server is not None:
                await server.start()
            self._running = (server, [asyncio.create_task(p.run()) for p in pollers])

    def _report_server(self) -> None:
        server = self.server
        if server is None or self._server_reported or not (server.port or server.error):
            return
        self._server_reported = True
        recorder = self._recorder
        if server.error is not None:
            recorder.record("io", f"Modbus server: {server.error}", long_term=True)
        else:
            recorder.record(
                "io", f"Modbus server listening on {server.host}:{server.port}", long_term=False
            )

    def _report_flood(self, meter: RequestMeter) -> None:
        """Once per flood (requests past the meter's rate after a quiet spell)."""
        self._floods = meter.floods
        self._recorder.record(
            "io",
            f"Modbus server: requests come faster than {meter.rate} a second; they are "
            "answered at that rate",
            long_term=False,
        )

    def _report_device(self, poller: DevicePoller, state: str, before: str) -> None:
        device, recorder = poller.device, self._recorder
        if state == "lost":
            recorder.record(
                "io", f"Modbus device {device.name} lost: {poller.last_error}; "
                "its inputs hold their safe values", long_term=True, device=device.name,
            )  # fmt: skip
        elif state == "connected":
            again = " again" if before == "lost" else ""
            recorder.record(
                "io", f"Modbus device {device.name} connected{again}", long_term=bool(again),
                device=device.name,
            )  # fmt: skip

    # ---- what the status and the `io` command show (cycle thread)
    def status(self) -> IoStatus | None:
        if self.server is None and not self.pollers:
            return None
        server = None
        if self.server is not None:
            counts = self.server.store.counts
            server = ModbusServerStatus(
                self.server.host, self.server.port, self.server.port != 0, self.server.error,
                counts.requests, counts.exceptions, counts.writes,
            )  # fmt: skip
        devices = [
            DeviceStatus(
                p.device.name,
                p.device.host,
                p.device.port,
                p.device.unit_id,
                # the state the cycle has taken, with its inputs: a status that says
                # "lost" comes after the safe values are in the process image
                self._seen.get(p.device.name, (0, "connecting"))[1],
                p.last_error,
                p.requests,
                p.failures,
                round(p.round_trip_ms, 3),
            )
            for p in self.pollers
        ]
        return IoStatus(server, devices)

    def points(self) -> list[IoPoint]:
        points: list[IoPoint] = []
        if self.server is not None:
            safe = not self._running_now()
            image = self.server.store.image
            for point, value in zip(self.server.store.points, image.values, strict=True):
                output = _is_output(point)
                quality = "safe" if output and safe else "good"
                points.append(_io_point("server", point, value, quality))
        for poller in self.pollers:
            delivery = poller.delivery
            for point in poller.device.points:
                if point.is_input:
                    value = delivery.values.get(point.variable, point.input_safe_value)
                    quality = "good" if delivery.good else "bad"
                else:
                    value = poller.sent.get(point.variable)
                    quality = "good" if point.variable in poller.sent else "bad"
                points.append(_io_point(poller.device.name, point, value, quality))
        return points

    def close(self) -> None:
        if self._loop is None:
            return
        try:
            self._loop.run(self._switch(None, []))
        except Exception:  # shutting down: what is left goes with the process
            log.exception("Modbus shutdown")
        self._loop.close()


def _is_output(point: Point) -> bool:
    return point.location.upper().startswith("%Q")


class ImageReader:
    """The values of the served points after a cycle, in the store's order (outputs
    first): outputs from the output image (safe in STOP), the others from the globals,
    each group with one C-level getter call, not a Python loop over 1,000 points."""

    def __init__(self, points: tuple[Point, ...], variables: Variables) -> None:
        self._variables = variables
        self._points = points
        outputs = [p.variable for p in points if _is_output(p)]
        others = [p for p in points if not _is_output(p)]
        self._outputs = operator.itemgetter(*outputs) if outputs else None
        self._single_output = len(outputs) == 1
        bound = [variables.find(p.variable) for p in others]
        simple = all(b is not None and b.program is None and len(b.path.attrs) == 1 for b in bound)
        attrs = [str(b.path.attrs[0]) for b in bound if b is not None] if simple else []
        self._others = operator.attrgetter(*attrs) if attrs else None
        self._single_other = len(attrs) == 1
        self._bound = bound
        self._other_points = others

    def values(self, outputs: dict[str, Any], globals_: Any) -> tuple[Any, ...]:
        head = self._output_values(outputs)
        if self._others is not None:
            tail = self._others(globals_)
            return (*head, *((tail,) if self._single_other else tail))
        read = self._variables.read
        return (*head, *(
            read(b) if b is not None else p.safe_value
            for p, b in zip(self._other_points, self._bound, strict=True)
        ))  # fmt: skip

    def _output_values(self, outputs: dict[str, Any]) -> tuple[Any, ...]:
        if self._outputs is None:
            return ()
        try:
            found = self._outputs(outputs)
        except KeyError:  # no output image yet
            served = (p for p in self._points if _is_output(p))
            return tuple(outputs.get(p.variable, p.safe_value) for p in served)
        return (found,) if self._single_output else tuple(found)


def _io_point(source: str, point: Point, value: Any, quality: str) -> IoPoint:
    return IoPoint(
        source, point.variable, point.location, point.type, point.area, point.address,
        point.writable, value, quality,
    )  # fmt: skip
