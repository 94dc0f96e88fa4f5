"""What a resource does for each command of the protocol (runtime/contract/protocol.py).

A request is decoded and checked whole by the contract's decoder, then its session is
checked against the level the command needs, then one handler per command acts on the
resource and returns the command's typed reply. Every refusal, wherever it arises, is a
`Refusal` and becomes the error reply; nothing a client sends can raise past `execute`.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from typing import Any

from runtime import online_writes, program_control, reload_switch
from runtime.commissioning import not_commissioned
from runtime.contract import protocol as p
from runtime.contract import scram
from runtime.contract.accounts import ANONYMOUS
from runtime.contract.protocol import Request, decode_request, encode_refusal, encode_reply
from runtime.contract.refusal import Refusal
from runtime.disposal import DISPOSAL
from runtime.online_parameters import set_parameter
from runtime.recorder import Recordings
from runtime.reload_switch import ReloadJob
from runtime.resource import Resource

Handler = Callable[[Resource, Any], Any]
log = logging.getLogger("runtime.commands")


def _status(resource: Resource) -> p.StatusReply:
    return p.StatusReply(resource.status())


def _then_status(action: Callable[[Resource, Any], None]) -> Handler:
    def run(resource: Resource, command: Any) -> p.StatusReply:
        action(resource, command)
        return _status(resource)

    return run


def _ms_to_ns(ms: int | None) -> int | None:
    return ms * 1_000_000 if ms is not None else None


def _login_begin(resource: Resource, command: p.LoginBegin, request: Request) -> p.LoginChallenge:
    """The challenge, signed with the resource's key: a client derives nothing from its
    password for a challenge that is not the resource's."""
    c = resource.begin_login(command.user, command.nonce, request.source)
    auth = scram.auth_message(
        resource.name, command.user, command.nonce, c.nonce, scram.unb64(c.salt), c.n, c.r, c.p
    )
    identity = resource.identity
    signature = scram.b64(identity.sign(scram.challenge_message(auth)))
    return p.LoginChallenge(c.nonce, c.salt, c.n, c.r, c.p, identity.public_key, signature)


def _login(resource: Resource, command: p.Login, request: Request) -> p.LoginReply:
    proof = scram.unb64(command.proof)
    proven = resource.finish_login(command.user, command.nonce, proof, request.source)
    session = proven.session
    signature, key = proven.server_signature, resource.identity.public_key
    return p.LoginReply(proven.token, session.user, session.level, signature, key)


def _events(resource: Resource, command: p.GetEvents) -> p.EventsReply:
    if command.log == "long":
        entries = resource.events.long_term_after(command.after, command.limit)
        return p.EventsReply([event for event, _ in entries], [prev for _, prev in entries])
    return p.EventsReply(resource.events.recent(command.after, command.limit))


def _watch(resource: Resource, command: p.Watch, request: Request) -> p.WatchReply:
    """A watch set belongs to the session that makes it (none when access is open)."""
    owner = _watcher(resource, request)
    session = resource.access.sessions.get(owner) if owner is not None else None
    account = (session.user, session.level) if session is not None else None
    online, now = resource.online, resource.clock.now_ns()
    paths, revision = online.watch(
        command.id, command.variables, command.period_ms, command.append, owner, now, account
    )
    return p.WatchReply(command.id, paths, revision)


def _watcher(resource: Resource, request: Request) -> str | None:
    """Whose watch sets a request acts on: its session's, each session seeing and
    stopping its own only (all are everybody's when access is open)."""
    return None if resource.access.open or not isinstance(request.token, str) else request.token


def _logout(resource: Resource, command: p.Logout, request: Request) -> p.Done:
    resource.access.logout(request.token or "")
    return p.Done()


def _transfer_begin(resource: Resource, command: p.TransferBegin) -> p.TransferBeginReply:
    resource.incoming.begin(command.size, command.crc)
    return p.TransferBeginReply(p.MAX_CHUNK)


def _load(resource: Resource, command: p.Load) -> p.StatusReply:
    artifact = resource.transferred("load")
    if artifact.resource.name != resource.name:  # sent to the wrong controller
        message = f"the configuration is for resource {artifact.resource.name}"
        resource.refused("load", message, artifact.crc)
        raise Refusal("resource", message)
    resource.load(artifact)
    return _status(resource)


def _reload(resource: Resource, command: p.Reload | p.ReloadPreview) -> Any:
    """`reload` and `reload_preview` in one go (the runtime process prepares on a worker
    thread instead, see CycleDriver)."""
    job = begin_reload(resource, command)
    job.prepare()
    return finish_reload(resource, job)


