"""The `[opcua]` settings of padt.toml: the variables the resource serves over OPC UA and the
remote servers it reads inputs from and writes outputs to (docs/opcua.md, the codes
E0621..E0627).

Every problem is a diagnostic at the line of the setting; the check goes on after one, so
the user sees them all. What passes becomes the artifact's `OpcuaConfig`; a project without
an `[opcua]` table has none (None), and its artifact's CRC is as before.

Paths are written as the runtime names the resource's variables (runtime/code/code_image.py):
a global by its bare name (`gSetpoint`), a program's variable after the program instance
(`TankControl.level`), the members of block instances and structures after a dot
(`TankControl.refillDelay.ET`, `gLine.speed`), each name as its declaration spells it
(`[opcua]` may spell it in any case). `expose` and `writable` name a program instance, a
block instance, a structure, an array or an elementary variable; an array is exposed whole,
never one of its elements.

The descriptions are the declaration comments (backend/compiler/comments.py) of the exposed
paths and of everything below them, each clipped to `comments.MAX_COMMENT` characters: a
program instance's is the comment before its PROGRAM, a block instance's that of its
declaration. What lies inside the elements of an array (the members of a structure or block
in an `ARRAY OF`) is described once for all elements, under the path with each index
written `[*]`: `gPoints[*].x` describes `gPoints[1].x`, `gPoints[2].x` ..., and
`grid[*].x` the elements `grid[0,1].x` of a two-dimensional one alike.
"""

from __future__ import annotations

import base64
import binascii
import re
from bisect import bisect_left
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import PurePosixPath, PureWindowsPath
from typing import Any

from backend.compiler.ast import key
from backend.compiler.checks.settings_table import SettingsChecker
from backend.compiler.checks.var_config import instance_variables
from backend.compiler.codes import Code
from backend.compiler.comments import declaration_comment
from backend.compiler.diagnostics import Diagnostic
from backend.compiler.resolve import PouSymbols, Resolved, Variable
from backend.compiler.source import SourceFile, stdlib_sources
from backend.compiler.types import ArrayType, ElementaryType, FbType, StructType, Type
from runtime.contract.artifact import ProgramConfig
from runtime.contract.modbus import ModbusConfig
from runtime.contract.opcua import (
    DEFAULT_HOST,
    DEFAULT_PORT,
    MODES,
    SECURITY,
    OpcuaConfig,
    OpcuaDevice,
    OpcuaPoint,
    OpcuaServer,
)
from runtime.contract.values import ValueRejected, representation

DEVICE_NAME = re.compile(r"[A-Za-z0-9_-]{1,32}$")
HOST = re.compile(r"[A-Za-z0-9.:_-]{1,253}$")
USER = re.compile(r"[^\x00-\x1f\x7f]{1,128}$")
# opc.tcp://host[:port][/path]: a host name, an IPv4 address or an IPv6 one in brackets
ENDPOINT = re.compile(
    r"opc\.tcp://(?P<host>[A-Za-z0-9](?:[A-Za-z0-9._-]{0,252})|\[[0-9A-Fa-f:.]{2,45}\])"
    r"(?::(?P<port>[0-9]{1,5}))?(?P<path>/[\x21-\x7e]*)?\Z"
)
MAX_ENDPOINT = 1024
MAX_PATH_FILE = 4096
# ns=<namespace>;<kind>=<identifier>, or i=<number> in namespace 0
NODE = re.compile(r"(?:ns=(?P<ns>[0-9]{1,5});)?(?P<kind>[isgb])=(?P<id>.*)\Z", re.DOTALL)
GUID = re.compile(r"[0-9A-Fa-f]{8}-[0-9A-Fa-f]{4}-[0-9A-Fa-f]{4}-[0-9A-Fa-f]{4}-[0-9A-Fa-f]{12}\Z")
MAX_NODE_ID = 4096  # characters of a string identifier, bytes of an opaque one (OPC UA's)
MIN_PERIOD_MS, MAX_PERIOD_MS, MAX_TIMEOUT_MS = 10, 60_000, 60_000
# what the server is set up with: [opcua] with none of these, only devices, serves nothing
SERVER_SETTINGS = ("host", "port", "expose", "writable", "anonymous", "trust_unknown_clients")
SERVER_KEYS = ("serve", *SERVER_SETTINGS, "device")
DEVICE_KEYS = (
    "name", "endpoint", "security", "user", "password_file", "mode", "period_ms",
    "timeout_ms", "point",
)  # fmt: skip
POINT_KEYS = ("variable", "node", "safe_value")
MAX_DEPTH = 64  # nesting followed below a path (a type holding itself is reported elsewhere)


