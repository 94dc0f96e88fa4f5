"""`padt dap`: a Debug Adapter Protocol server, so that VS Code (or any DAP client) debugs a
RUNNING resource: breakpoints, logpoints, the stack, the variables, steps and continue.

It only translates: each request becomes a command of the resource through the same
debugging session every client uses (`backend/engineering/debug_session.py`), logged in
with `user` and PADT_PASSWORD like every `padt` command; the resource checks each one. One
DAP thread per user program (its id, the program's id); a program in BKPT stands while the
other programs and the resource run on ("pausing stops the program, not the world").
Messages go over stdin/stdout (nothing else is written to stdout: the log goes to stderr),
or, with `--port`, over TCP on 127.0.0.1 for VS Code's `debugServer`. docs/debugging.md
shows the launch configuration."""

from __future__ import annotations

import contextlib
import logging
import os
import re
import signal
import socket
import sys
import threading
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any, BinaryIO

from backend.engineering.debug_session import DebugSession, source_name
from backend.engineering.literals import LiteralError, parse_literal
from backend.engineering.resource_client import ResourceClient, ResourceUnreachable
from padt.dap_messages import Malformed, MessageWriter, read_message
from runtime.contract import protocol as p
from runtime.contract.keyspace import resource_name_problem
from runtime.contract.protocol import ProgramState
from runtime.contract.refusal import Refusal
from runtime.contract.session_options import DEFAULT_ENDPOINT, RouterUnreachable
from runtime.contract.values import format_value

log = logging.getLogger("padt.dap")

CAPABILITIES = {
    "supportsConfigurationDoneRequest": True,
    "supportsConditionalBreakpoints": True,
    "supportsHitConditionalBreakpoints": True,
    "supportsLogPoints": True,
    "supportsSetVariable": True,
    "supportsEvaluateForHovers": True,
    "supportsTerminateRequest": False,
    "supportsRestartRequest": False,
}
# DAP's reasons for a stop, by the resource's
STOP_REASONS = {"breakpoint": "breakpoint", "step": "step", "run to": "goto", "cycle end": "step"}
_HIT = re.compile(r"\s*(>=|>)?\s*(\d{1,10})\s*")
_LOGGED = re.compile(r"\{([^{}]*)\}")
_ROOT = re.compile(r"[^.\[]+")  # a path's first name: a program's or a global's
_STEP = re.compile(r"\.?[^.\[]+|\[[^\]]*\]")  # one member or element further
MAX_EXPRESSION_PATH = 512


class DapError(Exception):
    """A request refused: its message goes to the client in the error response."""


@dataclass(frozen=True)
class VariableRef:
    """What a DAP `variablesReference` stands for: a frame's variables (path "") or the
    members or elements of one of them."""

    program: str
    frame: int
    path: str


@dataclass(frozen=True)
class GlobalsRef:
    """The resource's global variables (path ""), or the members or elements of one."""

    path: str


Ref = VariableRef | GlobalsRef


class Attached:
    """The session with one resource: its client (over a Zenoh session of its own) and
    the debugging session."""

    def __init__(self, client: ResourceClient, debug: DebugSession, project: Path) -> None:
        self.client, self.debug, self.project = client, debug, project

    def close(self) -> None:
        """Every breakpoint gone first, so that no program stays in BKPT."""
        try:
            self.debug.clear_all()
        except (Refusal, ResourceUnreachable) as exc:
            log.warning("padt dap: breakpoints not cleared: %s", exc)
        self.debug.close()  # its threads end before the session they ask through
        self.client.close()
        self.client.session.close()