def _debug(action: Callable[[Resource, Any], None], heard: bool = True) -> Handler:
    """A debugging command: the debugger acts, the reply is its state; a read-write one
    tells the debugger its client is still there."""

    def run(resource: Resource, command: Any) -> p.DebugReply:
        if heard:
            resource.debugger.heard(resource)
        action(resource, command)
        return p.DebugReply(resource.debugger.state(resource.clock.now_ns()))

    return run


def _recordings(resource: Resource) -> Recordings:
    recordings = resource.recordings
    if not isinstance(recordings, Recordings):
        raise Refusal("not_allowed", "this resource has no state folder to record into")
    return recordings


HANDLERS: dict[type[p.Command[Any]], Handler] = {
    p.GetStatus: lambda r, c: _status(r),
    p.GetVariables: lambda r, c: p.VariablesReply(r.variables.infos()),
    p.GetIo: lambda r, c: (
        p.IoReply(r.field_io.status(), r.field_io.points())
        if r.field_io is not None
        else p.IoReply(None, [])
    ),
    p.GetParameters: lambda r, c: p.ParametersReply(r.params, [x.config for x in r.programs]),
    p.GetForcing: lambda r, c: p.ForcingReply(r.forcing.state()),
    p.GetEvents: _events,
    p.Start: _then_status(lambda r, c: r.start()),
    p.Stop: _then_status(lambda r, c: r.stop()),
    p.ResetStats: _then_status(lambda r, c: r.reset_stats()),
    p.StartProgram: _then_status(lambda r, c: program_control.start_program(r, c.program)),
    p.StopProgram: _then_status(lambda r, c: program_control.stop_program(r, c.program)),
    p.Force: _then_status(lambda r, c: r.forcing.force(c.variable, c.value, c.switch)),
    p.Unforce: _then_status(lambda r, c: r.forcing.unforce(c.variable)),
    p.StartForcing: _then_status(lambda r, c: r.forcing.start(c.program, _ms_to_ns(c.timeout_ms))),
    p.StopForcing: _then_status(lambda r, c: r.forcing.stop(c.program)),
    p.Init: _then_status(lambda r, c: r.init()),
    p.ColdStart: _then_status(lambda r, c: r.cold_start()),
    p.Step: _then_status(lambda r, c: r.step()),
    p.Freeze: _then_status(lambda r, c: program_control.freeze(r, c.program)),
    p.Unfreeze: _then_status(lambda r, c: program_control.unfreeze(r, c.program)),
    p.StepProgram: _then_status(
        lambda r, c: program_control.step_program(r, c.program, _ms_to_ns(c.interval_ms))
    ),
    p.Write: _then_status(lambda r, c: online_writes.write(r, c.variable, c.value)),
    p.SetParameter: _then_status(lambda r, c: set_parameter(r, c.name, c.value)),
    p.TransferBegin: _transfer_begin,
    p.TransferChunk: lambda r, c: p.TransferChunkReply(r.incoming.chunk(c.offset, c.data)),
    p.Load: _load,
    p.ReloadPreview: _reload,
    p.Reload: _reload,
    p.RecordStart: lambda r, c: p.RecordingReply(_recordings(r).start(r, c)),
    p.RecordStop: lambda r, c: p.RecordingReply(_recordings(r).stop(r, c.id)),
    p.RecordDelete: lambda r, c: p.RecordingsReply(_recordings(r).delete(c.id)),
    p.DebugGet: lambda r, c: _debug(lambda r, c: None, heard=c.keep)(r, c),
    p.DebugSet: _debug(lambda r, c: r.debugger.set_file(r, c.file, c.breakpoints)),
    p.DebugClear: _debug(lambda r, c: r.debugger.clear(r)),
    p.DebugContinue: _debug(lambda r, c: r.debugger.continue_(r, c.program)),
    p.DebugStep: _debug(lambda r, c: r.debugger.step(r, c.program, c.kind)),
    p.DebugRunTo: _debug(lambda r, c: r.debugger.run_to(r, c.program, c.file, c.line)),
    p.DebugOptions: _debug(lambda r, c: r.debugger.set_timeout(r, c.silent_s)),
    p.DebugStack: lambda r, c: p.StackReply(r.debugger.frames(c.program)),
    p.DebugVariables: lambda r, c: p.DebugVariablesReply(
        r.debugger.variables(c.program, c.frame, c.path)
    ),
}


# commands whose answer reads files or is long to build: checked on the cycle thread, where
# they return the work that reads or builds, which the runtime process runs on another
# thread (the cycle never waits on a disk, nor on encoding 100,000 values); `answer` runs
# it at once
LATER_HANDLERS: dict[type[p.Command[Any]], Callable[[Resource, Any], Callable[[], Any]]] = {
    p.GetValues: lambda r, c: _values_later(r),
    p.RecordList: lambda r, c: _in_reply(_recordings(r).listing(), p.RecordingsReply),
    p.RecordRead: lambda r, c: _recordings(r).reading(c.file, c.offset, c.length),
}