@dataclass(frozen=True)
class _Node:
    """A path of the resource: a program instance (`pou`) or a variable."""

    path: str  # as declared
    variable: Variable | None = None
    pou: PouSymbols | None = None
    constant: bool = False  # the variable, or one it is in, is a CONSTANT


class _Checker(SettingsChecker):
    def __init__(self, resolved: Resolved, config_file: str, lines: dict[str, int]) -> None:
        super().__init__(config_file, lines, Code.OPCUA_SETTING, {"password": _NO_PASSWORD})
        self.resolved = resolved


_NO_PASSWORD = (
    "no password in the project: write it into a file on the runtime's host (readable by "
    "the runtime only) and name that file with password_file"
)


def check_opcua(
    resolved: Resolved,
    programs: list[ProgramConfig],
    sources: list[SourceFile],
    settings: Any,
    config_file: str,
    lines: dict[str, int],
    modbus: ModbusConfig | None = None,
) -> tuple[OpcuaConfig | None, list[Diagnostic]]:
    """The OPC UA configuration of a project from its `[opcua]` table (None: there is none,
    and the resource does no OPC UA); `modbus`: the project's checked Modbus configuration,
    whose device points no OPC UA point may map again."""
    if settings is None:
        return None, []
    checker = _Checker(resolved, config_file, lines)
    if not isinstance(settings, dict):
        checker.report("opcua", Code.OPCUA_SETTING, "[opcua] must be a table")
        return None, checker.diagnostics
    checker.unknown_keys(settings, SERVER_KEYS, "opcua")
    # only [[opcua.device]] tables: a client of remote servers, serving nothing
    device_only = "device" in settings and not set(settings) & set(SERVER_SETTINGS)
    serve = checker.flag(settings, "serve", "opcua", not device_only)
    host = checker.setting(
        settings, "host", "opcua", DEFAULT_HOST,
        lambda v: isinstance(v, str) and HOST.match(v) is not None, f"a text of {HOST.pattern}",
    )  # fmt: skip
    port = checker.integer(settings, "port", "opcua", DEFAULT_PORT, 1, 65535)
    nodes = _nodes(resolved, programs)
    exposed = _paths(checker, settings, "expose", nodes)
    writable = _paths(checker, settings, "writable", nodes)
    _check_writable(checker, writable, exposed)
    server = OpcuaServer(
        host=host,
        port=port,
        exposed=_sorted_paths(exposed),
        writable=_sorted_paths(writable),
        descriptions=_descriptions(nodes, exposed, sources) if serve else (),
        anonymous=checker.flag(settings, "anonymous", "opcua", False),
        trust_unknown_clients=checker.flag(settings, "trust_unknown_clients", "opcua", False),
    )
    mapped = {
        key(point.variable): f"Modbus device '{device.name}'"
        for device in (modbus.devices if modbus is not None else ())
        for point in device.points
    }
    devices = _devices(checker, settings.get("device", []), mapped)
    config = OpcuaConfig(server=server if serve else None, devices=devices)
    return config, checker.diagnostics


