"""The `[modbus]` settings of padt.toml: the served process image and the remote devices,
checked against the project's located globals (docs/modbus.md, the codes E0612..E0615).

Every problem is a diagnostic at the line of the setting; the check goes on after one, so
the user sees them all. What passes becomes the artifact's `ModbusConfig`.
"""

from __future__ import annotations

import re
from typing import Any

from backend.compiler.ast import key
from backend.compiler.checks.settings_table import SettingsChecker
from backend.compiler.codes import Code
from backend.compiler.diagnostics import Diagnostic
from backend.compiler.resolve import Resolved, Variable
from runtime.contract.modbus import (
    AREAS,
    BIT_AREAS,
    DEFAULT_HOST,
    DEFAULT_PORT,
    MAX_ADDRESS,
    ORDERS,
    WRITABLE_AREAS,
    Device,
    ModbusConfig,
    Point,
    fits,
    served_place,
)
from runtime.contract.values import ValueRejected, representation

DEVICE_NAME = re.compile(r"[A-Za-z0-9_-]{1,32}$")
HOST = re.compile(r"[A-Za-z0-9.:_-]{1,253}$")
MIN_PERIOD_MS, MAX_PERIOD_MS = 10, 60_000
SERVER_KEYS = ("serve", "host", "port", "writable", "byte_order", "word_order", "device")
DEVICE_KEYS = ("name", "host", "port", "unit_id", "period_ms", "timeout_ms", "point")
POINT_KEYS = ("variable", "area", "address", "byte_order", "word_order", "safe_value")


class _Checker(SettingsChecker):
    def __init__(self, resolved: Resolved, config_file: str, lines: dict[str, int]) -> None:
        super().__init__(config_file, lines, Code.MODBUS_SETTING)
        self.resolved = resolved

    def text(self, table: dict[str, Any], name: str, path: str, default: str, pattern: Any) -> str:
        valid = lambda v: isinstance(v, str) and pattern.match(v) is not None  # noqa: E731
        expected = f"a text of {pattern.pattern}"
        result: str = self.setting(table, name, path, default, valid, expected)
        return result

    def order(self, table: dict[str, Any], name: str, path: str) -> str:
        expected = '"big" or "little"'
        result: str = self.setting(table, name, path, "big", ORDERS.__contains__, expected)
        return result

    def located(self, name: Any, path: str) -> Variable | None:
        variable = self.resolved.globals_by_key.get(key(name)) if isinstance(name, str) else None
        if variable is None or variable.location is None:
            self.report(
                path, Code.MODBUS_VARIABLE, f"Modbus point '{name}': no located global variable"
            )
            return None
        return variable


def check_modbus(
    resolved: Resolved, settings: Any, config_file: str, lines: dict[str, int]
) -> tuple[ModbusConfig, list[Diagnostic]]:
    """The Modbus configuration of a project from its `[modbus]` table (None: absent)."""
    checker = _Checker(resolved, config_file, lines)
    # a partly specified location (`AT %Q*`) has no Modbus address of its own
    located = [
        v
        for _, v in sorted(resolved.globals_by_key.items())
        if v.location and not v.location.endswith("*")
    ]
    if settings is None:
        settings = {}
        serve_default = bool(located)  # nothing located, nothing to serve
    else:
        serve_default = True
    if not isinstance(settings, dict):
        checker.report("modbus", Code.MODBUS_SETTING, "[modbus] must be a table")
        return ModbusConfig(), checker.diagnostics
    checker.unknown_keys(settings, SERVER_KEYS, "modbus")
    serve = checker.setting(settings, "serve", "modbus", serve_default, _is_bool, "true or false")
    host = checker.text(settings, "host", "modbus", DEFAULT_HOST, HOST)
    port = checker.integer(settings, "port", "modbus", DEFAULT_PORT, 1, 65535)
    byte_order = checker.order(settings, "byte_order", "modbus")
    word_order = checker.order(settings, "word_order", "modbus")
    writable = _writable(checker, settings.get("writable", []))
    served = []
    for variable in located:
        assert variable.location is not None
        place = served_place(variable.location, _type_name(variable))
        if place is None:
            continue
        area, address = place
        point = Point(
            variable.name, variable.location, _type_name(variable), area, address,
            byte_order, word_order, writable=key(variable.location) in writable,
        )  # fmt: skip
        if point.address + point.count - 1 > MAX_ADDRESS:
            checker.report(
                "modbus", Code.MODBUS_TYPE,
                f"'{variable.name}' at {variable.location}: beyond the last Modbus address",
            )  # fmt: skip
            continue
        served.append(point)
    for location, where in sorted(writable.items()):
        point_of = next((p for p in served if key(p.location) == location), None)
        if point_of is None or point_of.area not in WRITABLE_AREAS:
            checker.report(
                where, Code.MODBUS_VARIABLE,
                f"writable {location}: no served coil or holding register (%QX, %QW, %MW, %MD)",
            )  # fmt: skip
    _overlaps(checker, served, "modbus", "the served image")
    devices = _devices(checker, settings.get("device", []))
    config = ModbusConfig(
        serve=bool(serve), host=host, port=port,
        served=tuple(sorted(served, key=lambda p: (p.area, p.address))) if serve else (),
        devices=devices,
    )  # fmt: skip
    return config, checker.diagnostics


