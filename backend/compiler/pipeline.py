"""The whole compiler: parse -> resolve -> check -> generate -> CRC -> artifact.

`compile_sources` never raises for bad input: it returns every diagnostic it found, and an
artifact only when there is no error.
"""

from __future__ import annotations

import functools
import sys
from dataclasses import dataclass, replace
from typing import Any

from backend.compiler import ast
from backend.compiler.ast import key
from backend.compiler.check import check
from backend.compiler.checks.exchange import check_exchange
from backend.compiler.checks.generated_names import check_generated_names
from backend.compiler.checks.modbus import check_modbus
from backend.compiler.checks.opcua import check_opcua
from backend.compiler.checks.programs import check_programs, globals_read, globals_written
from backend.compiler.checks.var_config import check_configuration
from backend.compiler.codes import Code
from backend.compiler.diagnostics import CompileError, Diagnostic
from backend.compiler.generate import (
    GeneratedUnit,
    GenerationError,
    action_control,
    class_name,
    declared_at,
    function_name,
    generate_globals,
    generate_pou,
    generate_struct,
    struct_class,
)
from backend.compiler.infer import instance_fields, is_external
from backend.compiler.limits import MAX_PROJECT_FORM, MiB
from backend.compiler.parse import TokenBudget, parse_source
from backend.compiler.resolve import PouSymbols, Resolved, Variable, resolve
from backend.compiler.source import Pos, ProjectSize, SourceFile, stdlib_sources
from backend.compiler.toml_lines import line_of
from backend.compiler.types import (
    ArrayType,
    FbType,
    OpenArrayType,
    StructType,
    Type,
    artifact_type_text,
)
from runtime.contract.accounts import account_problems
from runtime.contract.artifact import (
    Artifact,
    Association,
    ChartInfo,
    PouCode,
    ProgramConfig,
    ResourceConfig,
    UserAccount,
    VarInfo,
    canonical_json,
    crc32_hex,
)
from runtime.contract.code.form_json import FormRefused, encode_unit
from runtime.contract.keyspace import resource_name_problem
from runtime.contract.values import ValueRejected, representation


@dataclass(frozen=True)
class CompileResult:
    diagnostics: tuple[Diagnostic, ...]
    artifact: Artifact | None

    @property
    def ok(self) -> bool:
        return self.artifact is not None

    def as_json(self) -> dict[str, Any]:
        """The report of `padt compile --json` and of the REST API's compile."""
        crc: dict[str, Any] = {}
        if self.artifact is not None:
            crc = {
                "configuration": self.artifact.crc,
                "pous": {p.name: p.crc for p in self.artifact.pous},
                "programs": {p.name: p.crc for p in self.artifact.programs},
            }
        return {"ok": self.ok, "diagnostics": [d.as_json() for d in self.diagnostics], "crc": crc}


# Python frames of the parser and the tree walkers; deep ST is refused by the nesting
# limits of the parse stage long before this (see limits.py). Set once, when the
# compiler is imported.
RECURSION_LIMIT = 20_000
sys.setrecursionlimit(max(sys.getrecursionlimit(), RECURSION_LIMIT))


def parse_all(sources: list[SourceFile]) -> tuple[list[ast.SourceUnit], list[Diagnostic]]:
    """Every file of a project parsed, within the limits of size: a file too large is left
    out, and once the project is too large nothing more is parsed."""
    units: list[ast.SourceUnit] = []
    diagnostics: list[Diagnostic] = []
    budget = TokenBudget()
    size = ProjectSize()
    for source in sources:
        problem = size.add(source.text)
        if problem is not None:
            diagnostics.append(Diagnostic.at(Pos(source.name, 1, 1), *problem))
            if size.exceeded:
                break
            continue
        try:
            unit = parse_source(source.name, source.text, budget)
            units.append(unit)
            diagnostics.extend(unit.warnings)
        except CompileError as exc:
            diagnostics.extend(exc.diagnostics)
        if budget.spent:
            break
    return units, diagnostics


