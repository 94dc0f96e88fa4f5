"""The `[exchange]` settings of padt.toml: the global variables this resource publishes to
other resources, and the publications of others it takes into globals of its own
(docs/exchange.md, the codes E0628 and E0629).

Every problem is a diagnostic at the line of the setting; the check goes on after one. What
passes becomes the artifact's `ExchangeConfig`; a project without an `[exchange]` table, or
with one that names nothing, has none (None), and its artifact's CRC is as before.

A global that takes exchanged values has the exchange as its one writer: no user program
may write it (as E0606 keeps one writer per global), it is not located (the field or the
program sets those), and two subscriptions may not both fill it. Only elementary globals
travel (BOOL, the integers and bit strings, REAL, LREAL, TIME, the dates, STRING and
CHAR); the subscriber's global must have the publisher's type, which the subscriber checks
in every message, since the compiler sees one project only.
"""

from __future__ import annotations

from typing import Any

from backend.compiler.ast import key
from backend.compiler.checks.programs import globals_written
from backend.compiler.checks.settings_table import SettingsChecker
from backend.compiler.codes import Code
from backend.compiler.diagnostics import Diagnostic
from backend.compiler.resolve import Resolved, Variable
from backend.compiler.types import ElementaryType, artifact_type_text
from runtime.contract.artifact import ProgramConfig
from runtime.contract.exchange import (
    DEFAULT_PERIOD_MS,
    DEFAULT_TIMEOUT_MS,
    MAX_PERIOD_MS,
    MAX_VARIABLES,
    MIN_PERIOD_MS,
    PUBLICATION_NAME,
    ExchangeConfig,
    ExchangePoint,
    Publication,
    Published,
    Subscription,
)
from runtime.contract.keyspace import resource_name_problem
from runtime.contract.values import ValueRejected, representation

TABLE_KEYS = ("publish", "subscribe")
PUBLISH_KEYS = ("name", "variables", "period_ms")
SUBSCRIBE_KEYS = ("resource", "publication", "timeout_ms", "variable")
POINT_KEYS = ("variable", "from", "safe_value")
# a safe value left out: 0 / FALSE / empty, by the type's category (de-energise to trip)
_DEFAULTS: dict[str, Any] = {"bool": False, "real": 0.0, "string": ""}


def check_exchange(
    resolved: Resolved,
    programs: list[ProgramConfig],
    settings: Any,
    resource: str,
    config_file: str,
    lines: dict[str, int],
) -> tuple[ExchangeConfig | None, list[Diagnostic]]:
    """The exchange of a project from its `[exchange]` table (None: there is none, or it
    names nothing); `resource`: this resource's name, which no subscription may name."""
    if settings is None:
        return None, []
    checker = SettingsChecker(config_file, lines, Code.EXCHANGE_SETTING)
    if not isinstance(settings, dict):
        checker.report("exchange", Code.EXCHANGE_SETTING, "[exchange] must be a table")
        return None, checker.diagnostics
    checker.unknown_keys(settings, TABLE_KEYS, "exchange")
    publications = _publications(checker, resolved, _tables(checker, settings, "publish"))
    written = {
        name for program in programs for name in _written(resolved, program.pou)
    }  # the globals the user programs write
    subscriptions = _subscriptions(
        checker, resolved, _tables(checker, settings, "subscribe"), resource, written
    )
    config = ExchangeConfig(
        publications=tuple(sorted(publications, key=lambda p: p.name)),
        subscriptions=tuple(sorted(subscriptions, key=lambda s: (s.resource, s.publication))),
    )
    return (config if config else None), checker.diagnostics


def _tables(checker: SettingsChecker, settings: dict[str, Any], name: str) -> list[Any]:
    tables = settings.get(name, [])
    if not isinstance(tables, list) or not all(isinstance(t, dict) for t in tables):
        message = f"[exchange] {name} must be tables: [[exchange.{name}]]"
        checker.report(f"exchange.{name}", Code.EXCHANGE_SETTING, message)
        return []
    return tables


def _written(resolved: Resolved, pou: str) -> set[str]:
    return set(globals_written(resolved, key(pou))) if key(pou) in resolved.pous else set()


def _publications(
    checker: SettingsChecker, resolved: Resolved, tables: list[dict[str, Any]]
) -> list[Publication]:
    found: list[Publication] = []
    names: set[str] = set()
    for index, table in enumerate(tables):
        where = f"exchange.publish.{index}"
        checker.unknown_keys(table, PUBLISH_KEYS, where)
        name = _name(checker, table, "name", where)
        if name is not None and name in names:
            message = f"publication '{name}' is named twice"
            checker.report(f"{where}.name", Code.EXCHANGE_SETTING, message)
            name = None
        period = checker.integer(
            table, "period_ms", where, DEFAULT_PERIOD_MS, MIN_PERIOD_MS, MAX_PERIOD_MS
        )
        variables = _published(checker, resolved, table.get("variables"), where)
        if name is not None and variables:
            names.add(name)
            found.append(Publication(name, variables, period))
    return found


def _name(checker: SettingsChecker, table: dict[str, Any], field: str, where: str) -> str | None:
    value = table.get(field)
    if isinstance(value, str) and PUBLICATION_NAME.fullmatch(value):
        return value
    message = (
        f"[exchange] {field} must be 1 to 64 of A-Z a-z 0-9 _ - (it is part of a Zenoh key), "
        f"not {value!r}"
    )
    checker.report(f"{where}.{field}", Code.EXCHANGE_SETTING, message)
    return None