class DapServer:
    """One client's debugging session; requests are taken in order on the caller's thread,
    events come from the threads that follow the resource."""

    def __init__(self, writer: MessageWriter) -> None:
        self.out = writer
        self.attached: Attached | None = None
        self._lines_from = 1  # the client's first line number (DAP's linesStartAt1)
        self._lock = threading.Lock()
        self._told: dict[str, p.DebugPause] = {}  # the stops the client was told of
        self._threads: dict[str, int] = {}  # program name (upper case) -> its id
        self._names: dict[int, str] = {}  # program id -> its name
        self._frames: dict[int, tuple[str, int]] = {}  # frame id -> program, index
        self._refs: dict[int, Ref] = {}
        self._next_ref = 1
        self._wake = threading.Event()  # a status showed a told stop may have ended
        self._closed = False
        self._after: list[Callable[[], None]] = []  # events due after the response
        self._handlers: dict[str, Callable[[dict[str, Any]], dict[str, Any] | None]] = {
            "initialize": self._initialize,
            "attach": self._attach,
            "launch": self._attach,  # a running resource is never launched: attached to
            "setBreakpoints": self._set_breakpoints,
            "setExceptionBreakpoints": lambda args: {"breakpoints": []},
            "configurationDone": self._configuration_done,
            "threads": self._threads_request,
            "stackTrace": self._stack_trace,
            "scopes": self._scopes,
            "variables": self._variables,
            "setVariable": self._set_variable,
            "evaluate": self._evaluate,
            "next": lambda args: self._step(args, "over"),
            "stepIn": lambda args: self._step(args, "into"),
            "stepOut": lambda args: self._step(args, "out"),
            "continue": self._continue,
            "pause": self._pause,
        }

    # ---- the loop

    def serve(self, stream: BinaryIO, stop: StopSignal) -> None:
        """Take requests until `disconnect`, the end of the stream or `stop`; the
        resource's breakpoints of this client are cleared either way."""
        try:
            while True:
                with stop.waiting():
                    message = read_message(stream)
                if message is None:
                    return
                if isinstance(message, Malformed):
                    log.warning("padt dap: malformed message: %s", message.reason)
                    self.out.refuse(message.seq, message.command, message.reason)
                    continue
                if not self._handle(message):
                    return
        finally:
            self._detach()

    def _handle(self, request: dict[str, Any]) -> bool:
        """Answer one request; False after `disconnect`."""
        command: str = request["command"]
        if command == "disconnect":
            self._detach()
            self.out.respond(request)
            return False
        handler = self._handlers.get(command)
        self._after.clear()
        if handler is None:
            # not shown: a client's extension may send requests of its own (VS Code's
            # JavaScript debugger does when its type carries the `debugServer`)
            message = f"padt dap does not support the request '{command[:80]}'"
            self.out.refuse(request["seq"], command, message, show=False)
            return True
        try:
            body = handler(request["arguments"])
        except DapError as exc:
            self.out.refuse(request["seq"], command, str(exc))
        except Refusal as refused:
            self.out.refuse(request["seq"], command, f"refused ({refused.code}): {refused.message}")
        except ResourceUnreachable as exc:
            self.out.refuse(request["seq"], command, f"the resource did not answer: {exc}")
        except Exception as exc:  # a defect of ours: the session goes on, the log says where
            log.exception("padt dap: %s failed", command)
            self.out.refuse(request["seq"], command, f"padt dap failed: {exc!r}")
        else:
            self.out.respond(request, body)
            for then in self._after:
                then()
        return True

    def _detach(self) -> None:
        with self._lock:
            self._closed = True
            attached, self.attached = self.attached, None
        self._wake.set()
        if attached is not None:
            attached.close()

    # ---- requests

    def _initialize(self, args: dict[str, Any]) -> dict[str, Any]:
        self._lines_from = 0 if args.get("linesStartAt1") is False else 1
        return CAPABILITIES

    def _attach(self, args: dict[str, Any]) -> dict[str, Any] | None:
        if self.attached is not None:
            raise DapError("already attached to a resource")
        resource = _text(args, "resource")
        problem = resource_name_problem(resource)
        if problem is not None:
            raise DapError(f"resource: {problem}")
        project = Path(_text(args, "project"))
        if not project.is_dir():
            raise DapError(f"project: {project} is no folder")
        endpoint = _optional_text(args, "zenoh") or DEFAULT_ENDPOINT
        config = _optional_text(args, "zenohConfig")
        user = _optional_text(args, "user")
        password = os.environ.get("PADT_PASSWORD")
        if user is not None and password is None:
            raise DapError(
                f"log in as {user}: set PADT_PASSWORD in the environment of `padt dap` "
                "(it cannot be asked for: stdin carries the protocol)"
            )
        from runtime.contract.session import open_client

        try:
            session = open_client(endpoint, Path(config) if config else None)
        except RouterUnreachable as exc:
            raise DapError(str(exc)) from None
        try:
            client = ResourceClient(session, resource)
            if user is not None and password is not None:
                try:
                    client.login(user, password)
                except Refusal as refused:
                    raise DapError(f"login refused ({refused.code}): {refused.message}") from None
                client.use_credentials(user, password)
            self._know_programs(client.ask(p.GetStatus()).status)
            debug = DebugSession(client)
            try:
                debug.start()
            except BaseException:
                debug.close()  # its threads run from the start on, refused or not
                raise
        except BaseException:
            session.close()
            raise
        self.attached = Attached(client, debug, project.resolve())
        debug.on_stop(self._tell)
        client.on_events(self._resource_event)
        client.on_status(self._status)
        client.on_alive(self._alive)
        threading.Thread(target=self._watch, name="padt-dap-continued", daemon=True).start()
        log.info("padt dap: attached to %s over %s", resource, endpoint)
        # the client may now send its breakpoints, then configurationDone
        self._after.append(lambda: self.out.event("initialized"))
        return None

    def _set_breakpoints(self, args: dict[str, Any]) -> dict[str, Any]:
        attached = self._attached()
        source = args.get("source")
        if not isinstance(source, dict) or not isinstance(source.get("path"), str):
            raise DapError("setBreakpoints needs `source` with its `path`")
        path = source["path"]
        wanted = args.get("breakpoints", [])
        if not isinstance(wanted, list) or len(wanted) > p.MAX_BREAKPOINTS:
            raise DapError(f"`breakpoints`: a list of at most {p.MAX_BREAKPOINTS}")
        try:
            name = source_name(attached.project, Path(path))
        except (ValueError, OSError):
            why = f"{path} is no file of the project {attached.project}"
            return {"breakpoints": [_unverified(why) for _ in wanted]}
        specs: list[p.BreakpointSpec] = []
        problems: list[str | None] = []
        for entry in wanted:
            try:
                specs.append(self._spec(entry))
                problems.append(None)
            except DapError as exc:
                problems.append(str(exc))
        state = attached.debug.set_breakpoints(name, specs)
        armed = [b for b in state.breakpoints if b.file == name]  # in the order of `specs`
        answers, taken = [], iter(armed)
        for problem in problems:
            if problem is not None:
                answers.append(_unverified(problem))
                continue
            point = next(taken, None)
            if point is None:
                answers.append(_unverified("not armed"))
                continue
            shown: dict[str, Any] = {"id": point.id, "verified": point.verified}
            shown["line"] = self._dap_line(point.line or point.requested)
            shown["source"] = {"name": Path(name).name, "path": path}
            if point.message:
                shown["message"] = point.message
            answers.append(shown)
        return {"breakpoints": answers}

    def _spec(self, entry: Any) -> p.BreakpointSpec:
        """A DAP source breakpoint as the resource's; DapError says why not."""
        if not isinstance(entry, dict):
            raise DapError("a breakpoint is a JSON object")
        line = _integer(entry, "line") + 1 - self._lines_from
        if not 1 <= line <= 10_000_000:
            raise DapError(f"line {line} is out of range")
        condition = _optional_text(entry, "condition")
        if condition is not None and not condition.strip():
            condition = None
        hits = _optional_text(entry, "hitCondition")
        message = _optional_text(entry, "logMessage")
        logged = None
        if message is not None:
            logged = [found.strip() for found in _LOGGED.findall(message) if found.strip()]
            if len(logged) > p.MAX_LOGGED:
                raise DapError(f"a log message records at most {p.MAX_LOGGED} {{expressions}}")
        for text in [condition or "", *(logged or [])]:
            if len(text) > p.MAX_EXPRESSION:
                raise DapError(f"an expression longer than {p.MAX_EXPRESSION} characters")
        return p.BreakpointSpec(
            line,
            condition=condition,
            hit_count=_hit_count(hits) if hits and hits.strip() else None,
            log=logged,
        )

    def _configuration_done(self, args: dict[str, Any]) -> None:
        paused = self._attached().debug.state().paused
        if paused is not None:  # a program already stands (set by another client)
            self._after.append(lambda: self._tell(paused))

    def _threads_request(self, args: dict[str, Any]) -> dict[str, Any]:
        status = self._attached().client.ask(p.GetStatus()).status
        self._know_programs(status)
        return {"threads": [{"id": x.id, "name": x.name} for x in status.programs]}

    def _stack_trace(self, args: dict[str, Any]) -> dict[str, Any]:
        attached = self._attached()
        program = self._program(args)
        frames = attached.debug.stack(program)
        shown = []
        for frame in frames:
            name = frame.name
            if frame.instance and frame.instance.upper() != frame.name.upper():
                name = f"{frame.name} ({frame.instance})"
            shown.append(
                {
                    "id": self._frame_id(program, frame.index),
                    "name": name,
                    "line": self._dap_line(frame.line),
                    "column": 1,
                    "source": {
                        "name": Path(frame.file).name,
                        "path": str(attached.project / frame.file),
                    },
                }
            )
        if not frames:  # at the end of its program cycle: its own variables still show
            shown.append(
                {
                    "id": self._frame_id(program, 0),
                    "name": f"{program} (end of the program cycle)",
                    "line": 0,
                    "column": 0,
                    "presentationHint": "label",
                }
            )
        start = _optional_integer(args, "startFrame") or 0
        levels = _optional_integer(args, "levels") or len(shown)
        return {"stackFrames": shown[start : start + levels], "totalFrames": len(shown)}

    def _scopes(self, args: dict[str, Any]) -> dict[str, Any]:
        program, index = self._frame(args)
        return {
            "scopes": [
                {
                    "name": "Locals",
                    "presentationHint": "locals",
                    "variablesReference": self._reference(VariableRef(program, index, "")),
                    "expensive": False,
                },
                {
                    "name": "Globals",
                    "variablesReference": self._reference(GlobalsRef("")),
                    "expensive": False,
                },
            ]
        }

    def _variables(self, args: dict[str, Any]) -> dict[str, Any]:
        ref = self._ref(args, "variablesReference")
        return {"variables": [self._variable(ref, v) for v in self._listed(ref)]}

    def _listed(self, ref: Ref) -> list[p.DebugVariable]:
        attached = self._attached()
        if isinstance(ref, GlobalsRef):
            return global_variables(attached.client, set(self._threads), ref.path)
        return attached.debug.variables(ref.program, ref.frame, ref.path)

    def _set_variable(self, args: dict[str, Any]) -> dict[str, Any]:
        attached = self._attached()
        ref = self._ref(args, "variablesReference")
        name, text = _text(args, "name"), _text(args, "value")
        variable = _named(self._listed(ref), name)
        if variable.children:
            raise DapError(f"{name} is a {variable.type or 'structure'}: set its members")
        if variable.path is None:
            raise DapError(
                f"{name} is a local of a function or method: only a program's, an FB "
                "instance's and global variables can be written"
            )
        try:
            value = parse_literal(text, variable.type)
        except LiteralError as exc:
            raise DapError(f"{name}: {exc}") from None
        attached.client.ask(p.Write(variable.path, value))
        now = _named(self._listed(ref), name)
        return {"value": _shown(now), "type": now.type}

    def _evaluate(self, args: dict[str, Any]) -> dict[str, Any]:
        """A name of the frame or a global, or a member or element of one ("a.total",
        "arr[2]"): what a hover or a watch asks; no expressions are computed."""
        expression = _text(args, "expression").strip()
        if "frameId" not in args:
            raise DapError("only the variables of a stopped program's frames can be shown")
        if len(expression) > MAX_EXPRESSION_PATH:
            raise DapError(f"an expression longer than {MAX_EXPRESSION_PATH} characters")
        program, index = self._frame(args)
        if expression.endswith("]") and "[" in expression:
            cut = expression.rindex("[")
            parent, name = expression[:cut], expression[cut:]
        else:
            parent, _, name = expression.rpartition(".")
        shown: dict[str, Any] | None = None
        for ref in (VariableRef(program, index, parent), GlobalsRef(parent)):
            try:
                variable = _named(self._listed(ref), name)
            except (DapError, Refusal):
                continue
            shown = self._variable(ref, variable)
            break
        if shown is None:
            raise DapError(f"no variable '{expression}' in this frame or the globals")
        return {
            "result": shown["value"],
            "type": shown["type"],
            "variablesReference": shown["variablesReference"],
        }

    def _step(self, args: dict[str, Any], kind: p.DebugStepKind) -> dict[str, Any]:
        program = self._program(args)
        self._forget_frames()
        paused = self._attached().debug.step(program, kind).paused
        if paused is not None:  # where it now stands, told after the step's response
            self._after.append(lambda: self._tell(paused, again=True))
        return {}

    def _continue(self, args: dict[str, Any]) -> dict[str, Any]:
        program = self._program(args)
        self._forget_frames()
        with self._lock:
            self._told.pop(program.upper(), None)
        self._attached().debug.continue_(program)
        return {"allThreadsContinued": False}

    def _pause(self, args: dict[str, Any]) -> None:
        raise DapError(
            "pausing a running PLC program is not supported: set a breakpoint where it "
            "should stop (only that program stops there; the others run on)"
        )

    # ---- events, from the threads that follow the resource

    def _tell(self, pause: p.DebugPause, again: bool = False) -> None:
        """A `stopped` event for `pause`, once (`again`: after a step, where it may stand
        where it stood)."""
        with self._lock:
            key = pause.program.upper()
            if not again and self._told.get(key) == pause:
                return
            self._told[key] = pause
        thread = self._thread_of(pause.program)
        where = "the end of its program cycle" if pause.line == 0 else f"{pause.file}:{pause.line}"
        body: dict[str, Any] = {
            "reason": STOP_REASONS.get(pause.reason, "step"),
            "description": f"{pause.program} stands at {where} ({pause.reason})",
            "threadId": thread,
            "allThreadsStopped": False,  # the other programs run on
            "preserveFocusHint": False,
        }
        if pause.breakpoint is not None:
            body["hitBreakpointIds"] = [pause.breakpoint]
        self.out.event("stopped", body)

    def _status(self, status: p.Status) -> None:
        """On a Zenoh thread: a program told of as stopped that no longer stands is
        checked by `_watch` (no query from a Zenoh thread)."""
        standing = {x.name.upper() for x in status.programs if x.state == ProgramState.BKPT}
        if any(name not in standing for name in list(self._told)):
            self._wake.set()  # never the lock here: `_watch` holds it across a query

    def _watch(self) -> None:
        """A program the client was told of as stopped that left BKPT by other means (the
        resource stopped, another client continued it): a `continued` event."""
        while True:
            self._wake.wait()
            self._wake.clear()
            with self._lock:
                if self._closed:
                    return
                attached = self.attached
                if attached is None:
                    return
                # under the lock: no stop is told between this answer and its use, and
                # `_detach` closes the session only after it
                try:
                    paused = attached.debug.state().paused
                except (Refusal, ResourceUnreachable):
                    continue
                gone = [
                    name for name in self._told if paused is None or paused.program.upper() != name
                ]
                for name in gone:
                    del self._told[name]
            for name in gone:
                thread = self._threads.get(name, 0)
                self.out.event("continued", {"threadId": thread, "allThreadsContinued": False})

    def _resource_event(self, event: p.Event) -> None:
        """A logpoint's record: a line of the client's debug console."""
        if event.kind != "log":
            return
        body: dict[str, Any] = {"category": "console", "output": event.message + "\n"}
        attached, file, line = self.attached, event.details.get("file"), event.details.get("line")
        if attached is not None and isinstance(file, str) and isinstance(line, int):
            body["source"] = {"name": Path(file).name, "path": str(attached.project / file)}
            body["line"] = self._dap_line(line)
        self.out.event("output", body)

    def _alive(self, alive: bool) -> None:
        if not alive and self.attached is not None:
            resource = self.attached.client.resource
            self.out.event(
                "output", {"category": "important", "output": f"resource {resource} is gone\n"}
            )
            self.out.event("terminated")

    # ---- the tables of one stop

    def _attached(self) -> Attached:
        if self.attached is None:
            raise DapError("not attached to a resource: `attach` first")
        return self.attached

    def _know_programs(self, status: p.Status) -> None:
        with self._lock:
            for program in status.programs:
                self._threads[program.name.upper()] = program.id
                self._names[program.id] = program.name

    def _thread_of(self, program: str) -> int:
        if program.upper() not in self._threads and self.attached is not None:
            self._know_programs(self.attached.client.ask(p.GetStatus()).status)
        return self._threads.get(program.upper(), 0)

    def _program(self, args: dict[str, Any]) -> str:
        thread = _integer(args, "threadId")
        name = self._names.get(thread)
        if name is None:
            self._know_programs(self._attached().client.ask(p.GetStatus()).status)
            name = self._names.get(thread)
        if name is None:
            raise DapError(f"no program with the id {thread}")
        return name

    def _frame_id(self, program: str, index: int) -> int:
        with self._lock:
            for known, where in self._frames.items():
                if where == (program, index):
                    return known
            self._next_ref += 1
            self._frames[self._next_ref] = (program, index)
            return self._next_ref

    def _frame(self, args: dict[str, Any]) -> tuple[str, int]:
        found = self._frames.get(_integer(args, "frameId"))
        if found is None:
            raise DapError("that frame is gone: the program ran on")
        return found

    def _reference(self, ref: Ref) -> int:
        with self._lock:
            for known, value in self._refs.items():
                if value == ref:
                    return known
            self._next_ref += 1
            self._refs[self._next_ref] = ref
            return self._next_ref

    def _ref(self, args: dict[str, Any], name: str) -> Ref:
        found = self._refs.get(_integer(args, name))
        if found is None:
            raise DapError("those variables are gone: the program ran on")
        return found

    def _forget_frames(self) -> None:
        """Frames and variables are valid while a program stands (DAP's rule)."""
        with self._lock:
            self._frames.clear()
            self._refs.clear()

    def _variable(self, ref: Ref, variable: p.DebugVariable) -> dict[str, Any]:
        path = _below(ref.path, variable.name)
        below: Ref = GlobalsRef(path)
        if isinstance(ref, VariableRef):
            below = VariableRef(ref.program, ref.frame, path)
        children = self._reference(below) if variable.children else 0
        return {
            "name": variable.name,
            "value": _shown(variable),
            "type": variable.type,
            "evaluateName": path,
            "variablesReference": children,
        }

    def _dap_line(self, line: int) -> int:
        return line - 1 + self._lines_from


