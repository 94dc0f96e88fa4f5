"""The resources online, and every operation on one: status and statistics, login, load,
start and stop, programs and single step, reload preview and reload, parameters,
forcing, values, field I/O (Modbus), events and recordings.

Each request goes to the resource as a command with the caller's PES session (from `POST
.../login`); the resource checks the level itself and its refusal comes back unchanged
(code and message), with the HTTP status of docs/rest-api.md."""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Annotated, Any, Literal

from fastapi import APIRouter, Query, Response
from fastapi import Path as PathParameter
from fastapi.responses import StreamingResponse
from pydantic import BaseModel, Field, model_validator

from backend.api.auth import Credentials, ReadOnly, ReadWrite, Service
from backend.engineering import recordings
from backend.engineering.fleet import FleetReload, fleet_done, reload_fleet_done
from backend.engineering.literals import LiteralError, literals_of, parse_literal
from backend.engineering.recordings import RecordingSpec, TriggerError
from backend.engineering.reload import ReloadOptions, needs_confirmation, rename_map
from runtime.contract import protocol as p
from runtime.contract.protocol import (
    MAX_EVENTS,
    MAX_MS,
    MAX_PATH,
    MAX_PRE_CYCLES,
    MAX_RECORD_CYCLES,
    MAX_RECORDED,
)
from runtime.contract.refusal import Refusal
from runtime.contract.values import format_value
from runtime.contract.wire import encode

router = APIRouter(prefix="/api/resources", tags=["resources"])
JsonValue = bool | int | float | str | list[Any]  # a variable's value as `values` shows it
MAX_LITERAL = 1 << 16  # characters of a value's literal: no command carries more


class ProjectChoice(BaseModel):
    project: str = Field(description="a project served by this API (GET /api/projects)")


class ReloadPreviewRequest(ProjectChoice):
    renames: dict[str, str] = Field(
        default_factory=dict,
        description="OLD name -> NEW name: values of OLD go to NEW (full paths or globals)",
    )


class ReloadRequest(ReloadPreviewRequest):
    expected_crc: str = Field(
        pattern=r"^[0-9A-Fa-f]{8}$",
        description="`old_crc` of the preview confirmed: the reload is refused when the "
        "resource runs another configuration by now",
    )
    watchdog_ms: int | None = Field(default=None, gt=0, le=MAX_MS)
    target_cycle_ms: int | None = Field(default=None, gt=0, le=MAX_MS)
    keep_online: list[Annotated[str, Field(max_length=64)]] = Field(
        default_factory=list,
        max_length=32,
        description="parameters of the preview's `parameter_resets` whose online value is "
        "set again right after the reload",
    )


class ParameterValue(BaseModel):
    value: bool | int | str


class ValueRequest(BaseModel):
    value: JsonValue | None = Field(
        default=None, description="the value in the run-time representation (TIME in ns)"
    )
    literal: str | None = Field(
        default=None,
        max_length=MAX_LITERAL,
        description="or the value as an ST literal of the variable's type: T#1s500ms, "
        "D#2024-01-15, TOD#12:30:00, TRUE, 'text'",
    )

    @model_validator(mode="after")
    def _value_or_literal(self) -> ValueRequest:
        if (self.value is None) == (self.literal is None):
            raise ValueError("give the value as `value` or as `literal`, one of them")
        return self


class ForceRequest(ValueRequest):
    switch: bool = Field(default=True, description="the variable's force switch")


class ForcingLevel(BaseModel):
    program: str | None = Field(default=None, description="a program (local); none is global")


class ForcingStart(ForcingLevel):
    timeout_ms: int | None = Field(default=None, gt=0, le=MAX_MS)


class StepRequest(BaseModel):
    interval_ms: int | None = Field(default=None, gt=0, le=MAX_MS)


def _renames(renames: dict[str, str]) -> dict[str, str]:
    """OLD -> NEW as the user writes it; NEW -> OLD as the runtime takes it."""
    return rename_map((new, old) for old, new in sorted(renames.items()))


@router.get("", summary="The resources online, with their last published status")
def resources(caller: ReadOnly, service: Service) -> list[dict[str, Any]]:
    return [
        {
            "resource": name,
            "host": status.host if status is not None else None,
            "status": encode(status),
        }
        for name, status in service.directory.online()
    ]