def _nodes(resolved: Resolved, programs: list[ProgramConfig]) -> dict[str, _Node]:
    """Every path of the resource by upper-case path: the variables the configuration's
    paths reach (`var_config.instance_variables`: the globals, the programs' variables, the
    members of block instances), the program instances, and what lies inside structures and
    the elements of arrays (these under `[*]`)."""
    nodes: dict[str, _Node] = {}
    for program in programs:
        pou = resolved.pous.get(key(program.pou))
        if pou is not None and pou.kind == "PROGRAM":
            nodes.setdefault(key(program.name), _Node(program.name, pou=pou))
    found = instance_variables(resolved, programs)
    for upper in sorted(found, key=len):  # a path after those it lies in
        path, variable = found[upper]
        in_constant = any(nodes[p].constant for p in _prefixes(upper) if p in nodes)
        nodes[upper] = _Node(path, variable, constant=variable.constant or in_constant)
    for upper, (path, variable) in found.items():
        constant = nodes[upper].constant
        for inner_path, inner in _inside(resolved, path, variable.type, False, 0):
            nodes.setdefault(key(inner_path), _Node(inner_path, inner, constant=constant))
    return nodes


def _inside(
    resolved: Resolved, path: str, t: Type, blocks: bool, depth: int
) -> Iterator[tuple[str, Variable]]:
    """What lies below a variable of type `t` that `instance_variables` does not list: the
    members of structures, and everything in the elements of arrays; the members of a
    block instance only within an array (`blocks`: there)."""
    if depth > MAX_DEPTH:
        return
    members: list[Variable] = []
    if isinstance(t, StructType) and key(t.name) in resolved.structs:
        members = resolved.structs[key(t.name)].members
    elif isinstance(t, FbType) and blocks and key(t.name) in resolved.pous:
        members = [v for v in resolved.pous[key(t.name)].variables if _in_instance(v)]
    elif isinstance(t, ArrayType):
        yield from _inside(resolved, f"{path}[*]", t.element, True, depth + 1)
    for member in members:
        inner = f"{path}.{member.name}"
        yield inner, member
        yield from _inside(resolved, inner, member.type, blocks, depth + 1)


def _in_instance(variable: Variable) -> bool:
    """A variable that an instance holds and that has a path (as in `instance_variables`)."""
    return variable.kind not in ("VAR_GLOBAL", "VAR_EXTERNAL", "VAR_TEMP", "VAR_IN_OUT")


def _prefixes(upper: str) -> Iterator[str]:
    """The paths a path lies in: `A.B` for `A.B.C`."""
    while "." in upper:
        upper = upper.rpartition(".")[0]
        yield upper


def _paths(
    checker: _Checker, settings: dict[str, Any], name: str, nodes: dict[str, _Node]
) -> dict[str, _Node]:
    """The paths of `expose` or `writable`, by upper-case path; each one that names nothing
    is reported."""
    entries = settings.get(name, [])
    where = f"opcua.{name}"
    if not isinstance(entries, list) or not all(isinstance(e, str) for e in entries):
        checker.report(where, Code.OPCUA_SETTING, f"[opcua] {name} must be a list of paths")
        return {}
    found: dict[str, _Node] = {}
    for entry in entries:
        upper = key(entry.strip())
        node = nodes.get(upper) if "[" not in upper else None
        if node is None:
            if "[" in entry:
                why = "an array is exposed whole, never one of its elements"
            else:
                why = (
                    "no program instance or variable of the resource has it (a global by its "
                    "name, a program's variable as Program.variable, members after a dot)"
                )
            checker.report(where, Code.OPCUA_PATH, f"[opcua] {name} '{entry}': {why}")
            continue
        found[upper] = node
    return found


def _check_writable(
    checker: _Checker, writable: dict[str, _Node], exposed: dict[str, _Node]
) -> None:
    for upper, node in sorted(writable.items()):
        if upper not in exposed and not any(p in exposed for p in _prefixes(upper)):
            message = (
                f"writable '{node.path}' is not exposed: add it, or a path it is in, to expose"
            )
            checker.report("opcua.writable", Code.OPCUA_WRITABLE, message)
        elif node.constant:
            message = f"writable '{node.path}' is a CONSTANT (or in one): it cannot be written"
            checker.report("opcua.writable", Code.OPCUA_WRITABLE, message)


