"""OPC UA as a field I/O driver: the resource's server and the remote servers of one
`[opcua]` configuration, between the cycle and the I/O thread.

Before a cycle the inputs the remote servers delivered go into the process image, the
writes of OPC UA clients are carried out as online writes, and what the server noticed
(listening, a login or a certificate refused) becomes events; after it the server takes a
snapshot of the exposed variables when it asked for one.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

from runtime.contract.opcua import OpcuaConfig, OpcuaDevice
from runtime.contract.protocol import IoPoint, IoStatus, ServerStatus
from runtime.contract.refusal import Refusal
from runtime.field_io.driver import DriverContext
from runtime.field_io.opcua.remote import RemoteServer
from runtime.field_io.opcua.resource_server import ResourceServer
from runtime.field_io.remote_devices import RemoteDevices
from runtime.field_io.server_and_devices import ServerAndDevices


class OpcuaDriver(ServerAndDevices):
    def __init__(
        self, config: OpcuaConfig, context: DriverContext, port: int | None, folder: Path | None
    ) -> None:
        """`port`: the server's instead of the configured one (0: any free one); `folder`:
        of the certificates (None: a temporary one)."""
        self.config, self._context = config, context
        if folder is None:  # a resource without a state folder (tests): certificates for now
            self._temporary = tempfile.TemporaryDirectory(prefix="padt-opcua-")
            folder = Path(self._temporary.name)
        self.server: ResourceServer | None = None
        if config.server is not None:
            port = port if port is not None else config.server.port
            self.server = ResourceServer(
                config.server,
                context.resource,
                folder,
                port,
                context.accounts,
            )
        outputs = lambda: context.io.outputs  # noqa: E731  # replaced, never changed
        self.remotes = [
            RemoteServer(device, outputs, folder / "client") for device in config.devices
        ]
        devices = RemoteDevices(self.remotes, context, "opcua", "OPC UA server", _device_address)
        super().__init__(self.server, devices)

    # ---- the cycle thread
    def _rebind_server(self) -> None:
        assert self.server is not None
        variables = self._context.variables
        self.server.rebind(variables.bound, variables.memory)

    def before_cycle(self) -> None:
        self._devices.before_cycle()
        server = self.server
        if server is None:
            return
        recorder = self._context.recorder
        while not server.notices.empty():
            notice = server.notices.get_nowait()
            recorder.record("io", notice.message, long_term=notice.long_term, **notice.details)
        if not server.writes.empty():
            server.take_writes(self._context.write or _no_writes)

    def after_cycle(self) -> None:
        if self.server is not None:
            self.server.after_cycle()

    # ---- what the status and the `io` command show (cycle thread)
    def status(self) -> IoStatus:
        servers = []
        server = self.server
        if server is not None:
            counts, certificate = server.counts, server.certificate
            servers.append(
                ServerStatus(
                    server.host,
                    server.port,
                    listening=server.port != 0,
                    error=server.error,
                    requests=counts.requests,
                    exceptions=counts.refused,
                    writes=counts.writes,
                    protocol="opcua",
                    sessions=counts.sessions,
                    certificate=certificate.thumbprint if certificate is not None else "",
                )
            )
        return IoStatus(None, self._devices.statuses(), servers)

    def points(self) -> list[IoPoint]:
        points = [
            _point(device, point.variable, point.location, point.type, value, quality, point.node)
            for device, point, value, quality in self._devices.point_values()
        ]
        if self.server is not None:
            for path, kind, writable, value, node in self.server.shown():
                quality = "good" if value is not None else "waiting"
                points.append(
                    _point("OPC UA server", path, "", kind, value, quality, node, writable)
                )
        return points


def _point(
    source: str, variable: str, location: str, kind: str, value: object, quality: str,
    node: str, writable: bool = False,
) -> IoPoint:  # fmt: skip
    return IoPoint(
        source, variable, location, kind, area="", address=0, writable=writable,
        value=value, quality=quality, protocol="opcua", place=node,
    )  # fmt: skip


def _device_address(device: OpcuaDevice) -> tuple[str, int, int]:
    return device.endpoint, 0, 0


def _no_writes(path: str, value: object, user: str) -> None:
    raise Refusal("read_only", "this resource takes no writes from OPC UA clients")