# a project parsed: its units (the user's, then the standard library's it does not
# replace), the diagnostics of the user's files, the keys of the user's POUs
Parsed = tuple[list[ast.SourceUnit], list[Diagnostic], set[str]]


def parse_project(sources: list[SourceFile]) -> Parsed:
    """The user's files parsed, then the standard library's POUs the user does not replace
    (a user POU of the same name replaces the standard one); with the diagnostics of the
    user's files and the keys of the user's POUs."""
    units, diagnostics = parse_all(sources)
    return with_standard_library(units), diagnostics, {key(p.name) for u in units for p in u.pous}


def with_standard_library(units: list[ast.SourceUnit]) -> list[ast.SourceUnit]:
    """The user's units, then the standard library's without the POUs the user replaces."""
    user_pous = {key(p.name) for unit in units for p in unit.pous}
    result = list(units)
    for unit in _standard_library():
        kept = tuple(p for p in unit.pous if key(p.name) not in user_pous)
        result.append(replace(unit, pous=kept))
    return result


@functools.cache
def _standard_library() -> tuple[ast.SourceUnit, ...]:
    """The standard library parsed, once per process (its AST is immutable)."""
    units, diagnostics = parse_all(stdlib_sources())
    assert not diagnostics, diagnostics
    return tuple(units)


def compile_sources(
    sources: list[SourceFile],
    *,
    project: str = "project",
    resource: ResourceConfig | None = None,
    programs: list[ProgramConfig] | None = None,
    config_file: str = "padt.toml",
    safe_values: dict[str, Any] | None = None,
    users: list[UserAccount] | None = None,
    modbus: Any = None,
    config_lines: dict[str, int] | None = None,
    opcua: Any = None,
    parsed: Parsed | None = None,
    exchange: Any = None,
) -> CompileResult:
    """`modbus`, `opcua` and `exchange` are the `[modbus]`, `[opcua]` and `[exchange]`
    tables of padt.toml as read (None: there is none);
    `config_lines` where each setting of padt.toml is written (`toml_lines.key_lines`);
    `parsed`: `parse_project(sources)` when the caller has it already (the documentation
    needs the parse too; the AST is immutable, so sharing it is safe)."""
    settings = _Settings(
        safe_values or {}, users or [], modbus, config_lines or {}, opcua, exchange
    )
    try:
        return _compile(sources, project, resource, programs, config_file, settings, parsed)
    except (RecursionError, MemoryError) as exc:
        # the limits are meant to make this impossible; should one be missing, the caller
        # still gets a diagnostic (the project is too large for the compiler), never a
        # traceback
        where = Pos(sources[0].name if sources else config_file, 1, 1)
        cause = "stack" if isinstance(exc, RecursionError) else "memory"
        message = f"the compiler ran out of {cause} on this project"
        return CompileResult((Diagnostic.at(where, Code.PROJECT_SIZE, message),), None)


def in_reading_order(diagnostics: list[Diagnostic], unparsed: set[str]) -> list[Diagnostic]:
    """The cause before its consequences: first what is wrong in the files that did not
    parse (all they declare is missing, which may make errors elsewhere: a program whose
    POU is not found, a Modbus point without its global), each with a note that says so
    when errors follow in other files; then the rest, each file's by place."""
    causes = [d for d in diagnostics if d.file in unparsed]
    rest = [d for d in diagnostics if d.file not in unparsed]
    if any(d.severity == "error" for d in rest):
        for file in sorted(unparsed):
            first = min(
                (d for d in causes if d.file == file and d.severity == "error"), default=None
            )
            if first is not None:
                message = (
                    f"{file} did not parse, so nothing it declares is known: "
                    "errors in other files may follow from that"
                )
                causes.append(
                    Diagnostic.at(Pos(file, first.line, first.col), Code.UNPARSED_FILE, message)
                )
    return sorted(causes) + sorted(rest)


@dataclass(frozen=True)
class _Settings:
    """What padt.toml says besides the resource and its programs."""

    safe_values: dict[str, Any]
    users: list[UserAccount]
    modbus: Any
    lines: dict[str, int]
    opcua: Any = None
    exchange: Any = None