def _writable(checker: _Checker, entries: Any) -> dict[str, str]:
    """The locations clients may write (upper case) with the path to report them at."""
    if not isinstance(entries, list) or not all(isinstance(e, str) for e in entries):
        checker.report(
            "modbus.writable", Code.MODBUS_SETTING, "[modbus] writable must be a list of locations"
        )
        return {}
    return {key(entry.strip()): "modbus.writable" for entry in entries}


def _devices(checker: _Checker, entries: Any) -> tuple[Device, ...]:
    if not isinstance(entries, list):
        checker.report("modbus.device", Code.MODBUS_SETTING, "[[modbus.device]] must be tables")
        return ()
    devices: list[Device] = []
    delivered: dict[str, str] = {}  # input variable -> the device that delivers it
    for index, entry in enumerate(entries):
        path = f"modbus.device.{index}"
        if not isinstance(entry, dict):
            checker.report(path, Code.MODBUS_SETTING, "[[modbus.device]] must be a table")
            continue
        checker.unknown_keys(entry, DEVICE_KEYS, path)
        name = entry.get("name")
        if not isinstance(name, str) or not DEVICE_NAME.match(name):
            checker.report(
                path, Code.MODBUS_SETTING,
                f"[[modbus.device]] needs a name of 1 to 32 of A-Z a-z 0-9 _ -, not {name!r}",
            )  # fmt: skip
            continue
        if any(d.name == name for d in devices):
            checker.report(path, Code.MODBUS_SETTING, f"device '{name}' is defined twice")
            continue
        if not isinstance(entry.get("host"), str) or "port" not in entry:
            checker.report(path, Code.MODBUS_SETTING, f"device '{name}' needs a host and a port")
        host = checker.text(entry, "host", path, DEFAULT_HOST, HOST)
        port = checker.integer(entry, "port", path, 502, 1, 65535)
        unit_id = checker.integer(entry, "unit_id", path, 1, 0, 255)
        period = checker.integer(entry, "period_ms", path, 100, MIN_PERIOD_MS, MAX_PERIOD_MS)
        timeout = checker.integer(entry, "timeout_ms", path, 1000, MIN_PERIOD_MS, MAX_PERIOD_MS)
        points = _points(checker, entry.get("point", []), path, name, delivered)
        devices.append(Device(name, host, port, unit_id, period, timeout, points))
    return tuple(sorted(devices, key=lambda d: d.name))