def _published(
    checker: SettingsChecker, resolved: Resolved, entries: Any, where: str
) -> tuple[Published, ...]:
    if not _list_of(entries, str):
        message = "[exchange.publish] variables must be a list of one or more global names"
        checker.report(f"{where}.variables", Code.EXCHANGE_SETTING, message)
        return ()
    if len(entries) > MAX_VARIABLES:
        message = f"[exchange.publish] publishes at most {MAX_VARIABLES} variables"
        checker.report(f"{where}.variables", Code.EXCHANGE_SETTING, message)
        return ()
    found: dict[str, Published] = {}
    for entry in entries:
        variable = _global(checker, resolved, entry, f"{where}.variables")
        if variable is not None:
            found[key(variable.name)] = Published(variable.name, artifact_type_text(variable.type))
    return tuple(found[name] for name in sorted(found))


def _global(checker: SettingsChecker, resolved: Resolved, name: str, where: str) -> Variable | None:
    """The elementary global `name`, or None after a diagnostic."""
    variable = resolved.globals_by_key.get(key(name.strip()))
    if variable is None or variable.kind != "VAR_GLOBAL":
        message = f"'{name}' is no global variable of the project"
        checker.report(where, Code.EXCHANGE_VARIABLE, message)
        return None
    if not isinstance(variable.type, ElementaryType):
        message = (
            f"'{variable.name}' is of type {getattr(variable.type, 'name', '?')}: only "
            "elementary variables are exchanged (publish the members one by one)"
        )
        checker.report(where, Code.EXCHANGE_VARIABLE, message)
        return None
    return variable


def _subscriptions(
    checker: SettingsChecker,
    resolved: Resolved,
    tables: list[dict[str, Any]],
    resource: str,
    written: set[str],
) -> list[Subscription]:
    found: list[Subscription] = []
    taken: dict[str, str] = {}  # global (key) -> the subscription that fills it
    seen: set[tuple[str, str]] = set()
    for index, table in enumerate(tables):
        where = f"exchange.subscribe.{index}"
        checker.unknown_keys(table, SUBSCRIBE_KEYS, where)
        publisher = table.get("resource")
        problem = (
            resource_name_problem(publisher)
            if isinstance(publisher, str)
            else f"{publisher!r} is no resource name"
        )
        if problem is None and isinstance(publisher, str) and key(publisher) == key(resource):
            problem = f"'{publisher}' is this resource: it reads its own globals directly"
        if problem is not None:
            checker.report(f"{where}.resource", Code.EXCHANGE_SETTING, f"[exchange] {problem}")
        publication = _name(checker, table, "publication", where)
        timeout = checker.integer(
            table, "timeout_ms", where, DEFAULT_TIMEOUT_MS, MIN_PERIOD_MS, MAX_PERIOD_MS
        )
        if problem is not None or publication is None or not isinstance(publisher, str):
            continue
        if (key(publisher), publication) in seen:
            message = f"{publisher}/{publication} is subscribed twice"
            checker.report(f"{where}.publication", Code.EXCHANGE_SETTING, message)
            continue
        seen.add((key(publisher), publication))
        name = f"{publisher}/{publication}"
        points = _points(checker, resolved, table.get("variable"), where, name, taken, written)
        if points:
            found.append(Subscription(publisher, publication, timeout, points))
    return found


def _points(
    checker: SettingsChecker,
    resolved: Resolved,
    entries: Any,
    where: str,
    subscription: str,
    taken: dict[str, str],
    written: set[str],
) -> tuple[ExchangePoint, ...]:
    if (
        not isinstance(entries, list)
        or not entries
        or not all(isinstance(e, dict) for e in entries)
    ):
        message = (
            "[exchange.subscribe] takes its values with [[exchange.subscribe.variable]] tables"
        )
        checker.report(f"{where}.variable", Code.EXCHANGE_SETTING, message)
        return ()
    points: list[ExchangePoint] = []
    for index, entry in enumerate(entries):
        at = f"{where}.variable.{index}"
        checker.unknown_keys(entry, POINT_KEYS, at)
        name = entry.get("variable")
        if not isinstance(name, str):
            checker.report(at, Code.EXCHANGE_SETTING, "[exchange] variable must name a global")
            continue
        source = entry.get("from", name)
        if not isinstance(source, str) or not source.strip():
            message = f"[exchange] from must name the publisher's global, not {source!r}"
            checker.report(f"{at}.from", Code.EXCHANGE_SETTING, message)
            continue
        variable = _global(checker, resolved, name, f"{at}.variable")
        if variable is None:
            continue
        upper = key(variable.name)
        problem = None
        if variable.constant:
            problem = f"'{variable.name}' is a CONSTANT: the exchange cannot write it"
        elif variable.location is not None:
            problem = (
                f"'{variable.name}' is located ({variable.location}): the field or the "
                "program sets it"
            )
        elif upper in written:
            problem = (
                f"'{variable.name}' is written by a user program: a global that takes "
                "exchanged values has the exchange as its one writer"
            )
        elif upper in taken:
            problem = f"'{variable.name}' already takes the values of {taken[upper]}"
        if problem is not None:
            checker.report(f"{at}.variable", Code.EXCHANGE_VARIABLE, problem)
            continue
        taken[upper] = subscription
        type_text = artifact_type_text(variable.type)
        safe = entry.get("safe_value", _DEFAULTS.get(getattr(variable.type, "category", ""), 0))
        try:
            representation(type_text, safe)
        except ValueRejected as exc:
            checker.report(f"{at}.safe_value", Code.EXCHANGE_SETTING, f"safe_value: {exc}")
            continue
        points.append(ExchangePoint(variable.name, type_text, source.strip(), safe))
    return tuple(sorted(points, key=lambda p: key(p.variable)))


def _list_of(entries: Any, kind: type) -> bool:
    """Whether `entries` is a list of one or more `kind`."""
    return isinstance(entries, list) and bool(entries) and all(isinstance(e, kind) for e in entries)