def _compile(
    sources: list[SourceFile],
    project: str,
    resource: ResourceConfig | None,
    programs: list[ProgramConfig] | None,
    config_file: str,
    settings: _Settings,
    parsed: Parsed | None,
) -> CompileResult:
    users = settings.users
    units, parse_diagnostics, user_pous = parsed if parsed is not None else parse_project(sources)
    diagnostics = list(parse_diagnostics)  # the caller's parse stays as it was
    if any(d.code == Code.PROJECT_SIZE.id for d in diagnostics):
        # refused as a whole: checking the files parsed before the limit would only add
        # to what the refusal costs (seconds, on a project of that size)
        return CompileResult(tuple(sorted(diagnostics)), None)
    resolved = resolve(units)
    diagnostics.extend(resolved.diagnostics)
    diagnostics.extend(check(resolved))
    configured = _from_configuration(units, diagnostics)
    positions: dict[str, Pos] = {}
    named_at = Pos(config_file, line_of(settings.lines, "resource.name"), 1)
    if resource is None:
        named_at = _configured_resource_at(units) or named_at
        resource = configured[0] if configured else ResourceConfig(name="Resource1")
    diagnostics.extend(_check_resource_name(resource.name, named_at))
    if programs is None:
        programs = configured[1] if configured else _default_programs(units)
        positions = configured[2] if configured else {}
    else:  # padt.toml's [[resource.program]] tables, each at its line
        positions = {
            p.name: Pos(config_file, line_of(settings.lines, f"resource.program.{i}"), 1)
            for i, p in reversed(list(enumerate(programs)))  # a name given twice: the first
        }
    diagnostics.extend(check_programs(resolved, resource, programs, config_file, positions))
    configurations = [c for unit in units for c in unit.configurations]
    instance_io = check_configuration(resolved, configurations, resource.name, programs)
    diagnostics.extend(instance_io.diagnostics)
    safe, safe_diagnostics = _safe_values(resolved, settings.safe_values, config_file)
    diagnostics.extend(safe_diagnostics)
    modbus, modbus_diagnostics = check_modbus(
        resolved, settings.modbus, config_file, settings.lines
    )
    diagnostics.extend(modbus_diagnostics)
    opcua, opcua_diagnostics = check_opcua(
        resolved, programs, sources, settings.opcua, config_file, settings.lines, modbus
    )
    diagnostics.extend(opcua_diagnostics)
    exchange, exchange_diagnostics = check_exchange(
        resolved, programs, settings.exchange, resource.name, config_file, settings.lines
    )
    diagnostics.extend(exchange_diagnostics)
    diagnostics.extend(_check_users(users, config_file))
    unparsed = {source.name for source in sources} - {unit.file for unit in units}
    diagnostics = in_reading_order(diagnostics, unparsed)
    if any(d.severity == "error" for d in diagnostics):
        return CompileResult(tuple(diagnostics), None)

    included = _included_pous(resolved, user_pous, programs)
    try:
        codes, types, globals_code = _generate(resolved, included)
    except GenerationError as exc:
        return CompileResult(tuple(sorted([*diagnostics, *exc.diagnostics])), None)
    program_configs = tuple(_program_config(resolved, codes, p) for p in programs)
    artifact = Artifact(
        project=project,
        resource=resource,
        pous=tuple(codes[name] for name in sorted(codes, key=lambda n: _run_order(resolved, n))),
        programs=program_configs,
        types=types,
        globals=globals_code,
        safe_values=safe,
        users=tuple(sorted(users, key=lambda u: u.name)),
        modbus=modbus,
        located=instance_io.located,
        access_paths=instance_io.access_paths,
        opcua=opcua,
        exchange=exchange,
    ).with_crc()
    return CompileResult(tuple(diagnostics), artifact)


