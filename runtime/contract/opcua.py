"""OPC UA in the artifact: the server that shows the resource's variables to SCADA, HMI,
historians and MES, and the remote servers the resource reads inputs from and writes
outputs to as a client (docs/opcua.md).

The compiler checks a project's `[opcua]` settings and writes what it found here; the
runtime serves and connects exactly that.

- **The server** shows the variables the project exposes, by path: a program instance, a
  function block instance, a structure or a global names everything below it. Each is
  read-only unless it is also named writable; a writable variable is written by a user of
  level operator or above, as an online write is, with its checks and its event.
- **A remote server** (a device, as on Modbus) delivers located inputs (`%I`) and takes
  located outputs (`%Q`), each mapped to one node of it. Lost, its inputs hold their safe
  values.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from runtime.contract.values import ValueRejected, representation

DEFAULT_HOST = "127.0.0.1"
DEFAULT_PORT = 4840
# what a remote server's channel uses; the server offers Basic256Sha256 sign and
# sign & encrypt, never None
SECURITY = ("none", "sign", "sign_encrypt")
MODES = ("subscribe", "read")  # how a remote server's inputs come: monitored items or polls


@dataclass(frozen=True)
class OpcuaServer:
    """The served address space and who may reach it."""

    host: str = DEFAULT_HOST
    port: int = DEFAULT_PORT
    # variable paths as declared (`TankControl`, `TankControl.valve`, `gLevel`), sorted:
    # each exposes itself and everything below it
    exposed: tuple[str, ...] = ()
    writable: tuple[str, ...] = ()  # within `exposed`, sorted
    # the declaration's comment of an exposed path (an object or a variable), by path, sorted
    descriptions: tuple[tuple[str, str], ...] = ()
    anonymous: bool = False  # anonymous sessions may read (never write)
    # a client whose certificate nobody trusted yet is let in (else it lands in the
    # rejected certificates, to be trusted by hand)
    trust_unknown_clients: bool = False


@dataclass(frozen=True)
class OpcuaPoint:
    """A located global mapped to a node of a remote server."""

    variable: str  # the global's name, as declared
    location: str  # `%IW0`
    type: str  # its elementary type
    node: str  # the node's id as text: `ns=2;s=Tank1.TankControl.level`, `i=2258`
    safe_value: bool | int | float | str = 0  # an input's value while its server is lost

    @property
    def is_input(self) -> bool:
        return self.location.upper().startswith("%I")

    @property
    def input_safe_value(self) -> Any:
        """The safe value as the variable holds it (`opcua_config` checked that it fits)."""
        return representation(self.type, self.safe_value)


@dataclass(frozen=True)
class OpcuaDevice:
    """A remote OPC UA server the resource reaches as a client."""

    name: str
    endpoint: str  # opc.tcp://host:port[/path]
    security: str = "sign_encrypt"  # one of SECURITY, with Basic256Sha256
    user: str = ""  # "": an anonymous session
    # the file on the runtime's host that holds the user's password (mode 0600): a password
    # is never in the project or on the bus
    password_file: str = ""
    mode: str = "subscribe"  # one of MODES
    period_ms: int = 100  # the sampling and publishing interval, or the polling period
    timeout_ms: int = 1000  # no answer for this long: the server is lost
    points: tuple[OpcuaPoint, ...] = ()


@dataclass(frozen=True)
class OpcuaConfig:
    """What a resource does over OPC UA."""

    server: OpcuaServer | None = None  # None: nothing served
    devices: tuple[OpcuaDevice, ...] = ()


def opcua_config(data: dict[str, Any]) -> OpcuaConfig:
    """The artifact's `opcua` object back into its dataclasses (KeyError, TypeError when
    it is incomplete or of the wrong types)."""
    server = data["server"]
    return OpcuaConfig(
        server=_server(server) if server is not None else None,
        devices=tuple(_device(d) for d in data["devices"]),
    )


def _server(data: dict[str, Any]) -> OpcuaServer:
    server = OpcuaServer(
        host=_text(data["host"]),
        port=_number(data["port"]),
        exposed=tuple(_text(path) for path in data["exposed"]),
        writable=tuple(_text(path) for path in data["writable"]),
        descriptions=tuple((_text(path), _text(text)) for path, text in data["descriptions"]),
        anonymous=_flag(data["anonymous"]),
        trust_unknown_clients=_flag(data["trust_unknown_clients"]),
    )
    return server


def _device(data: dict[str, Any]) -> OpcuaDevice:
    device = OpcuaDevice(**{**data, "points": tuple(_point(p) for p in data["points"])})
    for name in ("name", "endpoint", "security", "user", "password_file", "mode"):
        _text(getattr(device, name))
    _number(device.period_ms), _number(device.timeout_ms)
    if device.security not in SECURITY or device.mode not in MODES:
        raise TypeError(f"OPC UA device '{device.name}': unknown security or mode")
    return device


def _point(data: dict[str, Any]) -> OpcuaPoint:
    point = OpcuaPoint(**data)
    for name in ("variable", "location", "type", "node"):
        _text(getattr(point, name))
    if point.is_input:
        try:
            point.input_safe_value  # noqa: B018 (checked here, so that a driver never raises)
        except ValueRejected as exc:
            raise TypeError(f"the safe value of OPC UA point '{point.variable}': {exc}") from None
    return point


def _text(value: Any) -> str:
    if not isinstance(value, str):
        raise TypeError(f"{value!r} in the OPC UA configuration is not text")
    return value


def _number(value: Any) -> int:
    if type(value) is not int:
        raise TypeError(f"{value!r} in the OPC UA configuration is not a whole number")
    return value


def _flag(value: Any) -> bool:
    if type(value) is not bool:
        raise TypeError(f"{value!r} in the OPC UA configuration is not true or false")
    return value