# ---- small readers of what a client sends (hostile: a wrong type is a DapError)


def _text(args: dict[str, Any], name: str) -> str:
    value = args.get(name)
    if not isinstance(value, str) or not value:
        raise DapError(f"`{name}`: a string is required")
    if len(value) > 4096:
        raise DapError(f"`{name}`: longer than 4096 characters")
    return value


def _optional_text(args: dict[str, Any], name: str) -> str | None:
    """None when absent, null or empty."""
    return None if args.get(name) in (None, "") else _text(args, name)


def _integer(args: dict[str, Any], name: str) -> int:
    value = args.get(name)
    if not isinstance(value, int) or isinstance(value, bool) or not 0 <= value < 2**53:
        raise DapError(f"`{name}`: a number is required")
    return value


def _optional_integer(args: dict[str, Any], name: str) -> int | None:
    return None if args.get(name) is None else _integer(args, name)


def _hit_count(text: str) -> int:
    """DAP's hit condition as the resource's hit count: "5" or ">= 5" stops from the
    fifth hit on, "> 5" from the sixth."""
    found = _HIT.fullmatch(text)
    if found is None:
        raise DapError(f"hit condition '{text[:80]}': write N or >= N (stop from the N-th hit)")
    count = int(found.group(2)) + (1 if found.group(1) == ">" else 0)
    if not 1 <= count <= 1_000_000_000:
        raise DapError(f"hit condition '{text[:80]}': N from 1 to 1000000000")
    return count


