"""Commands a client may send to a resource, and their structured replies.

Every reply is JSON: `{"ok": true, ...}` or `{"ok": false, "error": {"code", "message"}}`;
bad input gets an error reply, never an exception that escapes to the cycle.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from typing import Any

from runtime.resource import CommandRefused, Resource

MAX_REQUEST_BYTES = 64 * 1024


def error_reply(code: str, message: str) -> dict[str, Any]:
    return {"ok": False, "error": {"code": code, "message": message}}


def _status(resource: Resource) -> dict[str, Any]:
    return {"ok": True, "status": resource.status()}


def _values(resource: Resource) -> dict[str, Any]:
    return {"ok": True, "values": resource.values(), "cycle": resource.cycle_count}


def _variables(resource: Resource) -> dict[str, Any]:
    return {"ok": True, "variables": resource.variables()}


def _state_change(action: Callable[[Resource], None]) -> Callable[[Resource], dict[str, Any]]:
    def run(resource: Resource) -> dict[str, Any]:
        action(resource)
        return _status(resource)

    return run


COMMANDS: dict[str, Callable[[Resource], dict[str, Any]]] = {
    "status": _status,
    "values": _values,
    "variables": _variables,
    "start": _state_change(Resource.start),
    "stop": _state_change(Resource.stop),
    "step": _state_change(Resource.step),
    "init": _state_change(Resource.init),
}


def parse_request(payload: bytes) -> dict[str, Any] | dict[str, Any]:
    """Decode a request; returns the request, or an error reply with `ok` False."""
    if len(payload) > MAX_REQUEST_BYTES:
        return error_reply("too_large", f"request larger than {MAX_REQUEST_BYTES} bytes")
    try:
        request = json.loads(payload)
    except (ValueError, UnicodeDecodeError):
        return error_reply("bad_request", "request is not valid JSON")
    if not isinstance(request, dict) or not isinstance(request.get("cmd"), str):
        return error_reply("bad_request", 'request must be an object with a "cmd" string')
    return request


def execute(resource: Resource, payload: bytes) -> dict[str, Any]:
    request = parse_request(payload)
    if request.get("ok") is False:
        return request
    handler = COMMANDS.get(request["cmd"])
    if handler is None:
        return error_reply("unknown_command", f"unknown command '{request['cmd']}'")
    try:
        return handler(resource)
    except CommandRefused as refused:
        return error_reply(refused.code, refused.message)