class FleetLoadRequest(ProjectChoice):
    resources: list[Annotated[str, Field(max_length=64)]] = Field(
        min_length=1,
        max_length=256,
        description="the resources to load, in this order; each gets the project compiled "
        "for it, and the first refusal ends it",
    )


@router.post("/load", summary="Download one project into several resources in turn (a fleet load)")
def load_fleet(body: FleetLoadRequest, caller: ReadWrite, service: Service) -> Any:
    results = service.load_fleet(caller, body.resources, body.project)
    return {
        "done": fleet_done(results),
        "resources": [result.as_json() for result in results],
    }


class FleetReloadPreviewRequest(FleetLoadRequest):
    renames: dict[str, str] = Field(
        default_factory=dict,
        description="OLD name -> NEW name: values of OLD go to NEW, in each resource",
    )


class FleetReloadRequest(FleetReloadPreviewRequest):
    expected_crcs: dict[str, Annotated[str, Field(pattern=r"^[0-9A-Fa-f]{8}$")]] = Field(
        description="each resource's `old_crc` of the preview confirmed, by its name: its "
        "reload is refused when it runs another configuration by now",
    )
    keep_online: list[Annotated[str, Field(max_length=64)]] = Field(
        default_factory=list,
        max_length=32,
        description="parameters whose online value is set again right after the reload, "
        "in each resource whose reload resets them",
    )


def _fleet_reload(results: list[FleetReload]) -> dict[str, Any]:
    return {
        "done": reload_fleet_done(results),
        "possible": all(result.possible for result in results),
        "resources": [result.as_json() for result in results],
    }


@router.post(
    "/reload/preview",
    summary="The reload plan of one project in each of several resources (nothing changes)",
)
def preview_reload_fleet(
    body: FleetReloadPreviewRequest, caller: ReadWrite, service: Service
) -> Any:
    renames = _renames(body.renames)
    results = service.reload_fleet(caller, body.resources, body.project, renames, None, [])
    return _fleet_reload(results)


@router.post("/reload", summary="Reload one project into several resources in turn (online)")
def reload_fleet(body: FleetReloadRequest, caller: ReadWrite, service: Service) -> Any:
    renames = _renames(body.renames)
    expected = {name: crc.upper() for name, crc in body.expected_crcs.items()}
    results = service.reload_fleet(
        caller, body.resources, body.project, renames, expected, body.keep_online
    )
    return _fleet_reload(results)


@router.post("/{resource}/login", summary="Log in to the resource (its own accounts)")
def login(resource: str, credentials: Credentials, caller: ReadOnly, service: Service) -> Any:
    reply = service.log_in(caller, resource, credentials.user, credentials.password)
    return {"resource": resource, "user": reply.user, "level": reply.level}


@router.post("/{resource}/logout", status_code=204, summary="End the resource session")
def logout(resource: str, caller: ReadOnly, service: Service) -> Response:
    service.log_out(caller, resource)
    return Response(status_code=204)


def _status(service: Service, caller: ReadOnly, resource: str) -> p.Status:
    return service.ask(caller, resource, p.GetStatus()).status


@router.get("/{resource}/status", summary="State, configuration CRC, programs, statistics")
def status(resource: str, caller: ReadOnly, service: Service) -> Any:
    return encode(_status(service, caller, resource))


@router.get("/{resource}/statistics", summary="Cycle statistics of the resource and programs")
def statistics(resource: str, caller: ReadOnly, service: Service) -> dict[str, Any]:
    current = _status(service, caller, resource)
    programs = {
        p.name: {"cycles": p.cycles, "cpu_cycles_max": p.cpu_cycles_max} for p in current.programs
    }
    return {"cycle": current.cycle, "stats": encode(current.stats), "programs": programs}


@router.post("/{resource}/statistics/reset", summary="Reset the cycle statistics")
def reset_statistics(resource: str, caller: ReadWrite, service: Service) -> Any:
    return encode(service.ask(caller, resource, p.ResetStats()))


def _resource_action(command: type[p.Command[p.StatusReply]], summary: str) -> None:
    def action(resource: str, caller: ReadWrite, service: Service) -> Any:
        return encode(service.ask(caller, resource, command()))

    path = "/{resource}/" + command.NAME.replace("_", "-")
    router.post(path, summary=summary, name=command.NAME)(action)