def _sorted_paths(paths: dict[str, _Node]) -> tuple[str, ...]:
    return tuple(sorted(node.path for node in paths.values()))


def _descriptions(
    nodes: dict[str, _Node], exposed: dict[str, _Node], sources: list[SourceFile]
) -> tuple[tuple[str, str], ...]:
    """(path, comment) of every exposed path and every path below one that has a
    declaration comment, sorted by path."""
    if not exposed:
        return ()
    texts = {source.name: source.text for source in sources}
    order = sorted(nodes)
    chosen = set(exposed)
    for upper in exposed:
        for below in (f"{upper}.", f"{upper}["):  # apart in the order: `A.x` < `AB` < `A[*]`
            start = bisect_left(order, below)
            for inner in order[start:]:
                if not inner.startswith(below):
                    break
                chosen.add(inner)
    described: list[tuple[str, str]] = []
    for upper in chosen:
        node = nodes[upper]
        if node.pou is not None:
            pos = node.pou.pou.pos
        elif node.variable is not None:
            pos = node.variable.pos
        else:
            continue
        if pos.file not in texts and pos.file.startswith("stdlib/"):
            texts.update((s.name, s.text) for s in stdlib_sources())
        comment = declaration_comment(texts.get(pos.file), pos)
        if comment:
            described.append((node.path, comment))
    return tuple(sorted(described))


def _devices(checker: _Checker, entries: Any, mapped: dict[str, str]) -> tuple[OpcuaDevice, ...]:
    if not isinstance(entries, list):
        checker.report("opcua.device", Code.OPCUA_SETTING, "[[opcua.device]] must be tables")
        return ()
    devices: list[OpcuaDevice] = []
    for index, entry in enumerate(entries):
        path = f"opcua.device.{index}"
        if not isinstance(entry, dict):
            checker.report(path, Code.OPCUA_SETTING, "[[opcua.device]] must be a table")
            continue
        checker.unknown_keys(entry, DEVICE_KEYS, path)
        name = entry.get("name")
        if not isinstance(name, str) or not DEVICE_NAME.match(name):
            checker.report(
                path, Code.OPCUA_SETTING,
                f"[[opcua.device]] needs a name of 1 to 32 of A-Z a-z 0-9 _ -, not {name!r}",
            )  # fmt: skip
            continue
        if any(key(d.name) == key(name) for d in devices):
            checker.report(path, Code.OPCUA_SETTING, f"OPC UA device '{name}' is defined twice")
            continue
        device = OpcuaDevice(
            name=name,
            endpoint=_endpoint(checker, entry, path, name),
            security=checker.choice(entry, "security", path, "sign_encrypt", SECURITY),
            user=_user(checker, entry, path, name),
            password_file=_password_file(checker, entry, path, name),
            mode=checker.choice(entry, "mode", path, "subscribe", MODES),
            period_ms=checker.integer(entry, "period_ms", path, 100, MIN_PERIOD_MS, MAX_PERIOD_MS),
            timeout_ms=checker.integer(entry, "timeout_ms", path, 1000, 1, MAX_TIMEOUT_MS),
            points=_points(checker, entry.get("point", []), path, name, mapped),
        )
        devices.append(device)
    return tuple(sorted(devices, key=lambda d: d.name))


def _endpoint(checker: _Checker, entry: dict[str, Any], path: str, device: str) -> str:
    endpoint = entry.get("endpoint")
    if endpoint is None:
        message = f"OPC UA device '{device}' needs an endpoint (opc.tcp://host:port)"
        checker.report(path, Code.OPCUA_SETTING, message)
        return ""
    found = ENDPOINT.match(endpoint) if isinstance(endpoint, str) else None
    port = found["port"] if found is not None else None
    if (
        found is None
        or len(endpoint) > MAX_ENDPOINT
        or (port is not None and not 1 <= int(port) <= 65535)
    ):
        checker.report(
            f"{path}.endpoint", Code.OPCUA_ENDPOINT,
            f"OPC UA device '{device}': endpoint {endpoint!r} is no opc.tcp://host[:port][/path] "
            "(a port 1..65535, a path of printable characters without spaces)",
        )  # fmt: skip
        return ""
    return str(endpoint)


