"""Debugging in the editor (docs/debugging.md, "In the browser"): the breakpoints of the
gutter sent to the selected resource, and what its Debug panel shows of a program in
BKPT (where it stands, its call stack, the variables of the chosen frame) with the
panel's steps, all through the debug session service (backend/engineering/debug_session).

The refresher calls `follow` ten times a second; everything that asks the resource runs on
a thread of this browser's own (`LatestWork`), so that neither viser's thread nor the
refresher ever waits for an answer. What the resource says is kept here and sent to the
page as one message when it differs from what the page was sent last."""

from __future__ import annotations

import contextlib
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from backend.engineering.debug_session import DebugSession
from backend.engineering.resource_client import ResourceClient, ResourceUnreachable
from frontend.editor.latest_work import LatestWork
from frontend.editor.messages import BreakpointItem, DebugAction
from frontend.permissions import Allowed
from runtime.contract import protocol as p
from runtime.contract.refusal import Refusal
from runtime.contract.values import format_for_display

LOOK_S = 2.0  # the breakpoints' hits and verdicts read again this often while any is set
MAX_SHOWN = 2000  # variables listed (expanded members included)


@dataclass(frozen=True)
class Target:
    """The resource the editor debugs: the one selected in the navigation, when the project
    of the editor is what it runs (`runs` is the reason when it is not)."""

    resource: str
    client: ResourceClient
    allowed: Allowed  # the debug commands that change something (read-write)
    runs: str  # "" when the editor's project is the resource's running configuration
    status: p.Status | None


@dataclass
class _Seen:
    """What the resource last told, for the page."""

    state: p.DebugState | None = None
    frames: list[p.DebugFrame] = field(default_factory=list)
    frame: int = 0
    variables: dict[str, list[p.DebugVariable]] = field(default_factory=dict)  # "" the frame's
    error: str = ""


