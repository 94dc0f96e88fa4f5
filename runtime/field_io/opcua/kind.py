"""OPC UA as the exchange knows it (`drivers.py`): its section of the configuration, and
its driver made only for a configuration that uses OPC UA. The driver's module is imported
then and not before: asyncua takes 0.65 s of CPU to import, which every runtime process
and tool would otherwise pay."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from runtime.contract.artifact import Artifact
from runtime.contract.opcua import OpcuaConfig
from runtime.field_io.driver import DriverContext, DriverKind, FieldDriver


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
        from runtime.field_io.opcua.driver import OpcuaDriver  # asyncua: see above

        return OpcuaDriver(config, context, options.port, options.folder)

    return DriverKind("opcua", _config_of, make)


def _config_of(artifact: Artifact | None) -> OpcuaConfig:
    found = artifact.opcua if artifact is not None else None
    return found if found is not None else OpcuaConfig()
