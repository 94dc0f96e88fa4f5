"""The resource: its parameters and its programs' parameters, the system variables, the
users (names and levels, never their password hashes), and the I/O and network
configuration."""

from __future__ import annotations

from typing import Any

from backend.engineering.documentation.field_bus import field_bus
from backend.engineering.documentation.markup import Section, anchor, code, escape, heading, table
from backend.engineering.documentation.signals import located_signals
from backend.engineering.documentation.subject import Subject
from runtime.contract.keyspace import ROOT, exchange_key
from runtime.contract.parameters import PROGRAM_PARAMETERS, RESOURCE_PARAMETERS
from runtime.contract.session_options import DEFAULT_ENDPOINT
from runtime.contract.system_variables import NAMESPACE, SYSTEM_VARIABLES

# the keys a resource answers and publishes under (docs/architecture.md, key space v1)
_KEYS = (
    ("cmd", "queryable: commands in, replies out"),
    ("status", "publication: state, CRC, cycle statistics"),
    ("events", "publication: the event log"),
    ("watch/<id>", "publication: the values of watch set <id>"),
    ("watchers/<id>", "liveliness token of a client's watch set"),
    ("alive", "liveliness token while the runtime lives"),
)
_DIRECTIONS = {"I": "input", "Q": "output"}


def resource_section(subject: Subject) -> Section:
    resource = subject.artifact.resource
    base = anchor("resource", resource.name)
    parts: list[str] = []
    headings = []
    for level, title, part_id, body in (
        (1, f"Resource {resource.name}", base, ""),
        (2, "Resource parameters", f"{base}-parameters", _resource_parameters(subject)),
        (2, "Programs and program parameters", f"{base}-programs", _programs(subject)),
        (2, "System variables", f"{base}-system", _system_variables(subject)),
        (2, "Users", f"{base}-users", _users(subject)),
        (2, "I/O and network configuration", f"{base}-io", _io_and_network(subject)),
    ):
        html, entry = heading(level, title, part_id)
        parts.append(html + body)
        headings.append(entry)
    return Section('<section class="part">' + "".join(parts) + "</section>", tuple(headings))


def value_text(value: Any) -> str:
    if isinstance(value, bool):
        return "ON" if value else "OFF"
    return str(value)


def _resource_parameters(subject: Subject) -> str:
    resource = subject.artifact.resource
    rows = [
        [
            code(spec.name),
            escape(value_text(getattr(resource, spec.name))),
            "online" if spec.online else "with a download",
        ]
        for spec in RESOURCE_PARAMETERS
    ]
    crc = f"<p>Configuration CRC {code(subject.crc)}</p>"
    return crc + table(["parameter", "value", "changeable"], rows)


def _programs(subject: Subject) -> str:
    programs = sorted(subject.artifact.programs, key=lambda p: p.program_id)
    names = [p.name for p in programs]
    rows = [
        [code(spec.name), *(escape(value_text(getattr(p, spec.name))) for p in programs)]
        for spec in PROGRAM_PARAMETERS
    ]
    rows.insert(0, ["POU", *(code(p.pou) for p in programs)])
    rows.append(["CRC", *(code(p.crc) for p in programs)])
    rows.append(["globals written", *(_names(p.writes) for p in programs)])
    rows.append(["globals read", *(_names(p.reads) for p in programs)])
    return table(["parameter", *names], rows)


def _names(names: tuple[str, ...]) -> str:
    return ", ".join(escape(n) for n in names) or "none"


def _system_variables(subject: Subject) -> str:
    used = {entry.name.upper(): entry for entry in subject.uses if entry.kind == "SYSTEM"}
    rows = []
    for variable in SYSTEM_VARIABLES:
        uses = used.get(f"{NAMESPACE}.{variable.name}".upper())
        where = sorted({use.pou for use in uses.uses}) if uses is not None else []
        rows.append(
            [
                code(f"{NAMESPACE}.{variable.name}"),
                escape(variable.type),
                "logic and runtime" if variable.writable else "runtime only",
                escape(variable.meaning),
                ", ".join(escape(w) for w in where) or "not used",
            ]
        )
    return table(["variable", "type", "written by", "meaning", "used in"], rows, "system")


def _users(subject: Subject) -> str:
    users = subject.artifact.users
    if not users:
        return (
            '<p class="warning">No user accounts: the resource runs with open access '
            "(every command allowed to whoever reaches it).</p>"
        )
    rows = [[escape(u.name), escape(u.level)] for u in sorted(users, key=lambda u: u.name)]
    note = "Passwords are kept only as salted verifiers; they are not shown."
    return table(["user", "level"], rows) + f'<p class="note">{note}</p>'


def _io_and_network(subject: Subject) -> str:
    safe = {name.upper(): value for name, value in subject.artifact.safe_values}
    rows = []
    for signal in located_signals(subject):
        area = signal.location.upper()[1:2]
        safe_value = ""
        if area == "Q" and signal.name.upper() in safe:
            value = safe[signal.name.upper()]
            safe_value = str(value).upper() if isinstance(value, bool) else str(value)
        elif area == "Q":
            safe_value = "0 / FALSE (default)"
        rows.append(
            [
                code(signal.location),
                escape(signal.qualified),
                escape(signal.type),
                _DIRECTIONS.get(area, "memory"),
                escape(safe_value),
            ]
        )
    io = "<h3>Located variables (process image)</h3>" + table(
        ["address", "variable", "type", "direction", "safe value"], rows
    )
    resource = subject.artifact.resource.name
    prefix = f"{ROOT}/res/{resource}/"
    key_rows = [[code(prefix + key), escape(meaning)] for key, meaning in _KEYS]
    exchange = subject.artifact.exchange
    for publication in exchange.publications if exchange else ():
        meaning = f"publication: exchange '{publication.name}' to other resources"
        key_rows.append([code(exchange_key(resource, publication.name)), escape(meaning)])
    for subscription in exchange.subscriptions if exchange else ():
        key = exchange_key(subscription.resource, subscription.publication)
        key_rows.append([code(key), escape(f"subscribed: exchange from {subscription.resource}")])
    network = (
        "<h3>Network (Zenoh)</h3>"
        f"<p>Key space {code(prefix)}. The endpoint is chosen when the runtime starts "
        f"(default {code(DEFAULT_ENDPOINT)}, loopback only); it is not part of the "
        "configuration and does not change its CRC.</p>" + table(["key", "what"], key_rows)
    )
    return io + network + field_bus(subject.artifact)