def _unverified(message: str) -> dict[str, Any]:
    return {"verified": False, "message": message}


def _named(variables: list[p.DebugVariable], name: str) -> p.DebugVariable:
    for variable in variables:
        if variable.name.upper() == name.strip().upper():
            return variable
    raise DapError(f"no variable '{name[:80]}' here")


def _below(parent: str, name: str) -> str:
    """The frame-relative path of a member ("a.total") or an element ("arr[2]")."""
    if not parent:
        return name
    return f"{parent}{name}" if name.startswith("[") else f"{parent}.{name}"


def global_variables(
    client: ResourceClient, programs: set[str], below: str
) -> list[p.DebugVariable]:
    """The resource's global variables (`below` ""), or the members or elements of the
    global structure or array `below`, as the frames' variables are listed: from the
    resource's list of variables, those of no program (`programs`, upper case)."""
    types = {
        v.path: v.type
        for v in client.ask(p.GetVariables()).variables
        if _root(v.path).upper() not in programs
    }
    values = client.ask(p.GetValues()).values
    shown = []
    for child in _children(types, below):
        leaf = child in types
        name = child[len(below) :].lstrip(".") if below else child
        value = values.get(child) if leaf else None
        shown.append(p.DebugVariable(name, types.get(child, ""), value, child, not leaf))
    return shown


