"""OPC UA as a field I/O driver: the resource's server and the remote servers of one
`[opcua]` configuration, between the cycle and the I/O thread.

Before a cycle the writes of OPC UA clients are carried out as online writes, and what the
server noticed (listening, a login or a certificate refused) becomes events; after it the
server takes a snapshot of the exposed variables when it asked for one.
"""

from __future__ import annotations

import tempfile
from dataclasses import dataclass
from pathlib import Path

from runtime.contract.artifact import Artifact
from runtime.contract.opcua import OpcuaConfig
from runtime.contract.protocol import IoPoint, IoStatus, ServerStatus
from runtime.contract.refusal import Refusal
from runtime.field_io.driver import DriverContext, DriverKind, FieldDriver
from runtime.field_io.opcua.resource_server import ResourceServer


@dataclass(frozen=True)
class OpcuaOptions:
    """What the runtime's command line sets: the server's port instead of the configured
    one (0: any free one), and the folder of its certificates (None: a temporary one)."""

    port: int | None = None
    folder: Path | None = None


def opcua_kind(options: OpcuaOptions) -> DriverKind:
    def make(config: OpcuaConfig, context: DriverContext) -> FieldDriver | None:
        if config.server is None and not config.devices:
            return None
        return OpcuaDriver(config, context, options)

    return DriverKind("opcua", _config_of, make)


def _config_of(artifact: Artifact | None) -> OpcuaConfig:
    found = artifact.opcua if artifact is not None else None
    return found if found is not None else OpcuaConfig()


class OpcuaDriver:
    def __init__(self, config: OpcuaConfig, context: DriverContext, options: OpcuaOptions) -> None:
        self.config, self._context = config, context
        folder = options.folder
        if folder is None:  # a resource without a state folder (tests): certificates for now
            self._temporary = tempfile.TemporaryDirectory(prefix="padt-opcua-")
            folder = Path(self._temporary.name)
        self.server: ResourceServer | None = None
        if config.server is not None:
            port = options.port if options.port is not None else config.server.port
            self.server = ResourceServer(
                config.server,
                context.resource,
                folder,
                port,
                context.accounts,
                lambda: context.variables.globals,
            )
        self.bad: frozenset[str] = frozenset()

    # ---- the I/O thread
    async def start(self) -> None:
        if self.server is not None:
            await self.server.start()

    async def stop(self) -> None:
        if self.server is not None:
            await self.server.stop()

    # ---- the cycle thread
    def rebind(self) -> None:
        if self.server is not None:
            self.server.rebind(self._context.variables.bound)

    def before_cycle(self) -> None:
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
            counts = server.counts
            certificate = server.certificate.thumbprint if server.certificate is not None else ""
            servers.append(
                ServerStatus(
                    server.host,
                    server.port,
                    server.port != 0,
                    server.error,
                    counts.requests,
                    counts.refused,
                    counts.writes,
                    "opcua",
                    counts.sessions,
                    certificate,
                )
            )
        return IoStatus(None, [], servers)

    def points(self) -> list[IoPoint]:
        if self.server is None:
            return []
        return [
            IoPoint(
                "OPC UA server",
                path,
                "",
                kind,
                "",
                0,
                writable,
                value,
                "good" if value is not None else "waiting",
                "opcua",
                node,
            )
            for path, kind, writable, value, node in self.server.shown()
        ]


def _no_writes(path: str, value: object, user: str) -> None:
    raise Refusal("read_only", "this resource takes no writes from OPC UA clients")
