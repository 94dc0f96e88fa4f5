"""Live values over a WebSocket: `/api/resources/{resource}/live`.

The client's first message is `{"token", "variables", "period_ms"}` (a browser cannot set
headers on a WebSocket, so the API token comes in the message). The reply is
`{"variables": [...]}` with the canonical paths, then one message per period as the
resource sends it: `{"cycle", "values": {path: {"value", "literal", "quality"}}}`. A client that
reads slowly gets the newest message, not a backlog. The watch set ends with the
WebSocket; when the resource goes away the server sends an `unreachable` error and
closes."""

from __future__ import annotations

import asyncio
from typing import Any

from fastapi import APIRouter, WebSocket, WebSocketDisconnect
from starlette.concurrency import run_in_threadpool

from backend.api.errors import error_body
from backend.api.service import PadtService
from backend.engineering.literals import watch_values_shown
from backend.engineering.resource_client import ResourceUnreachable, WatchHandle
from runtime.contract.outside_json import JsonRefused, read_json
from runtime.contract.protocol import GetVariables
from runtime.contract.refusal import Refusal
from runtime.contract.wire import MAX_DEPTH

router = APIRouter()
ONLINE_CHECK_S = 1.0
POLICY_VIOLATION = 1008  # WebSocket close code: authentication failed or request refused
MAX_FIRST_MESSAGE = 1 << 20  # a token and the names of the variables to watch


def _subscription(message: Any) -> tuple[str, list[str], int]:
    if not isinstance(message, dict):
        raise Refusal("bad_request", "the first message is an object")
    token, variables = message.get("token"), message.get("variables")
    period = message.get("period_ms", 100)
    if not isinstance(token, str):
        raise Refusal("unauthenticated", '"token" (from POST /api/login) is missing')
    if not isinstance(variables, list) or not all(isinstance(v, str) for v in variables):
        raise Refusal("bad_request", '"variables" is a list of variable names')
    if not isinstance(period, int) or isinstance(period, bool):
        raise Refusal("bad_request", '"period_ms" is an integer')
    return token, variables, period


def _first_message(received: Any) -> Any:
    """The first message's JSON, read within the limits of outside JSON."""
    if received.get("type") == "websocket.disconnect":
        raise WebSocketDisconnect(received.get("code", 1000))
    text = received.get("text")
    if not isinstance(text, str):
        raise Refusal("bad_request", "the first message is JSON text, not binary")
    try:
        return read_json(text, "the first message", MAX_FIRST_MESSAGE, MAX_DEPTH)
    except JsonRefused as exc:
        raise Refusal("bad_request", str(exc)) from None


def _start_watch(service: PadtService, resource: str, message: Any, deliver: Any) -> WatchHandle:
    token, variables, period = _subscription(message)
    caller = service.caller(token, "read-only")
    client = service.client(caller, resource)
    try:
        # the types: each value goes out with the literal of its type beside it
        types = {v.path: v.type for v in client.ask(GetVariables()).variables}
        return client.watch(
            variables, lambda message: deliver(watch_values_shown(message, types)), period
        )
    except Refusal as refused:
        why = service.resource_refusal(caller, resource, refused)
        if why.code == "resource_login_required":
            raise why from None
        raise Refusal("watch_refused", f"{why.code}: {why.message}") from None
    except ResourceUnreachable as exc:
        raise Refusal("unreachable", str(exc)) from None


@router.websocket("/api/resources/{resource}/live")
async def live(websocket: WebSocket, resource: str) -> None:
    service: PadtService = websocket.app.state.service
    await websocket.accept()
    loop = asyncio.get_running_loop()
    newest: asyncio.Queue[dict[str, Any]] = asyncio.Queue(maxsize=1)

    def put_newest(message: dict[str, Any]) -> None:
        if newest.full():
            newest.get_nowait()  # the reader is behind: it gets this one instead
        newest.put_nowait(message)

    def deliver(message: dict[str, Any]) -> None:  # on a Zenoh thread
        loop.call_soon_threadsafe(put_newest, message)

    try:
        first = _first_message(await websocket.receive())
        watch = await run_in_threadpool(_start_watch, service, resource, first, deliver)
    except Refusal as error:
        await websocket.send_json(error_body(error))
        await websocket.close(POLICY_VIOLATION)
        return
    except WebSocketDisconnect:
        return
    try:
        await websocket.send_json({"variables": watch.variables})
        await _forward(websocket, newest, service, resource)
    except WebSocketDisconnect:
        pass
    finally:
        await run_in_threadpool(watch.close)


async def _forward(
    websocket: WebSocket,
    newest: asyncio.Queue[dict[str, Any]],
    service: PadtService,
    resource: str,
) -> None:
    closed = asyncio.ensure_future(websocket.receive())  # tells when the client goes
    try:
        while True:
            getting = asyncio.ensure_future(newest.get())
            done, _ = await asyncio.wait(
                {getting, closed}, timeout=ONLINE_CHECK_S, return_when=asyncio.FIRST_COMPLETED
            )
            if closed in done:
                getting.cancel()
                said = closed.result()
                if said["type"] == "websocket.disconnect":
                    raise WebSocketDisconnect(said.get("code", 1000))
                closed = asyncio.ensure_future(websocket.receive())  # chatter, text or not
                continue
            if getting in done:
                await websocket.send_json(getting.result())
                continue
            getting.cancel()
            if not service.directory.is_online(resource):
                gone = Refusal("unreachable", f"resource '{resource}' went away")
                await websocket.send_json(error_body(gone))
                await websocket.close(1011)
                return
    finally:
        closed.cancel()