class EditorDebugging:
    def __init__(
        self, push: Callable[[dict[str, Any]], None], notice: Callable[[str], None]
    ) -> None:
        """`push(message)` to the page (which opens the file where a program stopped and
        lights its line), `notice(text)` to the user."""
        self._push, self._notice = push, notice
        self._lock = threading.Lock()
        self._work = LatestWork("padt-debug")
        self._sessions: dict[str, DebugSession] = {}
        self._started: set[str] = set()
        self._target: Target | None = None
        self._seen = _Seen()
        self._changed = 0  # counts the changes of `_seen`: the page's message is made anew
        self._made: tuple[tuple[object, ...], dict[str, Any]] | None = None
        self._expanded: set[str] = set()  # frame-relative paths shown open
        self._status_key: tuple[object, ...] = ()
        self._looked = 0.0
        self._shown_pause: tuple[object, ...] | None = None
        self._sent: dict[str, Any] | None = None
        self._actions = 0

    # ---- the refresher's
    def follow(self, target: Target | None) -> None:
        with self._lock:
            before = self._target
            self._target = target
            if target is None or before is None or before.resource != target.resource:
                self._seen, self._expanded, self._shown_pause = _Seen(), set(), None
                self._changed += 1
            key = _status_key(target)
            now = time.monotonic()
            # while breakpoints are set (their hits), and after a refusal (a login since?)
            again = self._seen.error or (
                self._seen.state is not None and bool(self._seen.state.breakpoints)
            )
            due = bool(again) and now - self._looked >= LOOK_S
            if target is not None and not target.runs and (key != self._status_key or due):
                self._status_key, self._looked = key, now
                self._work.submit("look", self._look)
            elif target is None or target.runs:
                self._status_key = key
            message = self._message()
        if message != self._sent:
            self._sent = message
            self._push(message)

    def close(self) -> None:
        self._work.stop()
        for session in self._sessions.values():
            session.close()

    # ---- from the page
    def set_breakpoints(self, file: str, items: tuple[BreakpointItem, ...]) -> None:
        specs = [
            p.BreakpointSpec(i.line, None, None, i.condition, i.hit_count, _log(i)) for i in items
        ]

        def job() -> None:
            session = self._session(changing=True)
            if session is not None:
                self._asking(
                    f"The breakpoints of {file}", lambda: session.set_breakpoints(file, specs)
                )

        self._work.submit(f"breakpoints:{file}", job)

    def act(self, action: DebugAction) -> None:
        if action.action == "frame":
            with self._lock:
                self._seen.frame, self._expanded = action.frame, set()
                self._changed += 1
            self._work.submit("look", self._look)
            return
        if action.action in ("expand", "collapse"):
            with self._lock:
                if action.action == "expand":
                    self._expanded.add(action.path)
                else:
                    self._expanded = {x for x in self._expanded if not _within(x, action.path)}
            self._work.submit("look", self._look)
            return
        if action.action == "timeout":
            self._work.submit("timeout", lambda: self._set_timeout(action.seconds))
            return
        self._actions += 1  # each press its own job: none replaces another
        self._work.submit(f"act:{self._actions}", lambda: self._command(action))

    # ---- on the worker
    def _command(self, action: DebugAction) -> None:
        session = self._session(changing=True)
        if session is None:
            return
        with self._lock:
            state = self._seen.state
        paused = state.paused if state is not None else None
        if paused is None:
            self._notice("No program is in BKPT.")
            return
        program = paused.program
        if action.action == "continue":
            self._asking(f"Continue {program}", lambda: session.continue_(program))
        elif action.action == "run_to":
            where = f"{action.file}:{action.line}"
            self._asking(
                f"Run {program} to {where}",
                lambda: session.run_to(program, action.file, action.line),
            )
        else:
            kind: p.DebugStepKind = action.action  # type: ignore[assignment]  # a step: checked
            self._asking(f"Step {kind} in {program}", lambda: session.step(program, kind))

    def _set_timeout(self, seconds: int) -> None:
        session = self._session(changing=True)
        if session is not None:
            self._asking("The debug timeout", lambda: session.set_timeout(seconds))

    def _session(self, changing: bool) -> DebugSession | None:
        """The session with the resource debugged now; one that changes something is
        started first (its keep-alive). None, with a notice, when it may not."""
        with self._lock:
            target = self._target
        if target is None or target.runs:
            if changing:
                self._notice(target.runs if target is not None else "Select a resource to debug.")
            return None
        if changing and not target.allowed.ok:
            self._notice(f"Debugging: {target.allowed.reason}.")
            return None
        session = self._sessions.get(target.resource)
        if session is None or session.client is not target.client:
            session = self._sessions[target.resource] = DebugSession(target.client)
            self._started.discard(target.resource)
        if changing and target.resource not in self._started:
            self._started.add(target.resource)  # its threads run from here on, answered or not
            with contextlib.suppress(Refusal, ResourceUnreachable):
                session.start()  # refused or unanswered: the command that follows says why
        return session

    def _asking(self, what: str, command: Callable[[], p.DebugState]) -> None:
        """A command to the resource; its reply is the state now, and what a pause then
        shows is read. A refusal or no answer is told to the user."""
        try:
            state = command()
        except Refusal as refused:
            self._notice(f"{what} refused: {refused.message}")
            return
        except ResourceUnreachable as exc:
            self._notice(f"{what}: {exc}")
            return
        with self._lock:
            self._seen.state = state
            self._changed += 1
        self._look()

    def _look(self) -> None:
        """The debug state, and at a pause the stack and the variables of the frame shown."""
        session = self._session(changing=False)
        if session is None:
            return
        try:
            state = session.state()
            seen = _Seen(state, frame=0)
            if state.paused is not None:
                seen.frames = session.stack(state.paused.program)
                with self._lock:
                    same = self._shown_pause == _pause_key(state.paused)
                    frame, expanded = self._seen.frame, sorted(self._expanded)
                if not same:  # a new place: the innermost frame, nothing expanded
                    frame, expanded = 0, []
                    with self._lock:
                        self._expanded = set()
                seen.frame = min(frame, max(0, len(seen.frames) - 1))
                program = state.paused.program
                seen.variables[""] = session.variables(program, seen.frame)
                for path in expanded:
                    try:
                        seen.variables[path] = session.variables(program, seen.frame, path)
                    except Refusal:  # gone since (another frame, another pause)
                        continue
        except Refusal as refused:
            with self._lock:
                self._seen.error, self._changed = f"refused: {refused.message}", self._changed + 1
            return
        except ResourceUnreachable as exc:
            with self._lock:
                self._seen.error, self._changed = f"no answer: {exc}", self._changed + 1
            return
        with self._lock:
            self._seen = seen
            self._changed += 1
            self._shown_pause = _pause_key(state.paused) if state.paused is not None else None

    # ---- to the page
    def _message(self) -> dict[str, Any]:
        """The page's message, made anew only when something in it may have changed (the
        refresher asks ten times a second)."""
        target = self._target
        key: tuple[object, ...] = (self._changed,)
        if target is not None:
            key += (target.resource, target.runs, target.allowed, tuple(_in_bkpt(target.status)))
        if self._made is None or self._made[0] != key:
            self._made = (key, self._make())
        return self._made[1]

    def _make(self) -> dict[str, Any]:
        target, seen = self._target, self._seen
        if target is None:
            return {"k": "debug", "on": False, "why": "Select a resource to debug."}
        state = seen.state
        message: dict[str, Any] = {
            "k": "debug",
            "on": not target.runs,
            "resource": target.resource,
            "why": target.runs,
            "allowed": target.allowed.ok,
            "reason": target.allowed.reason,
            "error": seen.error,
            "breakpoints": [],
            "paused": None,
            "in_bkpt": _in_bkpt(target.status),
        }
        if target.runs or state is None:
            return message
        message["breakpoints"] = [_breakpoint(b) for b in state.breakpoints]
        message["timeout_s"] = state.timeout_s
        if state.paused is not None:
            pause = state.paused
            message["paused"] = {
                "program": pause.program,
                "pou": pause.pou,
                "file": pause.file,
                "line": pause.line,
                "reason": pause.reason,
            }
            message["frames"] = [
                {"index": f.index, "name": f.name, "kind": f.kind, "instance": f.instance,
                 "file": f.file, "line": f.line}
                for f in seen.frames
            ]  # fmt: skip
            message["frame"] = seen.frame
            message["variables"] = _rows(seen.variables, "", 0, [])
        return message


