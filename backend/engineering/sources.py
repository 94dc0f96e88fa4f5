"""The ST source of the running configuration, for the Code screen: which of the projects
the PADT knows compiles to the configuration CRC a resource runs, the source of each of its
POUs with the variables each line mentions, and which POU a program or FB instance is.

A source is shown only for the CRC it compiles to: a project edited since the download
compiles to another CRC and is not taken for the running one."""

from __future__ import annotations

import dataclasses
import re
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path

from backend.compiler import ast
from backend.compiler.checks.sfc import bool_actions
from backend.compiler.pipeline import parse_all
from backend.compiler.source import Pos, SourceFile, stdlib_sources
from backend.engineering.project import ProjectError, compile_project, load_project
from runtime.contract.artifact import Artifact, PouCode, VarInfo
from runtime.contract.values import array_shape

_NOT_OF_THE_INSTANCE = ("VAR_EXTERNAL", "VAR_GLOBAL")  # named by their bare global path


@dataclass(frozen=True)
class Mention:
    """A variable a line of source names, as written relative to the POU (`level`,
    `refillDelay.Q`, `points[2].x`); `local`: a variable of the instance, else a global."""

    text: str
    local: bool
    col: int


@dataclass(frozen=True)
class PouSource:
    name: str
    kind: str  # PROGRAM, FUNCTION_BLOCK, FUNCTION
    file: str  # as the compiler names it: relative to the project, or stdlib/<file>
    first_line: int  # the line of `PROGRAM ...` in the file
    lines: tuple[str, ...]  # the POU's lines, from `first_line` to its END_...
    mentions: dict[int, tuple[Mention, ...]]  # line in the file -> what it names, by column

    @property
    def last_line(self) -> int:
        return self.first_line + len(self.lines) - 1

    @property
    def standard(self) -> bool:
        """Part of the PADT's standard library (TON, CTU, ...), not of the project."""
        return self.file.startswith("stdlib/")


@dataclass(frozen=True)
class ConfigurationSources:
    """The sources of one configuration: the project that compiles to `crc`, its artifact
    (programs and variable tables) and the ST of its POUs (the standard ones included)."""

    crc: str
    project: str  # the PADT's name for the project
    artifact: Artifact
    pous: dict[str, PouSource]  # by upper-case name

    def pou_of(self, instance: str) -> PouCode | None:
        """The POU a program (`TankControl`) or FB instance (`TankControl.refillDelay`,
        `Line.valves[2]`) is an instance of; None for anything else (a struct, a value)."""
        head, *members = instance.split(".")
        program = next((p for p in self.artifact.programs if p.name.upper() == head.upper()), None)
        if program is None:
            return None
        unit = _unit(self.artifact, program.pou)
        for member in members:
            if unit is None:
                return None
            name, indexed = _strip_index(member)
            declared = next((v for v in unit.variables if v.name.upper() == name.upper()), None)
            if declared is None:
                return None
            type_name = declared.type
            if indexed:
                shape = array_shape(type_name)
                if shape is None:
                    return None
                type_name = shape.element
            unit = _unit(self.artifact, type_name)
        if unit is None or unit.kind not in ("PROGRAM", "FUNCTION_BLOCK"):
            return None
        return unit

    def source_of(self, instance: str) -> PouSource | None:
        unit = self.pou_of(instance)
        return self.pous.get(unit.name.upper()) if unit is not None else None

    def interface_of(self, instance: str) -> tuple[VarInfo, ...]:
        unit = self.pou_of(instance)
        return unit.variables if unit is not None else ()


def find_sources(crc: str, projects: Mapping[str, Path]) -> ConfigurationSources | None:
    """The sources of the configuration `crc` among the project folders the PADT knows:
    each is compiled, and the first whose configuration CRC is `crc` is taken. None when no
    project compiles to it (edited since, or never known here)."""
    for name, folder in sorted(projects.items()):
        try:
            project = load_project([folder])
        except (ProjectError, OSError):
            continue  # a project that cannot be read is not the running one
        result = compile_project(project)
        if result.artifact is not None and result.artifact.crc == crc.upper():
            return ConfigurationSources(
                crc=result.artifact.crc,
                project=name,
                artifact=result.artifact,
                pous=pou_sources([*project.sources, *stdlib_sources()]),
            )
    return None


def pou_sources(files: list[SourceFile]) -> dict[str, PouSource]:
    """Every POU of `files` with its lines and what each line mentions; a user POU of the
    same name as a standard one replaces it, as in the compiler."""
    units, _ = parse_all(files)
    return pou_sources_of(units, files)


def pou_sources_of(
    units: Iterable[ast.SourceUnit], files: list[SourceFile]
) -> dict[str, PouSource]:
    """`pou_sources` of files already parsed into `units`."""
    texts = {source.name: source.text.splitlines() for source in files}
    found: dict[str, PouSource] = {}
    for unit in units:
        for pou in unit.pous:
            if pou.name.upper() in found and unit.file.startswith("stdlib/"):
                continue
            found[pou.name.upper()] = _pou_source(pou, texts.get(unit.file, []))
    return found