def _points(
    checker: _Checker, entries: Any, device_path: str, device: str, delivered: dict[str, str]
) -> tuple[Point, ...]:
    if not isinstance(entries, list):
        message = f"device '{device}': points must be tables"
        checker.report(device_path, Code.MODBUS_SETTING, message)
        return ()
    points: list[Point] = []
    for index, entry in enumerate(entries):
        path = f"{device_path}.point.{index}"
        if not isinstance(entry, dict):
            checker.report(path, Code.MODBUS_SETTING, "[[modbus.device.point]] must be a table")
            continue
        checker.unknown_keys(entry, POINT_KEYS, path)
        missing = [k for k in ("variable", "area", "address") if k not in entry]
        if missing:
            message = f"a point of device '{device}' needs {', '.join(missing)}"
            checker.report(path, Code.MODBUS_SETTING, message)
            continue
        area = checker.setting(entry, "area", path, None, AREAS.__contains__, " or ".join(AREAS))
        address = checker.integer(entry, "address", path, -1, 0, MAX_ADDRESS)
        variable = checker.located(entry["variable"], f"{path}.variable")
        if area is None or address < 0 or variable is None:
            continue
        assert variable.location is not None
        point = Point(
            variable.name, variable.location, _type_name(variable), area, address,
            checker.order(entry, "byte_order", path), checker.order(entry, "word_order", path),
        )  # fmt: skip
        label = f"'{variable.name}' ({variable.location}) on {area} {address} of '{device}'"
        kind = variable.location.lstrip("%")[:1].upper()
        if kind not in "IQ":
            checker.report(
                f"{path}.variable", Code.MODBUS_VARIABLE,
                f"{label}: a device delivers inputs (%I) or takes outputs (%Q)",
            )  # fmt: skip
            continue
        if kind == "Q" and area not in WRITABLE_AREAS:
            checker.report(
                f"{path}.area", Code.MODBUS_VARIABLE,
                f"{label}: an output goes to a coil or a holding register",
            )  # fmt: skip
            continue
        if not fits(_type_name(variable), area):
            wanted = "BOOL" if area in BIT_AREAS else "a 16-bit, 32-bit integer or REAL type"
            checker.report(
                f"{path}.area", Code.MODBUS_TYPE,
                f"{label}: {_type_name(variable)} does not fit, {area} takes {wanted}",
            )  # fmt: skip
            continue
        if point.address + point.count - 1 > MAX_ADDRESS:
            checker.report(f"{path}.address", Code.MODBUS_TYPE, f"{label}: beyond address 65535")
            continue
        if kind == "I":
            if variable.name in delivered:
                checker.report(
                    f"{path}.variable", Code.MODBUS_OVERLAP,
                    f"{label}: already delivered by '{delivered[variable.name]}'",
                )  # fmt: skip
                continue
            delivered[variable.name] = device
            safe = _safe_value(checker, entry, path, variable)
            point = Point(**{**point.__dict__, "safe_value": safe})
        elif "safe_value" in entry:
            checker.report(
                f"{path}.safe_value", Code.MODBUS_SETTING,
                f"{label}: outputs take the resource's safe values ([resource.safe_values])",
            )  # fmt: skip
        points.append(point)
    _overlaps(checker, points, device_path, f"device '{device}'")
    return tuple(sorted(points, key=lambda p: (p.area, p.address)))


def _safe_value(checker: _Checker, entry: dict[str, Any], path: str, variable: Variable) -> Any:
    default = False if _type_name(variable) == "BOOL" else 0
    if "safe_value" not in entry:
        return default
    try:
        return representation(_type_name(variable), entry["safe_value"])
    except ValueRejected as exc:
        checker.report(
            f"{path}.safe_value", Code.MODBUS_SETTING, f"safe value of '{variable.name}': {exc}"
        )
        return default


def _overlaps(checker: _Checker, points: list[Point], path: str, where: str) -> None:
    """Two points on the same bit or register of one table."""
    taken: dict[tuple[str, int], Point] = {}
    for point in points:
        for address in range(point.address, point.address + point.count):
            other = taken.get((point.area, address))
            if other is not None and other.variable != point.variable:
                checker.report(
                    path, Code.MODBUS_OVERLAP,
                    f"{where}: '{point.variable}' and '{other.variable}' share "
                    f"{point.area} {address}",
                )  # fmt: skip
                break
            taken[(point.area, address)] = point


def _is_bool(value: Any) -> bool:
    return isinstance(value, bool)


def _type_name(variable: Variable) -> str:
    """An elementary type's name; other types (arrays, structures) have no place on Modbus."""
    name = getattr(variable.type, "name", "")
    return name if isinstance(name, str) else ""