def _values_later(resource: Resource) -> Callable[[], p.ValuesReply]:
    cycle, values = resource.cycle_count, resource.variables.read_values()
    return lambda: p.ValuesReply(values(), cycle)


def _in_reply(work: Callable[[], Any], reply: Callable[[Any], Any]) -> Callable[[], Any]:
    return lambda: reply(work())


# the commands that act on the request's session itself, or need to know where it came from
SESSION_HANDLERS: dict[type[p.Command[Any]], Callable[[Resource, Any, Request], Any]] = {
    p.LoginBegin: _login_begin,
    p.Login: _login,
    p.Logout: _logout,
    p.Watch: _watch,
    p.Unwatch: lambda r, c, q: p.UnwatchReply(r.online.watches.drop(c.id, _watcher(r, q))),
    p.GetWatches: lambda r, c, q: p.WatchesReply(r.online.watches.ids(_watcher(r, q))),
}


def execute(
    resource: Resource, payload: bytes, mac: bytes | None = None, source: str = ANONYMOUS
) -> bytes:
    """A request as it comes off the bus (with its MAC and source), answered: the encoded
    reply or refusal."""
    return respond(resource, lambda: answer(resource, decode_request(payload, source, mac)))


def respond(resource: Resource, work: Callable[[], Any]) -> bytes:
    """The encoded reply of `work`, or of its refusal; a defect met on the way is refused as
    `internal`, never the end of the process."""
    try:
        return encode_reply(work())
    except Refusal as refusal:
        return encode_refusal(refusal)
    except Exception as exc:
        return encode_refusal(internal_failure(resource, exc))


def internal_failure(resource: Resource, exc: Exception) -> Refusal:
    """A defect of the runtime met while answering: logged with its traceback, an event
    (short-term), and an `internal` refusal for the client. The resource runs on: every
    change a command makes is checked before it is applied, so nothing is half-applied."""
    log.exception("internal error while answering a command")
    cause = f"{type(exc).__name__}: {str(exc)[:200]}"
    resource.recorder.record("error", f"internal error while answering a command: {cause}")
    return Refusal("internal", f"internal error in the runtime ({type(exc).__name__})")


def answer(resource: Resource, request: Request) -> Any:
    """The typed reply to a decoded request; Refusal when it is refused."""
    authorize(resource, request)
    kind = type(request.command)
    if kind in SESSION_HANDLERS:
        return SESSION_HANDLERS[kind](resource, request.command, request)
    if kind in LATER_HANDLERS:
        return LATER_HANDLERS[kind](resource, request.command)()
    return HANDLERS[kind](resource, request.command)


def authorize(resource: Resource, request: Request) -> None:
    """Whether the request's session allows its command (the resource checks this for
    every request, whoever sends it); sets who acts, for the events."""
    resource.recorder.acting_user = None
    needed = request.command.level()
    if needed is None:  # the login's two steps
        return
    if (
        resource.setup is not None
        and request.token is None
        and isinstance(request.command, p.GetStatus)
    ):
        return  # a runtime waiting for its first configuration says so to anyone
    try:
        session = resource.access.check(
            request.token, needed, request.signed, request.mac, request.seq
        )
    except Refusal as refused:
        if resource.setup is None:
            raise
        raise not_commissioned(refused) from None
    resource.recorder.acting_user = session.user if session is not None else None


def begin_reload(resource: Resource, command: p.Reload | p.ReloadPreview) -> ReloadJob:
    """The first half of `reload` and `reload_preview`: checks, and the job to prepare
    (the runtime process prepares it on a worker thread while cycles go on)."""
    if isinstance(command, p.ReloadPreview):
        return reload_switch.begin_preview(resource, resource.incoming.complete(), command.renames)
    return reload_switch.begin(
        resource,
        resource.transferred("reload"),
        command.renames,
        watchdog_ms=command.watchdog_ms,
        target_cycle_ms=command.target_cycle_ms,
        user=resource.recorder.acting_user,
        expected_crc=command.expected_crc,
    )


def finish_reload(resource: Resource, job: ReloadJob) -> p.ReloadPlanReply | p.ReloadReply:
    """The second half, between two cycles: the switch-over (or the plan), and the reply."""
    if job.preview:
        if job.plan is None:
            assert job.failure is not None
            raise job.failure
        reply = p.ReloadPlanReply(job.plan.info())
        DISPOSAL.dispose(job.let_go())  # freed between cycles, as after a reload
        return reply
    return p.ReloadReply(reload_switch.finish(resource, job), resource.status())
