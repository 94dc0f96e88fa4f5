"""The compiled artifact: the versioned contract between the compiler and the runtime.

An artifact is canonical JSON (sorted keys, no spaces): the typed form of every POU (data
the runtime checks and prints as Python itself, runtime/contract/code/), the variable
tables the runtime needs for OLT and context saving, the user
programs with their parameters, and the CRCs. `docs/artifact.md` documents the format.
The configuration CRC is a CRC-32 over the canonical JSON of everything but the CRC
itself, so the runtime can check that what it received is exactly what was compiled.
"""

from __future__ import annotations

import json
import zlib
from dataclasses import asdict, dataclass, field
from typing import Any

from runtime.contract.code.form_check import check_unit
from runtime.contract.code.form_json import FormRefused, decode_unit
from runtime.contract.code.form_size import UnitCells, check_cells, unit_cells
from runtime.contract.code.python_text import unit_lines
from runtime.contract.code.units import Unit
from runtime.contract.exchange import ExchangeConfig, exchange_config
from runtime.contract.modbus import ModbusConfig, modbus_config
from runtime.contract.opcua import OpcuaConfig, opcua_config
from runtime.contract.outside_json import MIB, JsonRefused, read_json

FORMAT = "padt-artifact"
# 3: Modbus TCP (`modbus`); 4: `_tick` is None while no slice is metered; 5: each unit's
# typed form (`form`) instead of its Python source
VERSION = 5
MAX_ARTIFACT_BYTES = 64 * MIB  # as protocol.MAX_ARTIFACT: a larger one could never be loaded


class ArtifactError(ValueError):
    """The artifact is malformed, of another version, or its CRC does not match."""


@dataclass(frozen=True)
class VarInfo:
    name: str  # as declared in ST
    attr: str  # attribute name in the generated class
    type: str  # elementary type name, or the POU name of a function block
    kind: str  # VAR, VAR_INPUT, VAR_OUTPUT, ...
    retain: bool = False
    constant: bool = False
    location: str | None = None


@dataclass(frozen=True)
class Association:
    """A step naming an action with a qualifier (`S1: A(D, T#5s);`)."""

    step: str
    action: str
    qualifier: str


@dataclass(frozen=True)
class ChartInfo:
    """The structure of a POU's sequential function chart, for reload analysis."""

    steps: tuple[str, ...]  # as declared; each is also a variable of type SFC_STEP
    initial: tuple[str, ...]
    associations: tuple[Association, ...]
    controls: tuple[tuple[str, str], ...]  # (action, slot of its action control block)


@dataclass(frozen=True)
class PouCode:
    """One unit: a POU, a structure or the globals. Its code comes as its typed form, which
    the runtime decodes, checks and prints as Python itself (`unit`, `source`): nothing an
    artifact carries is run as it came."""

    name: str
    kind: str  # PROGRAM | FUNCTION_BLOCK | FUNCTION | STRUCT | GLOBALS
    class_name: str
    form: str  # the typed form (runtime/contract/code/form_json.py)
    crc: str
    variables: tuple[VarInfo, ...]
    file: str = ""  # the ST source file of a POU
    chart: ChartInfo | None = None
    # a FUNCTION's result type as `VarInfo.type` names types ("" without one): what a
    # caller in the native tier unboxes its result as
    returns: str = ""

    @property
    def unit(self) -> Unit:
        """The typed form, decoded and checked (FormRefused where it is not a unit's).
        Decoded anew at each call, but for the compiler's own code (`knowing`): a runtime
        keeps the Python it printed, not the tree of nodes (hundreds of thousands of
        objects for a large program, which the collector would walk and a reload free)."""
        known: Unit | None = self.__dict__.get("_known")
        if known is not None:
            return known
        what = f"the form of {self.kind} {self.name}"
        unit = decode_unit(self.form, what)
        check_unit(unit, self.kind, self.class_name, what)
        return unit

    def knowing(self, unit: Unit, source: str, st_lines: tuple[int, ...]) -> PouCode:
        """This code, given the unit its form was encoded from and its printed Python (the
        compiler's, in the process that compiled it): a process that runs what it
        compiled need not decode and print its own encoding again."""
        # not fields: no part of the artifact or its CRC
        self.__dict__["_known"], self.__dict__["_printed"] = unit, (source, st_lines)
        return self

    def printed_from(self, unit: Unit) -> tuple[str, tuple[int, ...]]:
        """The Python printed from `unit`, this code's form decoded, and the ST line of each
        of its lines; printed once (two threads that ask at once may both print it: the
        same text)."""
        printed: tuple[str, tuple[int, ...]] | None = self.__dict__.get("_printed")
        if printed is None:
            lines = list(unit_lines(unit))
            text = "\n".join(line for line, _ in lines) + "\n"
            printed = self.__dict__["_printed"] = (text, tuple(st for _, st in lines))
        return printed

    def _text(self) -> tuple[str, tuple[int, ...]]:
        printed: tuple[str, tuple[int, ...]] | None = self.__dict__.get("_printed")
        return printed if printed is not None else self.printed_from(self.unit)

    @property
    def source(self) -> str:
        """The unit's Python, as the runtime prints it from the form."""
        return self._text()[0]

    @property
    def st_lines(self) -> tuple[int, ...]:
        """Per line of `source`: its line in `file` (0: none)."""
        return self._text()[1]