def _generate(
    resolved: Resolved, included: list[str]
) -> tuple[dict[str, PouCode], tuple[PouCode, ...], PouCode]:
    """The code of the POUs (by key), the structures and the globals: each unit within
    MAX_UNIT_CODE (the generator keeps to that), their forms within MAX_PROJECT_FORM, and no
    name of the user among the names of a POU's own code."""
    total = 0

    def counted(code: PouCode, where: Pos) -> PouCode:
        nonlocal total
        total += len(code.form)
        if total > MAX_PROJECT_FORM:
            message = f"the project's typed form exceeds {MAX_PROJECT_FORM // MiB} MiB"
            raise GenerationError([Diagnostic.at(where, Code.CODE_SIZE, message)])
        return code

    codes: dict[str, PouCode] = {}
    clashes: list[Diagnostic] = []
    for name in included:
        pou = resolved.pous[name]
        codes[name] = counted(_pou_code(resolved, pou), pou.pou.pos)
        clashes += check_generated_names(resolved, pou)
    if clashes:
        raise GenerationError(clashes)
    any_pou = resolved.sorted_pous()[0]
    types = tuple(
        counted(
            _unit_code(
                info.name, "STRUCT", struct_class(info.name),
                generate_struct(resolved, info, any_pou), info.members,
                declared_at(info.members, any_pou),
            ),
            declared_at(info.members, any_pou),
        )
        for _, info in sorted(resolved.structs.items())
    )  # fmt: skip
    globals_code = _unit_code(
        "GLOBALS",
        "GLOBALS",
        "GLOBALS",
        generate_globals(resolved, any_pou),
        resolved.globals,
        declared_at(resolved.globals, any_pou),
    )
    return codes, types, counted(globals_code, declared_at(resolved.globals, any_pou))


def _configured_resource_at(units: list[ast.SourceUnit]) -> Pos | None:
    """Where the RESOURCE that names the resource is declared, if a CONFIGURATION does."""
    resources = [r for unit in units for c in unit.configurations for r in c.resources]
    return resources[0].pos if resources else None


def _check_resource_name(name: str, where: Pos) -> list[Diagnostic]:
    """The resource's name is part of its Zenoh keys: a wildcard (`*`, `**`, `$*`) or a
    `/` there would make keys that reach other resources."""
    problem = resource_name_problem(name)
    return [] if problem is None else [Diagnostic.at(where, Code.RESOURCE_NAME, problem)]


def _from_configuration(
    units: list[ast.SourceUnit], diagnostics: list[Diagnostic]
) -> tuple[ResourceConfig, list[ProgramConfig], dict[str, Pos]] | None:
    """Resource and user programs from the first RESOURCE of an IEC CONFIGURATION: each
    PROGRAM ... WITH task is a user program with the task's priority; the CPU cycle is the
    shortest task interval (one cycle for all programs, as on HIMA and M580 controllers)."""
    resources = [r for unit in units for c in unit.configurations for r in c.resources]
    if not resources:
        return None
    chosen = resources[0]
    for extra in resources[1:]:
        diagnostics.append(
            Diagnostic.at(
                extra.pos,
                Code.EXTRA_RESOURCE,
                f"resource '{extra.name}' ignored: one resource per project",
            )
        )
    tasks = {key(t.name): dict(t.params) for t in chosen.tasks}
    intervals = [
        interval.nanoseconds // 1_000_000
        for params in tasks.values()
        if isinstance(interval := params.get("INTERVAL"), ast.TimeLiteral)
    ]
    cycle_ms = max(1, min(intervals)) if intervals else 100
    programs = []
    for number, instance in enumerate(chosen.programs, 1):
        params = tasks.get(key(instance.task or ""), {})
        priority = params.get("PRIORITY")
        if instance.args:
            diagnostics.append(
                Diagnostic.at(
                    instance.pos,
                    Code.PROGRAM_ARGUMENTS,
                    "program arguments in a configuration are ignored",
                )
            )
        programs.append(
            ProgramConfig(
                name=instance.name,
                pou=instance.pou,
                program_id=number,
                priority=priority.value if isinstance(priority, ast.IntLiteral) else 0,
            )
        )
    positions = {p.name: p.pos for p in chosen.programs}  # where each program was declared
    resource = ResourceConfig(name=chosen.name, target_cycle_ms=cycle_ms, target_cycle_mode="fixed")
    return resource, programs, positions