def _root(path: str) -> str:
    found = _ROOT.match(path)
    return path if found is None else found.group(0)


def _children(paths: Iterable[str], below: str) -> list[str]:
    """The paths one step below `below` ("" : the roots), in the order of `paths`: a
    member ("g.x") or an element ("arr[2]")."""
    found: dict[str, None] = {}
    for path in paths:
        if below and not path.startswith((below + ".", below + "[")):
            continue
        step = _STEP.match(path, len(below))
        if step is not None:
            found.setdefault(path[: step.end()], None)
    return list(found)


def _shown(variable: p.DebugVariable) -> str:
    if variable.value is None and variable.children:
        return variable.type or "..."
    return format_value(variable.value, variable.type)


# ---- the command


def run(args: Any) -> int:
    """`padt dap [--port N]`: one client on stdin/stdout, or clients one after the other
    on 127.0.0.1:N. SIGTERM ends it as Ctrl-C does: a client's breakpoints cleared first."""
    logging.basicConfig(stream=sys.stderr, level=logging.INFO, format="%(message)s")
    stop = StopSignal()
    if args.port is None:
        # the protocol's own copy of stdout; whatever else writes to stdout (a library's
        # print) goes to stderr instead of corrupting the protocol
        protocol = os.fdopen(os.dup(sys.stdout.fileno()), "wb")
        os.dup2(sys.stderr.fileno(), sys.stdout.fileno())
        writer = MessageWriter(protocol)
        with contextlib.suppress(Stopped):
            DapServer(writer).serve(sys.stdin.buffer, stop)
        writer.close()
        return 0
    if not 0 <= args.port <= 65535:
        log.error("padt dap: --port %d is no TCP port", args.port)
        return 2
    return _serve_tcp(args.port, stop)