@dataclass(frozen=True)
class ProgramConfig:
    """A user program: an instance of a PROGRAM POU scheduled on the resource, with its
    parameters (ranges in runtime/parameters.py, meaning in docs/parameters.md)."""

    name: str
    pou: str
    program_id: int
    priority: int = 0  # 0 runs first
    max_duration_us: int = 0  # time slice per CPU cycle; 0: always runs to its end
    max_cycles: int = 1  # CPU cycles one program cycle may span
    start_allowed: bool = True
    freeze_allowed: bool = True  # single step possible
    reload_allowed: bool = True
    local_forcing_allowed: bool = False
    local_force_timeout_reaction: str = "stop-forcing"  # | stop-program
    safety_related: bool = False  # always cold-starts
    crc: str = ""
    # attribute names (in `_G`) of the globals the program writes, and of those it reads
    # without writing: what is copied out of and into its view of the globals
    writes: tuple[str, ...] = ()
    reads: tuple[str, ...] = ()


@dataclass(frozen=True)
class ResourceConfig:
    """The resource parameters (ranges in runtime/parameters.py, docs/parameters.md)."""

    name: str
    safety_time_ms: int = 600
    watchdog_ms: int = 200  # a CPU cycle longer than this is ERROR STOP
    target_cycle_ms: int = 0  # 0: no target, the cycle is as long as its work
    target_cycle_mode: str = "fixed-tolerant"
    multitasking_mode: int = 1
    com_slice_ms: int = 10  # time for communication in each cycle's housekeeping
    allow_online_settings: bool = True
    autostart: str = "off"  # off | cold | warm
    start_allowed: bool = True
    load_allowed: bool = True
    reload_allowed: bool = True
    global_forcing_allowed: bool = False
    global_force_timeout_reaction: str = "stop-forcing"  # | stop-resource
    safety_operation: bool = True  # no single step, forcing or OLT writes while ON


@dataclass(frozen=True)
class UserAccount:
    """A PES user: name, access level, and the salted scrypt hash of the password."""

    name: str
    level: str  # read | operator | read-write | administrator
    password_hash: str  # scrypt$N$r$p$salt$hash (base64)


@dataclass(frozen=True)
class AccessPath:
    """A VAR_ACCESS entry of the configuration: a name for a variable of the resource."""

    name: str
    path: str  # the variable's path in the resource (`Main.d1.open`) or a direct address
    type: str
    writable: bool  # READ_WRITE; else READ_ONLY


# fields added within version 4: left out of the CRC while empty, so that a configuration
# that does not use them keeps its CRC (and a runtime that does not know them refuses one
# that does: its CRC does not match)
_OPTIONAL_FIELDS = ("located", "access_paths", "opcua", "exchange")


@dataclass(frozen=True)
class Artifact:
    project: str
    resource: ResourceConfig
    pous: tuple[PouCode, ...]  # PROGRAM, FUNCTION_BLOCK, FUNCTION
    programs: tuple[ProgramConfig, ...]
    types: tuple[PouCode, ...] = ()  # STRUCT classes
    globals: PouCode | None = None  # the GLOBALS class (its instance is `_G`)
    # outputs whose safe value (in STOP and ERROR STOP) is not 0 / FALSE, by path, sorted
    safe_values: tuple[tuple[str, Any], ...] = ()
    users: tuple[UserAccount, ...] = ()  # none: open access (simulation, tests)
    # the served image and the remote devices (modbus.py)
    modbus: ModbusConfig = field(default_factory=ModbusConfig)
    # variables with a partly specified location (`AT %I*`) by path, with the address the
    # configuration's VAR_CONFIG gives them, sorted
    located: tuple[tuple[str, str], ...] = ()
    access_paths: tuple[AccessPath, ...] = ()  # sorted by name
    # the served address space and the remote servers (opcua.py); None: no OPC UA at all
    opcua: OpcuaConfig | None = None
    # the variable exchange with other resources (exchange.py); None: none
    exchange: ExchangeConfig | None = None
    crc: str = field(default="")
    format: str = FORMAT
    version: int = VERSION

    def pou(self, name: str) -> PouCode:
        for pou in self.pous:
            if pou.name.upper() == name.upper():
                return pou
        raise ArtifactError(f"artifact has no POU '{name}'")

    def units(self) -> tuple[PouCode, ...]:
        """Every unit: the structures, the POUs, the globals."""
        return (*self.types, *self.pous, *((self.globals,) if self.globals else ()))

    def body_json(self) -> str:
        """Canonical JSON of everything the configuration CRC covers."""
        data = asdict(self)
        del data["crc"]
        for name in _OPTIONAL_FIELDS:
            if not data[name]:
                del data[name]
        for unit in (*data["pous"], *data["types"], data["globals"]):
            if unit is not None and not unit["returns"]:  # a CRC as before the field was
                del unit["returns"]
        return canonical_json(data)

    def with_crc(self) -> Artifact:
        return Artifact(**{**self.__dict__, "crc": crc32_hex(self.body_json())})

    def to_json(self) -> str:
        return canonical_json(asdict(self))