def _run_order(resolved: Resolved, pou_key: str) -> tuple[int, str]:
    """Where a POU comes in the artifact, which runs its code in that order: a block after
    the blocks it extends (its class takes their methods as they are), by name otherwise."""
    depth, base = 0, resolved.pous[pou_key].base
    while base is not None:
        depth, base = depth + 1, resolved.pous[base].base
    return depth, pou_key


def _safe_values(
    resolved: Resolved, configured: dict[str, Any], config_file: str
) -> tuple[tuple[tuple[str, Any], ...], list[Diagnostic]]:
    """Safe values of outputs from the project: each must name a located output (%Q) and
    be a value of its type."""
    where = Pos(config_file, 1, 1)
    checked, diagnostics = [], []
    for name, value in sorted(configured.items()):
        variable = resolved.globals_by_key.get(key(name))
        location = variable.location if variable is not None else None
        if variable is None or location is None or not location.upper().startswith("%Q"):
            diagnostics.append(
                Diagnostic.at(
                    where, Code.SAFE_VALUE_TARGET, f"safe value for '{name}': no global output (%Q)"
                )
            )
            continue
        try:
            stored = representation(artifact_type_text(variable.type), value)
        except ValueRejected as exc:
            diagnostics.append(
                Diagnostic.at(where, Code.SAFE_VALUE, f"safe value for '{name}': {exc}")
            )
            continue
        checked.append((variable.name, stored))
    return tuple(checked), diagnostics


def _check_users(users: list[UserAccount], config_file: str) -> list[Diagnostic]:
    """PES accounts: valid names, levels and hashes, unique names, and (when there are
    any) at least one Administrator, or nobody could manage them."""
    where = Pos(config_file, 1, 1)
    diagnostics = [
        Diagnostic.at(where, Code.USER_ACCOUNT, problem)
        for user in users
        for problem in account_problems(user.name, user.level, user.password_hash)
    ]
    names = [user.name for user in users]
    for name in sorted({n for n in names if names.count(n) > 1}):
        diagnostics.append(
            Diagnostic.at(where, Code.DUPLICATE_USER, f"user '{name}' is defined twice")
        )
    if users and not any(user.level == "administrator" for user in users):
        diagnostics.append(
            Diagnostic.at(where, Code.NO_ADMINISTRATOR, "the users include no administrator")
        )
    return diagnostics


def _default_programs(units: list[ast.SourceUnit]) -> list[ProgramConfig]:
    """Without a configuration every PROGRAM runs as a user program named after its POU."""
    pous = [p for unit in units for p in unit.pous if p.kind == "PROGRAM"]
    return [ProgramConfig(name=p.name, pou=p.name, program_id=i) for i, p in enumerate(pous, 1)]


def _fb_dependencies(resolved: Resolved, *names: str) -> list[str]:
    """The POU keys `names` need, themselves included, sorted: the blocks of their
    instances, the bases they extend (whose methods and body their code calls), and the
    blocks of their methods' temporary instances."""
    seen: set[str] = set()
    stack = list(names)
    while stack:
        current = stack.pop()
        if current in seen:
            continue
        seen.add(current)
        pou = resolved.pous[current]
        if pou.base is not None:
            stack.append(pou.base)
        routines = pou.own_routines()
        for variable in (*pou.variables, *(v for r in routines for v in r.variables)):
            stack.extend(_fb_types_in(resolved, variable.type))
    return sorted(seen)


def _fb_types_in(resolved: Resolved, t: Type) -> list[str]:
    """Function block types a variable of type `t` contains (in arrays and structs too)."""
    if isinstance(t, FbType):
        return [key(t.name)]
    if isinstance(t, ArrayType):
        return _fb_types_in(resolved, t.element)
    if isinstance(t, StructType):
        found: list[str] = []
        for member in resolved.structs[key(t.name)].members:
            found.extend(_fb_types_in(resolved, member.type))
        return found
    return []


