"""`padt start`, `stop`, `status`, `freeze`, `step`, `unfreeze` and `params`: operating a
running resource and its programs (docs/cli.md)."""

from __future__ import annotations

import argparse
import json
from typing import Any

from padt.online import resource_client, run, table
from runtime.contract import protocol as p
from runtime.contract.wire import encode


def _program_state(status: p.Status, program: str) -> str:
    for entry in status.programs:
        if entry.name.upper() == program.upper():
            return entry.state
    return "?"


def _start_stop(args: argparse.Namespace, name: str) -> int:
    def body() -> int:
        with resource_client(args) as client:
            if args.program is None:
                command: p.Command[p.StatusReply] = p.Start() if name == "start" else p.Stop()
                print(f"resource {args.resource}: {client.ask(command).status.state}")
            else:
                program = p.StartProgram if name == "start" else p.StopProgram
                status = client.ask(program(args.program)).status
                print(f"program {args.program}: {_program_state(status, args.program)}")
        return 0

    return run(name, args, body)


def start(args: argparse.Namespace) -> int:
    return _start_stop(args, "start")


def stop(args: argparse.Namespace) -> int:
    return _start_stop(args, "stop")


def _ms(value: float) -> str:
    return f"{value:.3f} ms"


def status_lines(status: p.Status) -> list[str]:
    """A resource status for people: state, configuration, cycle statistics, programs."""
    lines = [f"resource {status.resource}: {status.state}"]
    if status.host is not None or status.zenoh_id is not None:
        lines.append(f"host {status.host or '-'}, Zenoh session {status.zenoh_id or '-'}")
    if status.error:
        lines.append(f"error: {status.error}")
    if status.crc is None:
        lines.append("configuration: none loaded")
    else:
        lines.append(f"configuration CRC {status.crc}, project {status.project}")
    stats = status.stats
    lines.append(
        f"cycle {status.cycle}: last {_ms(stats.last_ms)}, min {_ms(stats.min_ms)}, "
        f"max {_ms(stats.max_ms)}, mean {_ms(stats.mean_ms)}"
    )
    lines.append(
        f"period {_ms(stats.period_ms)}, largest jitter {_ms(stats.jitter_max_ms)}, "
        f"{stats.overruns} overruns"
    )
    lines.append(f"start: {status.start or '-'}, forcing: {'on' if status.forcing else 'off'}")
    if status.programs:
        rows = [
            [
                x.name,
                str(x.id),
                str(x.priority),
                x.state if x.paused_at is None else f"{x.state} at {x.paused_at}",
                str(x.cycles),
                x.crc,
                x.error or "",
            ]
            for x in status.programs
        ]
        lines += table(["program", "id", "priority", "state", "cycles", "crc", "error"], rows)
    return lines + io_lines(status.io)


def io_lines(io: p.IoStatus | None) -> list[str]:
    """Field I/O: each server (Modbus TCP, OPC UA, a publication of the exchange between
    resources) and each remote device (a subscription of the exchange is one)."""
    if io is None:
        return []
    lines = [_server_line(server) for server in io.servers]
    if io.devices:
        rows = [
            [d.name, _device_address(d), str(d.unit_id) if d.protocol == "modbus" else "",
             d.state, str(d.requests), str(d.failures), _ms(d.round_trip_ms), d.last_error or ""]
            for d in io.devices
        ]  # fmt: skip
        header = ["device", "address", "unit", "state", "requests", "failures", "round trip"]
        lines += table([*header, "last error"], rows)
    return lines


def _server_line(server: p.ServerStatus) -> str:
    if server.protocol == "zenoh":
        failed = f" (the last put failed: {server.error})" if server.error else ""
        return f"Exchange publication {server.host}: {server.requests} messages put{failed}"
    if server.protocol == "opcua":
        where = (
            f"opc.tcp://{server.host}:{server.port}"
            if server.listening
            else f"not listening ({server.error or 'starting'})"
        )
        return (
            f"OPC UA server {where}: {server.sessions} sessions, {server.requests} requests, "
            f"{server.exceptions} refused, {server.writes} writes; certificate SHA-1 "
            f"{server.certificate or '-'}"
        )
    where = (
        f"{server.host}:{server.port}"
        if server.listening
        else f"not listening ({server.error or 'starting'})"
    )
    return (
        f"Modbus server {where}: {server.requests} requests, {server.exceptions} "
        f"exception responses, {server.writes} writes"
    )


