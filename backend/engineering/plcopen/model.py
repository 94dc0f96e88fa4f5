"""A PLCopen project as the import needs it: small dataclasses, types and values already as
ST text (the reader turns the XML's type and value elements into that text)."""

from __future__ import annotations

from dataclasses import dataclass, field

from backend.compiler.graphics.model import GraphicBody
from backend.engineering.plcopen.issues import Where


@dataclass(frozen=True)
class Variable:
    name: str
    type: str  # ST: `INT`, `ARRAY [1..3] OF REAL`, `STRING[10]`, ...
    address: str = ""  # `%IX0.0`, or empty
    initial: str = ""  # ST initializer, or empty
    comment: str = ""

    def declaration(self) -> str:
        """`name AT %IX0.0 : TYPE := value` (without the `;`)."""
        located = f" AT {self.address}" if self.address else ""
        initial = f" := {self.initial}" if self.initial else ""
        return f"{self.name}{located} : {self.type}{initial}"


@dataclass(frozen=True)
class VarSection:
    kind: str  # VAR_INPUT, VAR_OUTPUT, VAR_IN_OUT, VAR, VAR_TEMP, VAR_EXTERNAL, VAR_GLOBAL
    qualifiers: tuple[str, ...]  # CONSTANT, RETAIN, NON_RETAIN, PERSISTENT
    variables: tuple[Variable, ...]


@dataclass(frozen=True)
class DataType:
    name: str
    declaration: str  # ST after `Name :`, initial value included, without the `;`
    where: Where


@dataclass(frozen=True)
class Action:
    name: str
    body: str  # ST statements
    drawing: GraphicBody | None = None  # or a drawing in FBD or LD


@dataclass(frozen=True)
class Method:
    """A CODESYS method (in a POU's or an interface's <addData>)."""

    name: str
    access: str  # PUBLIC, PRIVATE, PROTECTED, INTERNAL: always written (see access_of)
    modifiers: tuple[str, ...]  # ABSTRACT, FINAL
    return_type: str  # or empty
    sections: tuple[VarSection, ...]
    body: str | None  # ST statements; None: a prototype (of an interface) or ABSTRACT
    comment: str = ""


@dataclass(frozen=True)
class Accessor:
    """The GET or SET of a property: its own variables and its ST body."""

    sections: tuple[VarSection, ...]
    body: str


@dataclass(frozen=True)
class Property:
    name: str
    access: str
    modifiers: tuple[str, ...]
    type: str
    get: Accessor | None
    set: Accessor | None
    comment: str = ""


@dataclass(frozen=True)
class Pou:
    name: str
    kind: str  # PROGRAM, FUNCTION_BLOCK, FUNCTION
    return_type: str  # a FUNCTION's, or empty
    sections: tuple[VarSection, ...]
    body: str  # ST statements and textual SFC
    actions: tuple[Action, ...]
    comment: str
    where: Where
    extends: str = ""  # CODESYS's <Inheritance>: the base function block, or empty
    implements: tuple[str, ...] = ()
    methods: tuple[Method, ...] = ()
    properties: tuple[Property, ...] = ()
    graphic: GraphicBody | None = None  # a body drawn in FBD or LD (`body` empty)


@dataclass(frozen=True)
class Interface:
    """A CODESYS interface (the project's <addData>): prototypes without bodies."""

    name: str
    extends: tuple[str, ...]
    methods: tuple[Method, ...]
    properties: tuple[Property, ...]
    comment: str
    where: Where


@dataclass(frozen=True)
class NotImported:
    """A POU the import leaves out, and why (`IL`, or a sentence). `problem`: the place of
    a fault in one of its drawings (reported there, with its own code)."""

    name: str
    reason: str
    where: Where
    problem: Where | None = None


@dataclass(frozen=True)
class Task:
    name: str
    priority: int
    interval_ms: int | None  # None: no interval (an event task)
    where: Where


@dataclass(frozen=True)
class Instance:
    name: str
    pou: str
    task: str  # empty: none
    where: Where


@dataclass(frozen=True)
class Resource:
    name: str
    tasks: tuple[Task, ...]
    instances: tuple[Instance, ...]
    globals: tuple[VarSection, ...]
    where: Where


@dataclass(frozen=True)
class Configuration:
    name: str
    resources: tuple[Resource, ...]
    globals: tuple[VarSection, ...]
    where: Where


@dataclass
class PlcProject:
    name: str
    version: str = ""
    types: list[DataType] = field(default_factory=list)
    pous: list[Pou] = field(default_factory=list)
    interfaces: list[Interface] = field(default_factory=list)
    not_imported: list[NotImported] = field(default_factory=list)
    configurations: list[Configuration] = field(default_factory=list)
    # global variable lists outside the configuration (CODESYS puts its GVLs in <addData>)
    globals: list[VarSection] = field(default_factory=list)
    dropped: list[Dropped] = field(default_factory=list)
    # what the import reads and leaves out, to be reported (accessVars, configVars)
    left_out: list[tuple[Where, str]] = field(default_factory=list)


@dataclass(frozen=True)
class Dropped:
    """Part of an imported data type that is not imported (the EXTENDS of a CODESYS
    structure, in its <addData>)."""

    owner: str
    what: str
    where: Where