def instances(sources: ConfigurationSources, paths: Iterable[str]) -> list[str]:
    """The programs and FB instances of the running resource, from the paths of its
    variables (`TankControl.refillDelay.Q` -> `TankControl`, `TankControl.refillDelay`),
    in tree order: each program, then the instances inside it."""
    prefixes: set[str] = set()
    for path in paths:
        parts = path.split(".")
        prefixes.update(".".join(parts[:n]) for n in range(1, len(parts)))
    found = [p for p in prefixes if sources.pou_of(p) is not None]
    order = {p.name.upper(): i for i, p in enumerate(sources.artifact.programs)}
    return sorted(found, key=lambda p: (order.get(p.split(".")[0].upper(), 0), p.split(".")))


@dataclass(frozen=True)
class Shown:
    """A variable a line names, as written (`counts[2]`), the path of the variable that
    holds its value (`Line.counts`) and, for an element of an array of elementary values
    (one variable), its index as the runtime's array shapes spell it (`2`, `0,1`)."""

    label: str
    path: str
    element: str | None = None


def line_variables(
    source: PouSource, instance: str, first: int, last: int, paths: Iterable[str]
) -> dict[int, list[Shown]]:
    """For each line from `first` to `last` (lines of the file): the variables it mentions
    of `instance`'s variables and the globals; only those the running resource has
    (`paths`): a temporary, or an FB or struct as a whole, has no value."""
    known = {path.upper(): path for path in paths}
    shown: dict[int, list[Shown]] = {}
    for line in range(first, last + 1):
        seen: set[tuple[str, str | None]] = set()
        for mention in source.mentions.get(line, ()):
            found = _variable(mention, instance, known)
            if found is not None and (found.path, found.element) not in seen:
                seen.add((found.path, found.element))
                shown.setdefault(line, []).append(found)
    return shown


def _variable(mention: Mention, instance: str, known: dict[str, str]) -> Shown | None:
    wanted = f"{instance}.{mention.text}" if mention.local else mention.text
    path = known.get(wanted.upper())
    if path is not None:
        return Shown(mention.text, path)
    if wanted.endswith("]"):  # an element of an array of elementary values?
        array, _, index = wanted[:-1].rpartition("[")
        path = known.get(array.upper())
        if path is not None:
            return Shown(mention.text, path, index)
    return None


# ---- the mentions of a POU, from its syntax tree


def _pou_source(pou: ast.Pou, file_lines: list[str]) -> PouSource:
    declared = {
        decl.name.upper(): block.kind not in _NOT_OF_THE_INSTANCE
        for block in pou.var_blocks
        for decl in block.decls
    }
    for step in pou.sfc.steps if pou.sfc is not None else ():
        declared[step.name.upper()] = True  # a step is a variable of the instance
    found: dict[int, list[Mention]] = {}

    def mention(text: str, pos: Pos) -> None:
        local = declared.get(text.split(".")[0].split("[")[0].upper(), False)
        found.setdefault(pos.line, []).append(Mention(text, local, pos.col))

    for block in pou.var_blocks:
        for decl in block.decls:
            mention(decl.name, decl.pos)
    lines_seen = [pou.pos.line]
    for node in (pou.body, pou.sfc):
        for text, pos in _references(node, declared):
            mention(text, pos)
            lines_seen.append(pos.line)
    # methods and property accessors name the instance's variables too; their own
    # (parameters, locals, the result) live only during a call: no value to show
    for own, body in _member_bodies(pou):
        for text, pos in _references(body, declared):
            if text.split(".")[0].split("[")[0].upper() not in own:
                mention(text, pos)
            lines_seen.append(pos.line)
    if pou.sfc is not None:
        for step in pou.sfc.steps:
            mention(f"{step.name}.X", step.pos)
            mention(f"{step.name}.T", step.pos)
            lines_seen.append(step.pos.line)
        for action in bool_actions(pou.sfc):  # what the step sets: its action's Q
            mention(action.name, action.pos)
            lines_seen.append(action.pos.line)
    last = _end_line(pou, file_lines, max(lines_seen))
    return PouSource(
        name=pou.name,
        kind=pou.kind,
        file=pou.pos.file,
        first_line=pou.pos.line,
        lines=tuple(file_lines[pou.pos.line - 1 : last]),
        mentions={line: tuple(sorted(items, key=lambda m: m.col)) for line, items in found.items()},
    )


def _member_bodies(pou: ast.Pou) -> Iterator[tuple[set[str], tuple[ast.Statement, ...]]]:
    """(upper names of its own, body) of each method and property accessor of a block:
    its parameters and locals, and its name, which is its result."""
    for method in pou.methods:
        own = {decl.name.upper() for block in method.var_blocks for decl in block.decls}
        yield own | {method.name.upper()}, method.body
    for prop in pou.properties:
        for accessor in prop.accessors:
            own = {decl.name.upper() for block in accessor.var_blocks for decl in block.decls}
            yield own | {prop.name.upper()}, accessor.body