def canonical_json(data: Any) -> str:
    return json.dumps(data, sort_keys=True, separators=(",", ":"), ensure_ascii=True)


def crc32_hex(text: str) -> str:
    return f"{zlib.crc32(text.encode('utf-8')):08X}"


def _pou_code(data: dict[str, Any]) -> PouCode:
    variables = tuple(VarInfo(**v) for v in data["variables"])
    chart = data["chart"]
    if chart is not None:
        chart = ChartInfo(
            steps=tuple(chart["steps"]),
            initial=tuple(chart["initial"]),
            associations=tuple(Association(**a) for a in chart["associations"]),
            controls=tuple((action, slot) for action, slot in chart["controls"]),
        )
    return PouCode(**{**data, "variables": variables, "chart": chart})


def _program_config(data: dict[str, Any]) -> ProgramConfig:
    return ProgramConfig(**{**data, "writes": tuple(data["writes"]), "reads": tuple(data["reads"])})


def load_artifact(text: str | bytes) -> Artifact:
    """Parse and verify an artifact; raises ArtifactError on anything wrong."""
    try:
        data = read_json(text, "the artifact", MAX_ARTIFACT_BYTES)
    except JsonRefused as exc:
        raise ArtifactError(str(exc)) from None
    if not isinstance(data, dict) or data.get("format") != FORMAT:
        raise ArtifactError("not a padt artifact")
    if data.get("version") != VERSION:
        raise ArtifactError(f"artifact version {data.get('version')} is not {VERSION}")
    try:
        artifact = Artifact(
            project=data["project"],
            resource=ResourceConfig(**data["resource"]),
            pous=tuple(_pou_code(p) for p in data["pous"]),
            programs=tuple(_program_config(p) for p in data["programs"]),
            types=tuple(_pou_code(p) for p in data["types"]),
            globals=_pou_code(data["globals"]) if data["globals"] is not None else None,
            safe_values=tuple((name, value) for name, value in data["safe_values"]),
            users=tuple(UserAccount(**user) for user in data["users"]),
            modbus=modbus_config(data["modbus"]),
            located=tuple((path, location) for path, location in data.get("located", ())),
            access_paths=tuple(AccessPath(**entry) for entry in data.get("access_paths", ())),
            opcua=opcua_config(data["opcua"]) if data.get("opcua") is not None else None,
            exchange=(
                exchange_config(data["exchange"]) if data.get("exchange") is not None else None
            ),
            crc=data["crc"],
        )
    except (KeyError, TypeError, ValueError, AttributeError) as exc:  # ValueError: unpacking
        raise ArtifactError(f"artifact is incomplete: {exc}") from None
    expected = crc32_hex(artifact.body_json())
    if artifact.crc != expected:
        raise ArtifactError(f"artifact CRC {artifact.crc} does not match its content ({expected})")
    try:
        check_cells([_decoded_and_printed(unit) for unit in artifact.units()], _instances(artifact))
    except FormRefused as exc:
        raise ArtifactError(str(exc)) from None
    return artifact


def _decoded_and_printed(unit: PouCode) -> UnitCells:
    """Decode and check a unit's form, print its Python once, and keep of its nodes only
    what they allocate (a runtime keeps the text, not the tree)."""
    decoded = unit.unit
    cells = unit_cells(decoded)
    unit.printed_from(decoded)
    return cells


def _instances(artifact: Artifact) -> dict[str, int]:
    """How many instances of each class a resource sets up, at most: one of each PROGRAM and
    one for each user program of it, the globals once and once more for each program's
    view of them (runtime/code/instances.py)."""
    classes = {pou.name.upper(): pou.class_name for pou in artifact.pous}
    counted: dict[str, int] = {}
    for name in [p.name for p in artifact.pous if p.kind == "PROGRAM"] + [
        program.pou for program in artifact.programs
    ]:
        if (class_name := classes.get(name.upper())) is not None:
            counted[class_name] = counted.get(class_name, 0) + 1
    if artifact.globals is not None:
        counted[artifact.globals.class_name] = 1 + len(artifact.programs)
    return counted