def _user(checker: _Checker, entry: dict[str, Any], path: str, device: str) -> str:
    user = entry.get("user", "")
    if not isinstance(user, str) or (user and not USER.match(user)):
        message = f"OPC UA device '{device}': user must be a name of 1 to 128 characters"
        checker.report(f"{path}.user", Code.OPCUA_SETTING, message)
        return ""
    if user and "password_file" not in entry:
        message = (
            f"OPC UA device '{device}': user '{user}' needs a password_file, the file on the "
            "runtime's host that holds the password"
        )
        checker.report(f"{path}.user", Code.OPCUA_SETTING, message)
    return user


def _password_file(checker: _Checker, entry: dict[str, Any], path: str, device: str) -> str:
    if "password_file" not in entry:
        return ""
    name = entry["password_file"]
    absolute = isinstance(name, str) and (
        PurePosixPath(name).is_absolute() or PureWindowsPath(name).is_absolute()
    )
    if not absolute or "\x00" in name or len(name) > MAX_PATH_FILE:
        message = (
            f"OPC UA device '{device}': password_file must be an absolute path on the "
            f"runtime's host, not {name!r}"
        )
        checker.report(f"{path}.password_file", Code.OPCUA_SETTING, message)
        return ""
    if not entry.get("user"):
        message = f"OPC UA device '{device}': a password_file without a user"
        checker.report(f"{path}.password_file", Code.OPCUA_SETTING, message)
    return str(name)


def _points(
    checker: _Checker, entries: Any, device_path: str, device: str, mapped: dict[str, str]
) -> tuple[OpcuaPoint, ...]:
    if not isinstance(entries, list):
        message = f"OPC UA device '{device}': points must be tables"
        checker.report(device_path, Code.OPCUA_SETTING, message)
        return ()
    points: list[OpcuaPoint] = []
    for index, entry in enumerate(entries):
        path = f"{device_path}.point.{index}"
        if not isinstance(entry, dict):
            checker.report(path, Code.OPCUA_SETTING, "[[opcua.device.point]] must be a table")
            continue
        checker.unknown_keys(entry, POINT_KEYS, path)
        missing = [k for k in ("variable", "node") if k not in entry]
        if missing:
            message = f"a point of OPC UA device '{device}' needs {' and '.join(missing)}"
            checker.report(path, Code.OPCUA_SETTING, message)
            continue
        node = _node_id(checker, entry["node"], f"{path}.node", device)
        variable = _located(checker, entry["variable"], f"{path}.variable", device)
        if variable is None or node is None:
            continue
        assert variable.location is not None
        type_name = _type_text(variable.type)
        label = f"'{variable.name}' ({variable.location}) of OPC UA device '{device}'"
        if key(variable.name) in mapped:
            message = f"{label}: already mapped by {mapped[key(variable.name)]}"
            checker.report(f"{path}.variable", Code.OPCUA_MAPPED_TWICE, message)
            continue
        mapped[key(variable.name)] = f"OPC UA device '{device}'"
        safe = _safe_value(checker, entry, path, variable, type_name, label)
        points.append(OpcuaPoint(variable.name, variable.location, type_name, node, safe))
    return tuple(sorted(points, key=lambda p: key(p.variable)))


def _located(checker: _Checker, name: Any, path: str, device: str) -> Variable | None:
    """The located global of a point: an input (%I) or an output (%Q) of an elementary type
    that values from outside can be stored in."""
    variable = checker.resolved.globals_by_key.get(key(name)) if isinstance(name, str) else None
    location = variable.location if variable is not None else None
    if variable is None or location is None or location.endswith("*"):
        message = f"OPC UA point '{name}' of device '{device}': no global with a complete location"
        checker.report(path, Code.OPCUA_VARIABLE, message)
        return None
    label = f"'{variable.name}' ({location}) of OPC UA device '{device}'"
    if location.lstrip("%")[:1].upper() not in ("I", "Q"):
        message = f"{label}: a device delivers inputs (%I) or takes outputs (%Q)"
        checker.report(path, Code.OPCUA_VARIABLE, message)
        return None
    if not isinstance(variable.type, ElementaryType) or _stored(variable.type) is None:
        message = f"{label}: {variable.type.name} is no elementary type a node's value fits"
        checker.report(path, Code.OPCUA_VARIABLE, message)
        return None
    return variable