def _end_line(pou: ast.Pou, file_lines: list[str], after: int) -> int:
    """The line of the POU's END_PROGRAM / END_FUNCTION_BLOCK / END_FUNCTION: the first at
    or after the last line its syntax tree has a position on; the file's end when none."""
    end = re.compile(rf"\bEND_{pou.kind}\b", re.IGNORECASE)
    for number in range(after, len(file_lines) + 1):
        if end.search(file_lines[number - 1]):
            return number
    return len(file_lines)


def _references(node: object, declared: dict[str, bool]) -> Iterator[tuple[str, Pos]]:
    """The variables an ST fragment names, as (text relative to the POU, position): whole
    references (`fb.Q`, not `fb` and `fb.Q`), the named inputs and outputs of a call of an
    FB instance (`fb(IN := x)` names `fb.IN`), FOR's counter."""
    if isinstance(node, (ast.NameRef, ast.MemberRef, ast.IndexRef, ast.BitRef)):
        text = _chain(node)
        if text is not None:
            yield text, node.pos
        yield from _inside_chain(node, declared)
        return
    if isinstance(node, ast.Call):
        called = _called_instance(node, declared)
        if called is not None:  # an FB instance
            for argument in node.args:
                if argument.name is not None:
                    yield f"{called}.{argument.name}", argument.pos
        for argument in node.args:
            yield from _references(argument.value, declared)
        yield from _references(node.receiver, declared)
        yield from _references(node.instance, declared)
        return
    if isinstance(node, ast.For):
        yield node.variable, node.pos
    if isinstance(node, tuple):
        for item in node:
            yield from _references(item, declared)
    elif dataclasses.is_dataclass(node) and not isinstance(node, (type, Pos)):
        for item in dataclasses.fields(node):
            yield from _references(getattr(node, item.name), declared)


def _called_instance(call: ast.Call, declared: dict[str, bool]) -> str | None:
    """The text of the one FB instance a call runs: `fb`, `fbs[2]`, `axis.timer`; None for
    `fbs[i]` (any of them) and for a call of no instance."""
    instance: ast.Expr
    if call.instance is not None:
        instance = call.instance
    elif call.receiver is not None:
        instance = ast.MemberRef(call.receiver, call.name, call.pos)
    else:
        return call.name if call.name.upper() in declared else None
    text = _chain(instance)
    match instance:
        case ast.IndexRef() if text is not None and text.endswith("]"):
            return text
        case ast.MemberRef(member=member) if text is not None and text.endswith(f".{member}"):
            return text
    return None


def _chain(node: ast.Expr) -> str | None:
    """`fb.Q`, `points[2].x`; an index that is not a constant ends the reference at the
    array (`values[i]` -> `values`: an array of elementary values is one variable)."""
    if isinstance(node, ast.NameRef):
        return node.name
    if isinstance(node, ast.MemberRef):
        base = _chain(node.base)
        if base is None or not isinstance(node.base, (ast.NameRef, ast.MemberRef, ast.IndexRef)):
            return base
        if isinstance(node.base, ast.IndexRef) and not _constant_index(node.base):
            return base
        return f"{base}.{node.member}"
    if isinstance(node, ast.IndexRef):
        base = _chain(node.base)
        if base is None or not _constant_index(node):
            return base
        return f"{base}[{','.join(str(_int(i)) for i in node.indices)}]"
    if isinstance(node, ast.BitRef):
        return _chain(node.base)
    return None


def _inside_chain(node: ast.Expr, declared: dict[str, bool]) -> Iterator[tuple[str, Pos]]:
    """The variables in the indices of a reference (`values[i]` names `i` too)."""
    if isinstance(node, ast.IndexRef):
        for index in node.indices:
            yield from _references(index, declared)
        yield from _inside_chain(node.base, declared)
    elif isinstance(node, (ast.MemberRef, ast.BitRef)):
        yield from _inside_chain(node.base, declared)
    elif isinstance(node, ast.Deref):
        yield from _references(node.base, declared)


def _constant_index(node: ast.IndexRef) -> bool:
    return all(_int(index) is not None for index in node.indices)


def _int(node: ast.Expr) -> int | None:
    if isinstance(node, ast.IntLiteral):
        return node.value
    if isinstance(node, ast.Unary) and node.op == "-" and isinstance(node.operand, ast.IntLiteral):
        return -node.operand.value
    return None


def _unit(artifact: Artifact, name: str) -> PouCode | None:
    """A POU or structure of the artifact by its name (any case)."""
    for unit in (*artifact.pous, *artifact.types):
        if unit.name.upper() == name.upper():
            return unit
    return None


def _strip_index(member: str) -> tuple[str, bool]:
    """`valves[2]` -> (`valves`, True)."""
    name, bracket, _ = member.partition("[")
    return name, bool(bracket)