_resource_action(p.Start, "Start the resource (RUN)")
_resource_action(p.Stop, "Stop the resource (STOP, safe output values)")
_resource_action(p.Init, "Leave ERROR STOP for STOP")
_resource_action(p.ColdStart, "Make the next start a cold start")
_resource_action(p.Step, "In STOP: one CPU cycle of every program")


@router.post("/{resource}/load/preview", summary="What a download would do, or why not now")
def preview_load(resource: str, body: ProjectChoice, caller: ReadWrite, service: Service) -> Any:
    plan = service.preview_load(caller, resource, body.project)
    return {**dataclasses.asdict(plan), "possible": plan.possible}


@router.post("/{resource}/load", summary="Download a project (in STOP; a cold start follows)")
def load(resource: str, body: ProjectChoice, caller: ReadWrite, service: Service) -> Any:
    done = service.load(caller, resource, body.project)
    return {
        "status": encode(done.status),
        "warnings": list(done.warnings),
        **_backup(done.backup.path, done.backup.error),
    }


def _backup(path: Path | None, error: str | None) -> dict[str, Any]:
    # the resource has the configuration already; only the record of it may be missing
    if path is None:
        return {"backup": None, "backup_error": error}
    return {"backup": path.name}


@router.post("/{resource}/reload/preview", summary="What a reload would do to every value")
def preview_reload(
    resource: str, body: ReloadPreviewRequest, caller: ReadWrite, service: Service
) -> Any:
    preview = service.preview_reload(caller, resource, body.project, _renames(body.renames))
    return {
        "plan": encode(preview.plan),
        "risks": needs_confirmation(preview.plan),
        "why_not_online": list(preview.why_not),
        "parameter_resets": [dataclasses.asdict(reset) for reset in preview.resets],
        "source_diff": [dataclasses.asdict(diff) for diff in preview.diff],
        "running_sources": preview.running_from or None,
    }


@router.post("/{resource}/reload", summary="Reload (online change) after a preview")
def reload(resource: str, body: ReloadRequest, caller: ReadWrite, service: Service) -> Any:
    options = ReloadOptions(
        _renames(body.renames), body.expected_crc.upper(), body.watchdog_ms, body.target_cycle_ms
    )
    changed = service.reload(caller, resource, body.project, options, body.keep_online)
    done = changed.reloaded
    return {
        "reload": encode(done.reply.reload),
        "status": encode(done.reply.status),
        **_backup(done.backup.path, done.backup.error),
        "kept_online": list(changed.kept),
        "not_kept_online": list(changed.not_kept),
    }


@router.get("/{resource}/programs", summary="The user programs and their states")
def programs(resource: str, caller: ReadOnly, service: Service) -> Any:
    return encode(_status(service, caller, resource).programs)


ProgramCommand = p.StartProgram | p.StopProgram | p.Freeze | p.Unfreeze


def _program_action(command: type[ProgramCommand], verb: str, summary: str) -> None:
    def action(resource: str, program: str, caller: ReadWrite, service: Service) -> Any:
        return encode(service.ask(caller, resource, command(program)))

    router.post(f"/{{resource}}/programs/{{program}}/{verb}", summary=summary, name=command.NAME)(
        action
    )


_program_action(p.StartProgram, "start", "Start a user program")
_program_action(p.StopProgram, "stop", "Stop a user program")
_program_action(p.Freeze, "freeze", "Freeze a program for single step (RUN_FREEZE)")
_program_action(p.Unfreeze, "unfreeze", "Leave single step: the program runs again")


@router.post("/{resource}/programs/{program}/step", summary="One cycle of a frozen program")
def step_program(
    resource: str,
    program: str,
    caller: ReadWrite,
    service: Service,
    body: StepRequest | None = None,
) -> Any:
    interval = body.interval_ms if body else None
    return encode(service.ask(caller, resource, p.StepProgram(program, interval)))


@router.get("/{resource}/parameters", summary="Resource and program parameters")
def parameters(resource: str, caller: ReadOnly, service: Service) -> Any:
    return encode(service.ask(caller, resource, p.GetParameters()))


