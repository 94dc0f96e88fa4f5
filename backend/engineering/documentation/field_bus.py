"""The field bus of the resource: the Modbus TCP maps (docs/modbus.md), the OPC UA server
and remote servers (docs/opcua.md) and the variables exchanged with other resources
(docs/exchange.md), as the configuration says them."""

from __future__ import annotations

from backend.engineering.documentation.markup import code, escape, table
from runtime.contract.artifact import Artifact
from runtime.contract.exchange import ExchangeConfig
from runtime.contract.keyspace import exchange_key
from runtime.contract.modbus import ModbusConfig, Point
from runtime.contract.opcua import OpcuaConfig, OpcuaDevice

_SECURITY = {"none": "no security", "sign": "Basic256Sha256, signed",
             "sign_encrypt": "Basic256Sha256, signed and encrypted"}  # fmt: skip


def field_bus(artifact: Artifact) -> str:
    return (
        _modbus(artifact.modbus)
        + _opcua(artifact.opcua)
        + _exchange(artifact.resource.name, artifact.exchange)
    )


def _modbus(modbus: ModbusConfig) -> str:
    """The Modbus TCP maps (docs/modbus.md): the served image and every remote device."""
    if not modbus.serve and not modbus.devices:
        return "<h3>Field bus (Modbus TCP)</h3><p>The configuration uses no Modbus TCP.</p>"
    parts = ["<h3>Field bus (Modbus TCP)</h3>"]
    if modbus.serve:
        parts.append(
            f"<p>The process image is served on {code(f'{modbus.host}:{modbus.port}')} "
            "(the port can be moved when the runtime starts). In STOP and ERROR STOP the "
            "outputs are served at their safe values.</p>"
            + _points_table(modbus.served, served=True)
        )
    else:
        parts.append("<p>The process image is not served.</p>")
    for device in modbus.devices:
        parts.append(
            f"<h4>Remote device {escape(device.name)}</h4><p>{code(f'{device.host}:{device.port}')}"
            f" unit {device.unit_id}, polled every {device.period_ms} ms, lost after "
            f"{device.timeout_ms} ms without an answer (its inputs then take their safe "
            "values).</p>" + _points_table(device.points, served=False)
        )
    return "".join(parts)


def _points_table(points: tuple[Point, ...], served: bool) -> str:
    rows = [
        [
            escape(point.area.replace("_", " ")),
            str(point.address),
            code(point.location),
            escape(point.variable),
            escape(point.type),
            escape(f"{point.byte_order}/{point.word_order}"),
            ("yes" if point.writable else "") if served else escape(_shown(point.safe_value)),
        ]
        for point in points
    ]
    last = "writable" if served else "safe value"
    head = ["table", "address", "location", "variable", "type", "byte/word order", last]
    return table(head, rows)


def _shown(value: bool | int | float | str) -> str:
    return str(value).upper() if isinstance(value, bool) else str(value)


def _opcua(opcua: OpcuaConfig | None) -> str:
    """The OPC UA server and every remote server (docs/opcua.md)."""
    if opcua is None:
        return ""
    parts = ["<h3>OPC UA</h3>"]
    server = opcua.server
    if server is not None:
        anonymous = "anonymous sessions may read" if server.anonymous else "no anonymous sessions"
        trust = (
            "any client certificate is trusted"
            if server.trust_unknown_clients
            else "client certificates are trusted by hand"
        )
        # each path once, sorted: exposed ones, and writable ones below them
        writable = {path.upper() for path in server.writable}
        paths = {path.upper(): path for path in (*server.exposed, *server.writable)}
        rows = [
            [code(path), "yes" if upper in writable else ""]
            for upper, path in sorted(paths.items())
        ]
        parts.append(
            f"<p>Served on {code(f'opc.tcp://{server.host}:{server.port}')} (the port can be "
            "moved when the runtime starts), Basic256Sha256 signed or signed and encrypted, "
            f"users of the resource's accounts ({anonymous}; {trust}); operators and above "
            "write what is writable, as online writes.</p>"
            + table(["variables (each with everything below it)", "writable"], rows)
        )
    else:
        parts.append("<p>Nothing is served over OPC UA.</p>")
    for device in opcua.devices:
        parts.append(_remote_server(device))
    return "".join(parts)


def _remote_server(device: OpcuaDevice) -> str:
    user = f"as user {escape(device.user)}" if device.user else "anonymously"
    how = "subscribed" if device.mode == "subscribe" else "read"
    rows = [
        [
            code(point.location),
            escape(point.variable),
            escape(point.type),
            code(point.node),
            escape(_shown(point.safe_value)) if point.is_input else "",
        ]
        for point in device.points
    ]
    return (
        f"<h4>Remote OPC UA server {escape(device.name)}</h4><p>{code(device.endpoint)}, "
        f"{_SECURITY.get(device.security, escape(device.security))}, {user}; inputs {how} "
        f"every {device.period_ms} ms, lost after {device.timeout_ms} ms without an answer "
        "(its inputs then take their safe values).</p>"
        + table(["location", "variable", "type", "node", "safe value"], rows)
    )


def _exchange(resource: str, exchange: ExchangeConfig | None) -> str:
    """What the resource publishes to other resources and takes from them."""
    if exchange is None:
        return ""
    parts = ["<h3>Exchange with other resources</h3>"]
    for publication in exchange.publications:
        rows = [[escape(v.variable), escape(v.type)] for v in publication.variables]
        parts.append(
            f"<h4>Publication {escape(publication.name)}</h4><p>On "
            f"{code(exchange_key(resource, publication.name))} every {publication.period_ms} "
            "ms, signed with the resource's key.</p>" + table(["variable", "type"], rows)
        )
    for subscription in exchange.subscriptions:
        rows = [
            [
                escape(point.variable),
                escape(point.type),
                escape(point.source),
                escape(_shown(point.safe_value)),
            ]
            for point in subscription.points
        ]
        parts.append(
            f"<h4>From {escape(subscription.name)}</h4><p>Publication "
            f"{code(exchange_key(subscription.resource, subscription.publication))}; stale "
            f"after {subscription.timeout_ms} ms without a message, or at once when its "
            "resource does not run (the variables then take their safe values).</p>"
            + table(["variable", "type", "from", "safe value"], rows)
        )
    return "".join(parts)
