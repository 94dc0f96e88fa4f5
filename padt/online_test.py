"""`padt values`, `write`, `force` and `events`: online test from a terminal or a CI job
(docs/cli.md). Values are read and written as ST literals of the variable's type; `--json`
gives the protocol's own JSON, one object (or, with `--follow`, one line per message), with
each value's literal beside it as the REST API gives them."""

from __future__ import annotations

import argparse
import json
import queue
from datetime import UTC, datetime
from typing import Any

from backend.engineering.literals import (
    LiteralError,
    literals_of,
    parse_literal,
    watch_values_shown,
)
from backend.engineering.resource_client import ResourceClient
from padt.online import Failed, resource_client, run, table
from runtime.contract import protocol as p
from runtime.contract.refusal import Refusal
from runtime.contract.stop_request import StopRequest
from runtime.contract.values import format_value
from runtime.contract.wire import encode


def _types(client: ResourceClient) -> dict[str, str]:
    """Every variable's type by its upper-case path (ST names are case-insensitive)."""
    return {v.path.upper(): v.type for v in client.ask(p.GetVariables()).variables}


def _type_of(types: dict[str, str], name: str, resource: str) -> str:
    found = types.get(name.upper())
    if found is None:
        raise Refusal("unknown_variable", f"resource {resource} has no variable '{name}'")
    return found


def _print_json(data: Any, follow: bool) -> None:
    print(json.dumps(encode(data), sort_keys=True, indent=None if follow else 2), flush=True)


# ---- padt values


def values(args: argparse.Namespace) -> int:
    """Every variable (or the ones named) once; with `--follow`, a line per watch-set
    message until Ctrl-C."""

    def body() -> int:
        with resource_client(args) as client:
            types = _types(client)
            names = list(args.variables)
            for name in names:
                _type_of(types, name, args.resource)
            if args.follow:
                return _follow_values(args, client, names or sorted(types), types)
            reply = client.ask(p.GetValues())
        wanted = {n.upper() for n in names}
        shown = {k: v for k, v in reply.values.items() if not wanted or k.upper() in wanted}
        if args.json:
            literals = literals_of(shown, {path: types[path.upper()] for path in shown})
            _print_json({"cycle": reply.cycle, "values": shown, "literals": literals}, False)
        else:
            rows = [
                [k, types[k.upper()], format_value(v, types[k.upper()])] for k, v in shown.items()
            ]
            print("\n".join(table(["variable", "type", "value"], rows)))
        return 0

    return run("values", args, body)


def _follow_values(
    args: argparse.Namespace, client: ResourceClient, names: list[str], types: dict[str, str]
) -> int:
    stop = StopRequest()
    arrived: queue.Queue[p.WatchValues] = queue.Queue()
    watch = client.watch(names, arrived.put, args.period_ms)
    try:
        while not stop.event.is_set():
            try:
                message = arrived.get(timeout=0.2)
            except queue.Empty:
                continue
            if args.json:
                path_types = {path: types[path.upper()] for path in message.values}
                _print_json(watch_values_shown(message, path_types), follow=True)
                continue
            shown = " ".join(
                f"{path}={format_value(entry.value, types[path.upper()])}"
                + ("" if entry.quality == p.Quality.LIVE else f"({entry.quality})")
                for path, entry in message.values.items()
            )
            print(f"cycle {message.cycle}: {shown}", flush=True)
    finally:
        watch.close()
    return 0


# ---- padt write


def _value(types: dict[str, str], name: str, literal: str, resource: str) -> Any:
    try:
        return parse_literal(literal, _type_of(types, name, resource))
    except LiteralError as exc:
        raise Failed(f"{name}: {exc}", 2) from None


def write(args: argparse.Namespace) -> int:
    def body() -> int:
        with resource_client(args) as client:
            types = _types(client)
            value = _value(types, args.variable, args.value, args.resource)
            client.ask(p.Write(args.variable, value))
            now = client.ask(p.GetValues()).values
        path = next(k for k in now if k.upper() == args.variable.upper())
        print(f"{path} := {format_value(now[path], types[path.upper()])}")
        return 0

    return run("write", args, body)


# ---- padt force


def force(args: argparse.Namespace) -> int:
    """`force start|stop [--program P]`, `force set VAR VALUE [--off]`, `force clear VAR`,
    `force show`."""

    def body() -> int:
        with resource_client(args) as client:
            if args.action == "start":
                client.ask(p.StartForcing(args.program, args.timeout_ms))
            elif args.action == "stop":
                client.ask(p.StopForcing(args.program))
            elif args.action == "set":
                value = _value(_types(client), args.variable, args.value, args.resource)
                client.ask(p.Force(args.variable, value, switch=not args.off))
            elif args.action == "clear":
                client.ask(p.Unforce(args.variable))
            state = client.ask(p.GetForcing()).forcing
            types = _types(client)
        if args.json:
            _print_json(state, follow=False)
        else:
            print("\n".join(forcing_lines(state, types)))
        return 0

    return run("force", args, body)


def forcing_lines(state: p.ForcingState, types: dict[str, str]) -> list[str]:
    started = [level or "global" for level in state.started]
    lines = [f"forcing started: {', '.join(started) if started else 'nowhere'}"]
    for level, remaining in state.remaining_ms.items():
        if remaining is not None:
            lines.append(f"{level}: {remaining / 1000:.1f} s left")
    rows = [
        [
            e.variable,
            e.level,
            format_value(e.value, types.get(e.variable.upper(), "")),
            "ON" if e.switch else "OFF",
            "forced" if e.active else "-",
        ]
        for e in state.entries
    ]
    if rows:
        lines += table(["variable", "level", "value", "switch", "now"], rows)
    return lines


# ---- padt events


def event_line(event: p.Event) -> str:
    moment = datetime.fromtimestamp(event.time_ns / 1e9, UTC).strftime("%Y-%m-%d %H:%M:%S")
    return f"{event.seq:>6}  {moment}  {event.kind:<9} {event.user or '-':<12} {event.message}"


def events(args: argparse.Namespace) -> int:
    """The short-term event log (after `--after`); with `--follow`, then every new event
    until Ctrl-C."""

    def body() -> int:
        with resource_client(args) as client:
            arrived: queue.Queue[p.Event] = queue.Queue()
            if args.follow:  # subscribed before reading the log: no event falls between
                client.on_events(arrived.put)
            last = args.after
            while True:  # pages of at most MAX_EVENTS
                page = client.ask(p.GetEvents(last, p.MAX_EVENTS)).events
                for event in page:
                    _show(event, args.json)
                    last = event.seq
                if len(page) < p.MAX_EVENTS:
                    break
            if not args.follow:
                return 0
            stop = StopRequest()
            while not stop.event.is_set():
                try:
                    event = arrived.get(timeout=0.2)
                except queue.Empty:
                    continue
                if event.seq > last:
                    _show(event, args.json)
                    last = event.seq
            client.close()
        return 0

    return run("events", args, body)


def _show(event: p.Event, as_json: bool) -> None:
    if as_json:
        _print_json(event, follow=True)
    else:
        print(event_line(event), flush=True)