@router.put("/{resource}/parameters/{name}", summary="Change an online parameter")
def set_parameter(
    resource: str, name: str, body: ParameterValue, caller: ReadWrite, service: Service
) -> Any:
    return encode(service.ask(caller, resource, p.SetParameter(name, body.value)))


@router.get("/{resource}/variables", summary="Every variable: full path and type")
def variables(resource: str, caller: ReadOnly, service: Service) -> Any:
    return encode(service.ask(caller, resource, p.GetVariables()).variables)


def _types(service: Service, caller: ReadOnly, resource: str) -> dict[str, str]:
    """Every variable's type by its path."""
    return {v.path: v.type for v in service.ask(caller, resource, p.GetVariables()).variables}


def _run_time_value(
    service: Service, caller: ReadWrite, resource: str, variable: str, body: ValueRequest
) -> Any:
    """The value of a write or a force: as given, or read from its literal with the
    variable's type (ST names are case-insensitive)."""
    if body.literal is None:
        return body.value
    types = {path.upper(): kind for path, kind in _types(service, caller, resource).items()}
    kind = types.get(variable.upper())
    if kind is None:
        message = f"resource {resource} has no variable '{variable[:MAX_PATH]}'"
        raise Refusal("unknown_variable", message)
    try:
        return parse_literal(body.literal, kind)
    except LiteralError as exc:
        raise Refusal("bad_value", f"{variable[:MAX_PATH]}: {exc}") from None


@router.get("/{resource}/values", summary="Every value now (for chosen ones, use /live)")
def values(resource: str, caller: ReadOnly, service: Service) -> Any:
    reply = service.ask(caller, resource, p.GetValues())
    literals = literals_of(reply.values, _types(service, caller, resource))
    return {**encode(reply), "literals": literals}


@router.get("/{resource}/io", summary="Modbus TCP: server, devices, every point and its value")
def io(resource: str, caller: ReadOnly, service: Service) -> Any:
    reply = service.ask(caller, resource, p.GetIo())
    shown = encode(reply)
    for point, given in zip(shown["points"], reply.points, strict=True):
        point["literal"] = format_value(given.value, given.type)
    return shown


@router.put("/{resource}/values/{variable}", summary="Write a value once (not forcing)")
def write(
    resource: str, variable: str, body: ValueRequest, caller: ReadWrite, service: Service
) -> Any:
    value = _run_time_value(service, caller, resource, variable, body)
    return encode(service.ask(caller, resource, p.Write(variable, value)))


@router.get("/{resource}/forcing", summary="Force levels, switches and forced values")
def forcing(resource: str, caller: ReadOnly, service: Service) -> Any:
    state = service.ask(caller, resource, p.GetForcing()).forcing
    shown = encode(state)
    types = _types(service, caller, resource)
    for entry, given in zip(shown["entries"], state.entries, strict=True):
        entry["literal"] = format_value(given.value, types.get(given.variable, ""))
    return shown


@router.post("/{resource}/forcing/start", summary="Start forcing (global, or one program)")
def start_forcing(resource: str, body: ForcingStart, caller: ReadWrite, service: Service) -> Any:
    command = p.StartForcing(body.program, body.timeout_ms)
    return encode(service.ask(caller, resource, command))


@router.post("/{resource}/forcing/stop", summary="Stop forcing (global, or one program)")
def stop_forcing(resource: str, body: ForcingLevel, caller: ReadWrite, service: Service) -> Any:
    return encode(service.ask(caller, resource, p.StopForcing(body.program)))


@router.put("/{resource}/forces/{variable}", summary="Set a force value and its switch")
def force(
    resource: str, variable: str, body: ForceRequest, caller: ReadWrite, service: Service
) -> Any:
    value = _run_time_value(service, caller, resource, variable, body)
    return encode(service.ask(caller, resource, p.Force(variable, value, body.switch)))


@router.delete("/{resource}/forces/{variable}", summary="Remove a force value")
def unforce(resource: str, variable: str, caller: ReadWrite, service: Service) -> Any:
    return encode(service.ask(caller, resource, p.Unforce(variable)))