def _device_address(device: p.DeviceStatus) -> str:
    if device.protocol in ("opcua", "zenoh"):  # an endpoint URL, a publication's key
        return device.host
    return f"{device.host}:{device.port}"


def point_lines(points: list[p.IoPoint]) -> list[str]:
    """Every mapped point with what is on the wire now; `place` is where on the bus (a
    Modbus table and address, an OPC UA node id)."""
    rows = [
        [x.source.replace(" ", "_"), x.variable, x.location or "-", x.type, x.place,
         "yes" if x.writable else "", json.dumps(x.value), x.quality]
        for x in points
    ]  # fmt: skip
    header = ["source", "variable", "location", "type", "place", "writable"]
    return table([*header, "value", "quality"], rows)


def status(args: argparse.Namespace) -> int:
    def body() -> int:
        with resource_client(args) as client:
            current = client.ask(p.GetStatus()).status
            points = client.ask(p.GetIo()).points if args.io else None
        if args.json:
            shown: dict[str, Any] = encode(current)
            if points is not None:
                shown["points"] = encode(points)
            print(json.dumps(shown, indent=2, sort_keys=True))
            return 0
        print("\n".join(status_lines(current)))
        if points:
            print("\n".join(point_lines(points)))
        return 0

    return run("status", args, body)


def single_step(args: argparse.Namespace) -> int:
    """`freeze`, `step` (`--cycles N` program cycles) and `unfreeze` of one program."""

    def body() -> int:
        with resource_client(args) as client:
            if args.verb == "freeze":
                current = client.ask(p.Freeze(args.program)).status
            elif args.verb == "unfreeze":
                current = client.ask(p.Unfreeze(args.program)).status
            else:
                step = p.StepProgram(args.program, args.interval_ms)
                current = client.ask(step).status
                for _ in range(args.cycles - 1):
                    current = client.ask(step).status
        shown = next(x for x in current.programs if x.name.upper() == args.program.upper())
        print(f"program {shown.name}: {shown.state}, {shown.cycles} program cycles")
        return 0

    return run(args.verb, args, body)


def parse_setting(text: str) -> tuple[str, bool | int | str]:
    """`NAME=VALUE`: VALUE as the parameter table takes it (ON/OFF/TRUE/FALSE, a whole
    number, or a word such as `fixed`); the resource checks it against the parameter."""
    name, sep, value = text.partition("=")
    name, value = name.strip(), value.strip()
    if not sep or not name or not value:
        raise argparse.ArgumentTypeError(f"'{text}' is not NAME=VALUE")
    switch = {"on": True, "true": True, "off": False, "false": False}.get(value.lower())
    if switch is not None:
        return name, switch
    try:
        return name, int(value)
    except ValueError:
        return name, value


def _shown(value: Any) -> str:
    return ("ON" if value else "OFF") if isinstance(value, bool) else str(value)


def params(args: argparse.Namespace) -> int:
    """The resource and program parameters; `--set NAME=VALUE` changes resource parameters
    online (each refused or done in the order given)."""

    def body() -> int:
        with resource_client(args) as client:
            for name, value in args.set:
                client.ask(p.SetParameter(name, value))
                print(f"parameter {name}: {_shown(value)}")
            current = client.ask(p.GetParameters())
        if args.json:
            print(json.dumps(encode(current), indent=2, sort_keys=True))
            return 0
        if not args.set:
            resource = encode(current.resource)
            print("\n".join(table(["parameter", "value"], _rows(resource))))
            for program in current.programs:
                print(f"\nprogram {program.name}")
                settings = encode(program)
                for internal in ("name", "writes", "reads"):
                    settings.pop(internal)
                print("\n".join(table(["parameter", "value"], _rows(settings))))
        return 0

    return run("params", args, body)


def _rows(settings: dict[str, Any]) -> list[list[str]]:
    return [[name, _shown(value)] for name, value in settings.items()]
