"""Debugging in the code over HTTP (docs/debugging.md): the breakpoints and logpoints of a
resource's files, the program in BKPT, continue, step and run to, the call stack and the
variables of a frame, the silent-client timeout and a keep-alive.

Each route is one call of the debug session service with the caller's PES session, as the
other resource routes are; the resource checks the level (read for the list, the stack
and the variables; read-write for the rest) and safety operation itself."""

from __future__ import annotations

from typing import Annotated, Any, Literal

from fastapi import APIRouter, Query
from fastapi import Path as PathParameter
from pydantic import BaseModel, Field

from backend.api.auth import ReadOnly, ReadWrite, Service
from backend.engineering.debug_session import DebugSession
from runtime.contract import protocol as p
from runtime.contract.protocol import (
    MAX_BREAKPOINTS,
    MAX_DEBUG_TIMEOUT_S,
    MAX_EXPRESSION,
    MAX_LOGGED,
    MAX_NAME,
    MAX_PATH,
    MIN_DEBUG_TIMEOUT_S,
)
from runtime.contract.values import format_value
from runtime.contract.wire import encode

router = APIRouter(prefix="/api/resources", tags=["debugging"])

SourceFile = Annotated[
    str, PathParameter(max_length=MAX_PATH, description="as the project names it: lib/tank.st")
]
Program = Annotated[str, PathParameter(max_length=MAX_NAME)]
Expression = Annotated[str, Field(max_length=MAX_EXPRESSION)]


class Breakpoint(BaseModel):
    line: int = Field(ge=1, le=10_000_000, description="it stands at the first statement from here")
    program: str | None = Field(default=None, max_length=MAX_NAME, description="only this program")
    instance: str | None = Field(
        default=None, max_length=MAX_PATH, description="only this FB instance: Main.valve1"
    )
    condition: Expression | None = Field(default=None, description="an ST boolean expression")
    hit_count: int | None = Field(default=None, ge=1, le=1_000_000_000, description="from hit N")
    log: list[Expression] | None = Field(
        default=None, max_length=MAX_LOGGED, description="a logpoint: these recorded, no stop"
    )

    def spec(self) -> p.BreakpointSpec:
        return p.BreakpointSpec(
            self.line, self.program, self.instance, self.condition, self.hit_count, self.log
        )


class FileBreakpoints(BaseModel):
    breakpoints: list[Breakpoint] = Field(max_length=MAX_BREAKPOINTS)


class StepRequest(BaseModel):
    kind: Literal["over", "into", "out", "cycle"] = "over"


class RunToRequest(BaseModel):
    file: str = Field(max_length=MAX_PATH)
    line: int = Field(ge=1, le=10_000_000)


class TimeoutRequest(BaseModel):
    timeout_s: int = Field(ge=MIN_DEBUG_TIMEOUT_S, le=MAX_DEBUG_TIMEOUT_S)


@router.get("/{resource}/debug", summary="Breakpoints, the program in BKPT, the timeout")
def debug_state(resource: str, caller: ReadOnly, service: Service) -> Any:
    return encode(service.act(caller, resource, lambda c: DebugSession(c).state()))


@router.post("/{resource}/debug/keep-alive", summary="Tell the resource the client is there")
def keep_alive(resource: str, caller: ReadWrite, service: Service) -> Any:
    return encode(service.act(caller, resource, lambda c: DebugSession(c).state(keep=True)))


@router.put("/{resource}/debug/timeout", summary="A silent client: continue after this long")
def set_timeout(resource: str, body: TimeoutRequest, caller: ReadWrite, service: Service) -> Any:
    return encode(
        service.act(caller, resource, lambda c: DebugSession(c).set_timeout(body.timeout_s))
    )


@router.delete("/{resource}/debug/breakpoints", summary="Clear every breakpoint and logpoint")
def clear_all(resource: str, caller: ReadWrite, service: Service) -> Any:
    return encode(service.act(caller, resource, lambda c: DebugSession(c).clear_all()))


@router.get("/{resource}/debug/breakpoints/{file:path}", summary="A file's breakpoints")
def file_breakpoints(resource: str, file: SourceFile, caller: ReadOnly, service: Service) -> Any:
    state = service.act(caller, resource, lambda c: DebugSession(c).state())
    return encode([x for x in state.breakpoints if x.file == file])


@router.put("/{resource}/debug/breakpoints/{file:path}", summary="Set a file's breakpoints")
def set_breakpoints(
    resource: str, file: SourceFile, body: FileBreakpoints, caller: ReadWrite, service: Service
) -> Any:
    specs = [x.spec() for x in body.breakpoints]
    return encode(
        service.act(caller, resource, lambda c: DebugSession(c).set_breakpoints(file, specs))
    )


@router.delete("/{resource}/debug/breakpoints/{file:path}", summary="Clear a file's breakpoints")
def clear_file(resource: str, file: SourceFile, caller: ReadWrite, service: Service) -> Any:
    return encode(
        service.act(caller, resource, lambda c: DebugSession(c).set_breakpoints(file, []))
    )


@router.post("/{resource}/debug/programs/{program}/continue", summary="The program runs on")
def continue_(resource: str, program: Program, caller: ReadWrite, service: Service) -> Any:
    return encode(service.act(caller, resource, lambda c: DebugSession(c).continue_(program)))


@router.post("/{resource}/debug/programs/{program}/step", summary="Step over, into, out, cycle")
def step(
    resource: str,
    program: Program,
    caller: ReadWrite,
    service: Service,
    body: StepRequest | None = None,
) -> Any:
    kind = body.kind if body is not None else "over"
    return encode(service.act(caller, resource, lambda c: DebugSession(c).step(program, kind)))


@router.post("/{resource}/debug/programs/{program}/run-to", summary="Run to a file's line")
def run_to(
    resource: str, program: Program, body: RunToRequest, caller: ReadWrite, service: Service
) -> Any:
    return encode(
        service.act(
            caller, resource, lambda c: DebugSession(c).run_to(program, body.file, body.line)
        )
    )


@router.get("/{resource}/debug/programs/{program}/stack", summary="The call stack in BKPT")
def stack(resource: str, program: Program, caller: ReadOnly, service: Service) -> Any:
    frames = service.act(caller, resource, lambda c: DebugSession(c).stack(program))
    return {"frames": encode(frames)}


@router.get("/{resource}/debug/programs/{program}/variables", summary="A frame's variables")
def variables(
    resource: str,
    program: Program,
    caller: ReadOnly,
    service: Service,
    frame: Annotated[int, Query(ge=0, le=10_000, description="0: the innermost")] = 0,
    path: Annotated[
        str, Query(max_length=MAX_PATH, description="a member's children: a, a.sub, arr[2]")
    ] = "",
) -> Any:
    found = service.act(caller, resource, lambda c: DebugSession(c).variables(program, frame, path))
    shown = encode(found)
    for entry, given in zip(shown, found, strict=True):
        entry["literal"] = None if given.children else format_value(given.value, given.type)
    return {"variables": shown}