@router.get("/{resource}/events", summary="The resource's event log, oldest first")
def events(
    resource: str,
    caller: ReadOnly,
    service: Service,
    after: Annotated[int, Query(ge=0, description="only events after this sequence number")] = 0,
    limit: Annotated[int, Query(ge=1, le=MAX_EVENTS)] = 200,
    log: Annotated[
        Literal["short", "long"],
        Query(description="long: user actions and configuration, kept across restarts"),
    ] = "short",
) -> Any:
    reply = service.ask(caller, resource, p.GetEvents(after, limit, log))
    events = encode(reply.events)
    # a long-term entry carries the SHA-256 of the one before it, to check the chain
    for event, prev in zip(events, reply.prev, strict=False):
        event["prev"] = prev
    return events


WEEK_S = 7 * 86_400


class RecordingRequest(BaseModel):
    variables: list[Annotated[str, Field(max_length=MAX_PATH)]] = Field(
        default_factory=list,
        max_length=MAX_RECORDED,
        description="variable paths, or `Prefix*` for every variable whose path starts so",
    )
    all_inputs: bool = Field(
        default=False, description="also every input of every cycle (for `padt replay`)"
    )
    trigger: str | None = Field(
        default=None,
        max_length=2 * MAX_PATH,
        description="start writing when it becomes true: `Main.level > 80`, `Main.alarm`, "
        "`NOT Main.alarm` (= <> < <= > >=, the value an ST literal)",
    )
    pre_cycles: int = Field(default=0, ge=0, le=MAX_PRE_CYCLES, description="before the trigger")
    cycles: int | None = Field(default=None, ge=1, le=MAX_RECORD_CYCLES)
    seconds: int | None = Field(default=None, ge=1, le=WEEK_S)
    rotate_mb: int = Field(default=256, ge=1, le=4096, description="a new file every N MB")
    rotate_s: int | None = Field(default=None, ge=1, le=WEEK_S, description="... or N seconds")
    id: str | None = Field(default=None, pattern=r"^[A-Za-z0-9_-]{1,64}$")

    def spec(self) -> RecordingSpec:
        spec = RecordingSpec(
            tuple(self.variables), self.all_inputs, self.trigger, self.pre_cycles,
            self.cycles, self.seconds, self.rotate_mb, self.rotate_s, self.id,
        )  # fmt: skip
        try:
            spec.command()
        except TriggerError as exc:
            raise Refusal("bad_request", f"trigger: {exc}") from None
        return spec


RecordingId = Annotated[str, PathParameter(pattern=r"^[A-Za-z0-9_-]{1,64}$")]


@router.post("/{resource}/recordings", summary="Start a recording (MCAP, in the resource)")
def start_recording(
    resource: str, body: RecordingRequest, caller: ReadWrite, service: Service
) -> Any:
    spec = body.spec()
    return encode(service.act(caller, resource, lambda client: recordings.start(client, spec)))


@router.get("/{resource}/recordings", summary="The recordings, the running ones first")
def list_recordings(resource: str, caller: ReadOnly, service: Service) -> Any:
    return encode(service.act(caller, resource, recordings.list_recordings))


@router.post("/{resource}/recordings/{recording}/stop", summary="Stop a recording")
def stop_recording(
    resource: str, recording: RecordingId, caller: ReadWrite, service: Service
) -> Any:
    return encode(service.act(caller, resource, lambda c: recordings.stop(c, recording)))


@router.delete("/{resource}/recordings/{recording}", summary="Delete a recording that has ended")
def delete_recording(
    resource: str, recording: RecordingId, caller: ReadWrite, service: Service
) -> Any:
    return encode(service.act(caller, resource, lambda c: recordings.delete(c, recording)))


@router.get(
    "/{resource}/recordings/files/{name}",
    summary="Download a recording file (MCAP)",
    response_class=Response,
    responses={200: {"content": {"application/octet-stream": {}}}},
)
def recording_file(
    resource: str,
    name: Annotated[str, PathParameter(pattern=r"^[A-Za-z0-9_-]{1,64}-[0-9]{1,6}\.mcap$")],
    caller: ReadOnly,
    service: Service,
) -> Response:
    # the first piece is read here, so that a file the resource refuses is an error
    # reply; the others stream as the client takes them, never the whole file in memory
    size, pieces = service.act(caller, resource, lambda c: recordings.download_chunks(c, name))
    headers = {
        "Content-Disposition": f'attachment; filename="{name}"',
        "Content-Length": str(size),
    }
    return StreamingResponse(pieces, media_type="application/octet-stream", headers=headers)