def _rows(
    found: dict[str, list[p.DebugVariable]], parent: str, depth: int, rows: list[dict[str, Any]]
) -> list[dict[str, Any]]:
    """The variables as the panel lists them: each open one followed by its members."""
    for v in found.get(parent, []):
        if len(rows) >= MAX_SHOWN:
            break
        path = _child(parent, v.name)
        is_open = v.children and path in found
        value = "" if v.children else format_for_display(v.value, v.type)
        rows.append({"name": v.name, "type": v.type, "value": value, "path": path,
                     "children": v.children, "open": is_open, "depth": depth,
                     "resource_path": v.path})  # fmt: skip
        if is_open:
            _rows(found, path, depth + 1, rows)
    return rows


def _child(parent: str, name: str) -> str:
    if not parent:
        return name
    return f"{parent}{name}" if name.startswith("[") else f"{parent}.{name}"


def _within(path: str, parent: str) -> bool:
    return path == parent or path.startswith((f"{parent}.", f"{parent}["))


def _breakpoint(b: p.ArmedBreakpoint) -> dict[str, Any]:
    return {"id": b.id, "file": b.file, "requested": b.requested, "line": b.line,
            "verified": b.verified, "message": b.message or "", "hits": b.hits,
            "condition": b.spec.condition, "hit_count": b.spec.hit_count,
            "log": b.spec.log}  # fmt: skip


def _log(item: BreakpointItem) -> list[str] | None:
    return list(item.log) if item.log is not None else None


def _pause_key(pause: p.DebugPause) -> tuple[object, ...]:
    return (pause.program, pause.file, pause.line, pause.reason)


def _in_bkpt(status: p.Status | None) -> list[str]:
    if status is None:
        return []
    return [x.name for x in status.programs if x.state == p.ProgramState.BKPT]


def _status_key(target: Target | None) -> tuple[object, ...]:
    """What, in the resource's status, says the debug state may have changed (or that it
    may be read now: the editor's project is found to be the running one, a login)."""
    if target is None or target.status is None:
        return ()
    programs = tuple((x.name, x.state, x.paused_at) for x in target.status.programs)
    return (target.resource, target.runs, target.allowed, target.status.crc, programs)
