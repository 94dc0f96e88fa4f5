"""Commands a client may send to a resource, and their structured replies.

Every reply is JSON: `{"ok": true, ...}` or `{"ok": false, "error": {"code", "message"}}`;
bad input gets an error reply, never an exception that escapes to the cycle.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from typing import Any, TypeVar

from runtime.access import ADMINISTRATOR_PARAMETERS, COMMAND_LEVELS, AccessDenied
from runtime.contract.artifact import Artifact
from runtime.resource import CommandRefused, ReloadJob, Resource
from runtime.transfer import MAX_CHUNK, TransferError

MAX_REQUEST_BYTES = 64 * 1024


def error_reply(code: str, message: str) -> dict[str, Any]:
    return {"ok": False, "error": {"code": code, "message": message}}


Request = dict[str, Any]
Reply = dict[str, Any]
T = TypeVar("T")


def _status(resource: Resource, request: Request) -> Reply:
    return {"ok": True, "status": resource.status()}


def _values(resource: Resource, request: Request) -> Reply:
    return {"ok": True, "values": resource.values(), "cycle": resource.cycle_count}


def _variables(resource: Resource, request: Request) -> Reply:
    return {"ok": True, "variables": resource.variables()}


def _events(resource: Resource, request: Request) -> Reply:
    after = _arg(request, "after", int, 0)
    limit = _arg(request, "limit", int, 200)
    return {"ok": True, "events": [e.as_json() for e in resource.events.recent(after, limit)]}


def _forcing(resource: Resource, request: Request) -> Reply:
    return {"ok": True, "forcing": resource.forcing()}


def _parameters(resource: Resource, request: Request) -> Reply:
    programs = [p.config.__dict__ for p in resource.programs]
    return {"ok": True, "resource": resource.params.__dict__, "programs": programs}


def _arg(request: Request, name: str, kind: type, default: Any = ...) -> Any:
    """A request argument of the given JSON type; CommandRefused when missing or wrong."""
    if name not in request:
        if default is ...:
            raise CommandRefused("bad_request", f'"{name}" is missing')
        return default
    value = request[name]
    if kind is not object and (
        not isinstance(value, kind) or (kind is int and isinstance(value, bool))
    ):
        raise CommandRefused("bad_request", f'"{name}" must be a {kind.__name__}')
    return value


def _ms_to_ns(request: Request, name: str) -> int | None:
    value = _arg(request, name, int, None)
    if value is not None and value <= 0:
        raise CommandRefused("bad_request", f'"{name}" must be positive')
    return value * 1_000_000 if value is not None else None


def _then_status(
    action: Callable[[Resource, Request], None],
) -> Callable[[Resource, Request], Reply]:
    def run(resource: Resource, request: Request) -> Reply:
        action(resource, request)
        return {"ok": True, "status": resource.status()}

    return run


def _program(request: Request) -> str:
    return str(_arg(request, "program", str))


def _transfer_begin(resource: Resource, request: Request) -> Reply:
    resource.incoming.begin(_arg(request, "size", int), _arg(request, "crc", str))
    return {"ok": True, "max_chunk": MAX_CHUNK}


def _transfer_chunk(resource: Resource, request: Request) -> Reply:
    received = resource.incoming.chunk(_arg(request, "offset", int), _arg(request, "data", str))
    return {"ok": True, "received": received}


def _renames(request: Request) -> dict[str, str]:
    renames = _arg(request, "renames", dict, {})
    if not all(isinstance(k, str) and isinstance(v, str) for k, v in renames.items()):
        raise CommandRefused("bad_request", '"renames" maps new names to old names (strings)')
    return dict(renames)


def _transferred(resource: Resource, what: str) -> Artifact:
    """The artifact the transfer brought; a failed transfer is a refused load / reload."""
    try:
        return resource.incoming.complete()
    except TransferError as exc:
        resource.refused(what, str(exc))
        raise


def _load(resource: Resource, request: Request) -> Reply:
    artifact = _transferred(resource, "load")
    if artifact.resource.name != resource.name:  # sent to the wrong controller
        message = f"the configuration is for resource {artifact.resource.name}"
        resource.refused("load", message, artifact.crc)
        raise CommandRefused("resource", message)
    resource.load(artifact)
    return {"ok": True, "status": resource.status()}


def begin_reload(resource: Resource, request: Request) -> ReloadJob:
    """The first half of `reload` and `reload_preview`: checks, and the job to prepare
    (the runtime process prepares it on a worker thread while cycles go on)."""
    if request["cmd"] == "reload_preview":
        return resource.begin_preview(resource.incoming.complete(), _renames(request))
    return resource.begin_reload(
        _transferred(resource, "reload"),
        _renames(request),
        watchdog_ms=_arg(request, "watchdog_ms", int, None),
        target_cycle_ms=_arg(request, "target_cycle_ms", int, None),
        user=resource.acting_user,
        expected_crc=_arg(request, "expected_crc", str, None),
    )


def finish_reload(resource: Resource, job: ReloadJob) -> Reply:
    """The second half, between two cycles: the switch-over (or the plan), and the reply."""
    if job.preview:
        if job.plan is None:
            return error_reply("reload_failed", f"the new configuration failed: {job.failure}")
        return {"ok": True, "plan": job.plan.as_json()}
    return guarded(
        lambda: {"ok": True, "reload": resource.finish_reload(job), "status": resource.status()}
    )


def _reload(resource: Resource, request: Request) -> Reply:
    """`reload` and `reload_preview` in one go (the runtime process prepares on a worker
    thread instead, see CycleDriver)."""
    job = begin_reload(resource, request)
    job.prepare()
    return finish_reload(resource, job)


def _watch(resource: Resource, request: Request) -> Reply:
    names = _arg(request, "variables", list)
    if not all(isinstance(name, str) for name in names):
        raise CommandRefused("bad_request", '"variables" is a list of variable names')
    watch_id = _arg(request, "id", str)
    period = _arg(request, "period_ms", int, 100)
    paths = resource.watch(watch_id, names, period, _arg(request, "append", bool, False))
    return {"ok": True, "id": watch_id, "variables": paths}


def _unwatch(resource: Resource, request: Request) -> Reply:
    return {"ok": True, "dropped": resource.watches.drop(_arg(request, "id", str))}


def _watches(resource: Resource, request: Request) -> Reply:
    return {"ok": True, "watches": resource.watches.ids()}


def _login(resource: Resource, request: Request) -> Reply:
    token, session = resource.login(_arg(request, "user", str), _arg(request, "password", str))
    return {"ok": True, "token": token, "user": session.user, "level": session.level}


def _logout(resource: Resource, request: Request) -> Reply:
    resource.access.logout(_arg(request, "token", str, ""))
    return {"ok": True}


COMMANDS: dict[str, Callable[[Resource, Request], Reply]] = {
    "login": _login,
    "logout": _logout,
    "watch": _watch,
    "unwatch": _unwatch,
    "watches": _watches,
    "transfer_begin": _transfer_begin,
    "transfer_chunk": _transfer_chunk,
    "load": _load,
    "reload_preview": _reload,
    "reload": _reload,
    "status": _status,
    "values": _values,
    "variables": _variables,
    "events": _events,
    "forcing": _forcing,
    "parameters": _parameters,
    "start": _then_status(lambda r, q: r.start()),
    "stop": _then_status(lambda r, q: r.stop()),
    "step": _then_status(lambda r, q: r.step()),
    "init": _then_status(lambda r, q: r.init()),
    "cold_start": _then_status(lambda r, q: r.cold_start()),
    "start_program": _then_status(lambda r, q: r.start_program(_program(q))),
    "stop_program": _then_status(lambda r, q: r.stop_program(_program(q))),
    "freeze": _then_status(lambda r, q: r.freeze(_program(q))),
    "unfreeze": _then_status(lambda r, q: r.unfreeze(_program(q))),
    "step_program": _then_status(
        lambda r, q: r.step_program(_program(q), _ms_to_ns(q, "interval_ms"))
    ),
    "write": _then_status(lambda r, q: r.write(_arg(q, "variable", str), _arg(q, "value", object))),
    "force": _then_status(
        lambda r, q: r.force(
            _arg(q, "variable", str), _arg(q, "value", object), _arg(q, "switch", bool, True)
        )
    ),
    "unforce": _then_status(lambda r, q: r.unforce(_arg(q, "variable", str))),
    "start_forcing": _then_status(
        lambda r, q: r.start_forcing(_arg(q, "program", str, None), _ms_to_ns(q, "timeout_ms"))
    ),
    "stop_forcing": _then_status(lambda r, q: r.stop_forcing(_arg(q, "program", str, None))),
    "set_parameter": _then_status(
        lambda r, q: r.set_parameter(_arg(q, "name", str), _arg(q, "value", object))
    ),
    "reset_stats": _then_status(lambda r, q: r.reset_stats()),
}


def parse_request(payload: bytes) -> dict[str, Any]:
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
    refusal = authorize(resource, request)
    if refusal is not None:
        return refusal
    return guarded(lambda: handler(resource, request))


def authorize(resource: Resource, request: Request) -> Reply | None:
    """Whether the caller's session token allows this command (the resource checks it for
    every request, whoever sends it); sets who acts, for the events. An error reply, or
    None to go on."""
    command = request["cmd"]
    resource.acting_user = None
    if command in ("login", "logout"):
        return None
    needed = COMMAND_LEVELS.get(command, "administrator")
    if command == "set_parameter" and request.get("name") in ADMINISTRATOR_PARAMETERS:
        needed = "administrator"
    try:
        session = resource.access.check(request.get("token"), needed)
    except AccessDenied as denied:
        return error_reply(denied.code, denied.message)
    resource.acting_user = session.user if session is not None else None
    return None


def start_reload(resource: Resource, request: Request) -> ReloadJob | Reply:
    """For the runtime process, which prepares a reload on a worker thread: the job, or
    the reply that refuses it (access, state, transfer)."""
    refusal = authorize(resource, request)
    if refusal is not None:
        return refusal
    return guarded(lambda: begin_reload(resource, request))


def guarded(action: Callable[[], T]) -> T | Reply:
    """What the action gives, or the structured error reply for a refusal."""
    try:
        return action()
    except CommandRefused as refused:
        return error_reply(refused.code, refused.message)
    except TransferError as exc:
        return error_reply("transfer", str(exc))