def _node_id(checker: _Checker, text: Any, path: str, device: str) -> str | None:
    """The node's id as written, when it reads as an OPC UA NodeId."""
    problem = _node_problem(text)
    if problem is None:
        assert isinstance(text, str)
        return text
    checker.report(
        path, Code.OPCUA_NODE,
        f"OPC UA device '{device}': node {text!r} {problem} (ns=<namespace>;i=<number>, "
        "ns=<namespace>;s=<text>, ns=<namespace>;g=<guid>, ns=<namespace>;b=<base64>, or "
        "i=<number>)",
    )  # fmt: skip
    return None


def _node_problem(text: Any) -> str | None:
    if not isinstance(text, str):
        return "is no text"
    found = NODE.match(text)
    if found is None:
        return "is no node id"
    kind, identifier = found["kind"], found["id"]
    if found["ns"] is None and kind != "i":
        return "names no namespace"
    if found["ns"] is not None and int(found["ns"]) > 65535:
        return "has a namespace beyond 65535"
    if kind == "i":
        if not identifier.isascii() or not identifier.isdigit() or int(identifier) >= 1 << 32:
            return "has no number 0..4294967295 after i="
    elif kind == "s":
        if not identifier or len(identifier) > MAX_NODE_ID:
            return f"has no text of 1 to {MAX_NODE_ID} characters after s="
        if re.search(r"[\x00-\x1f\x7f]", identifier):
            return "has a control character in its text"
    elif kind == "g":
        if not GUID.match(identifier):
            return "has no GUID (xxxxxxxx-xxxx-xxxx-xxxx-xxxxxxxxxxxx) after g="
    else:
        try:
            opaque = base64.b64decode(identifier, validate=True)
        except (binascii.Error, ValueError):
            opaque = b""
        if not opaque or len(opaque) > MAX_NODE_ID:
            return f"has no base64 of 1 to {MAX_NODE_ID} bytes after b="
    return None


def _safe_value(
    checker: _Checker,
    entry: dict[str, Any],
    path: str,
    variable: Variable,
    type_name: str,
    label: str,
) -> Any:
    default = _stored(variable.type)
    if "safe_value" not in entry:
        return default
    assert variable.location is not None
    if not variable.location.upper().startswith("%I"):
        checker.report(
            f"{path}.safe_value", Code.OPCUA_SETTING,
            f"{label}: outputs take the resource's safe values ([resource.safe_values])",
        )  # fmt: skip
        return default
    try:
        return representation(type_name, entry["safe_value"])
    except ValueRejected as exc:
        message = f"safe value of '{variable.name}': {exc}"
        checker.report(f"{path}.safe_value", Code.OPCUA_SETTING, message)
        return default


def _stored(t: Type) -> bool | int | float | str | None:
    """The value a variable of an elementary type starts from (a safe value by default), or
    None for a type that values from outside are never stored in."""
    if not isinstance(t, ElementaryType):
        return None
    value: bool | int | str = False if t.category == "bool" else "" if t.category == "string" else 0
    try:
        stored: bool | int | float | str = representation(_type_text(t), value)
    except ValueRejected:
        return None
    return stored


def _type_text(t: Type) -> str:
    """An elementary type as the artifact names it: a string with its length (`STRING[80]`),
    as the runtime checks what it stores."""
    if isinstance(t, ElementaryType) and t.category == "string" and t.name in ("STRING", "WSTRING"):
        return f"{t.name}[{t.max_length}]"
    return t.name