def _included_pous(
    resolved: Resolved, user_pous: set[str], programs: list[ProgramConfig]
) -> list[str]:
    included = _fb_dependencies(resolved, *sorted(user_pous), *(key(p.pou) for p in programs))
    return [name for name in included if not is_external(resolved.pous[name])]


def _unit_code(
    name: str, kind: str, class_: str, generated: GeneratedUnit, variables: list[Variable],
    where: Pos,
) -> PouCode:  # fmt: skip
    infos = tuple(
        VarInfo(
            name=v.name,
            attr=v.attr,
            type=artifact_type_text(v.type),
            kind=v.kind,
            retain=v.retain,
            constant=v.constant,
            location=v.location,
        )
        for v in variables
    )
    try:
        form = encode_unit(generated.unit)
    except FormRefused:
        message = f"statements and expressions nested deeper than a resource reads ({name})"
        raise GenerationError([Diagnostic.at(where, Code.STATEMENT_DEPTH, message)]) from None
    # the CRC of the code itself: its Python, in which the ST lines the form also carries
    # do not stand (a comment added above a POU does not change it)
    crc = crc32_hex(generated.source)
    return _knowing(PouCode(name, kind, class_, form, crc, infos), generated)


def _pou_code(resolved: Resolved, pou: PouSymbols) -> PouCode:
    generated = generate_pou(resolved, pou)
    if pou.kind == "FUNCTION":
        code = _unit_code(pou.name, pou.kind, function_name(pou.name), generated, [], pou.pou.pos)
        if pou.return_type is not None:
            returns = artifact_type_text(pou.return_type)
            code = _knowing(replace(code, returns=returns), generated)
    else:
        # a variable-length in-out is the caller's array, shown where the caller has it
        stored = [v for v in instance_fields(pou) if not isinstance(v.type, OpenArrayType)]
        code = _unit_code(pou.name, pou.kind, class_name(pou.name), generated, stored, pou.pou.pos)
    chart = _chart(pou.pou.sfc)
    return _knowing(replace(code, file=pou.pou.pos.file, chart=chart), generated)


def _knowing(code: PouCode, generated: GeneratedUnit) -> PouCode:
    return code.knowing(generated.unit, generated.source, generated.st_lines)


def _chart(sfc: ast.Sfc | None) -> ChartInfo | None:
    if sfc is None:
        return None
    associations = tuple(
        Association(step.name, a.action, a.qualifier)
        for step in sfc.steps
        for a in step.associations
    )
    actions = list(dict.fromkeys(association.action for association in associations))
    return ChartInfo(
        steps=tuple(step.name for step in sfc.steps),
        initial=tuple(step.name for step in sfc.steps if step.initial),
        associations=associations,
        controls=tuple((action, action_control(action)) for action in actions),
    )


def _program_config(
    resolved: Resolved, codes: dict[str, PouCode], program: ProgramConfig
) -> ProgramConfig:
    """A user program as the artifact carries it: with the globals it writes and reads (by
    attribute, sorted), and its CRC."""
    attr = {k: v.attr for k, v in resolved.globals_by_key.items()}
    written = sorted(attr[k] for k in globals_written(resolved, key(program.pou)))
    read = sorted(attr[k] for k in globals_read(resolved, key(program.pou)))
    program = replace(
        program, writes=tuple(written), reads=tuple(a for a in read if a not in written)
    )
    return replace(program, crc=_program_crc(resolved, codes, program))


def _program_crc(resolved: Resolved, codes: dict[str, PouCode], program: ProgramConfig) -> str:
    """CRC of a user program: its code, the code of every FB it uses (their CRCs), and its
    parameters."""
    parts = [codes[name].crc for name in _fb_dependencies(resolved, key(program.pou))]
    params = replace(program, crc="").__dict__
    return crc32_hex(canonical_json({"code": parts, "parameters": params}))