class Stopped(BaseException):
    """Raised by `StopSignal` in a wait for a client or a request; a BaseException, so
    that no `except Exception` of a request takes it."""


class StopSignal:
    """SIGTERM and SIGINT end `padt dap` in order. The handler runs on the main thread
    between two of its bytecodes: an exception raised there at any moment could land in
    a cleanup (`finally`, a `__del__`, a library's handler) that swallows it, or cut one
    short and leave a Zenoh session open, whose callback threads are not daemons (the
    interpreter waits for them at exit): the process would not end. So it raises
    `Stopped` only while the main thread waits (for a client, or for a request: nothing is
    half done there); during a request it only notes the stop, which the next wait sees."""

    def __init__(self) -> None:
        self.requested = False
        self._waiting = False
        for sig in (signal.SIGTERM, signal.SIGINT):
            signal.signal(sig, self._handle)

    def _handle(self, signum: int, frame: Any) -> None:
        self.requested = True
        if self._waiting:
            raise Stopped

    @contextlib.contextmanager
    def waiting(self) -> Iterator[None]:
        """Around a blocking wait: `Stopped` on a stop that came before it or comes during
        it (marked waiting first: a signal between the check and the wait is not lost)."""
        self._waiting = True
        try:
            if self.requested:
                raise Stopped
            yield
        finally:
            self._waiting = False


def _serve_tcp(port: int, stop: StopSignal) -> int:
    try:
        server = socket.create_server(("127.0.0.1", port))
    except OSError as exc:
        log.error("padt dap: cannot listen on 127.0.0.1:%d: %s", port, exc.strerror or exc)
        return 1
    with server:
        log.info("padt dap: listening on 127.0.0.1:%d", server.getsockname()[1])
        try:
            while True:
                with stop.waiting():
                    connection, peer = server.accept()
                log.info("padt dap: a client from %s:%d", *peer[:2])
                with connection:
                    _serve_connection(connection, stop)
                log.info("padt dap: the client left")
        except Stopped:
            return 0


def _serve_connection(connection: socket.socket, stop: StopSignal) -> None:
    reading, writing = connection.makefile("rb"), connection.makefile("wb")
    writer = MessageWriter(writing)
    try:
        DapServer(writer).serve(reading, stop)
    finally:
        writer.close()
        with contextlib.suppress(OSError):  # a client gone leaves the last bytes unsent
            writing.close()
        reading.close()
