"""`padt debug`: breakpoints, logpoints, stepping, the call stack and the variables of a
program in BKPT on a running resource (docs/debugging.md), each verb one call of the
debug session service (backend/engineering/debug_session.py).

Files are named as the artifact names them (relative to the project folder, with `/`);
a path given here is mapped to that name when it lies in the project (`--project`, or the
current folder when it holds padt.toml), else taken as that name as it is."""

from __future__ import annotations

import argparse
import json
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from backend.engineering.debug_session import DebugSession, source_name
from padt.online import Failed, resource_client, run, table
from runtime.contract import protocol as p
from runtime.contract.refusal import Refusal
from runtime.contract.values import format_value
from runtime.contract.wire import encode

BAD_OPTION = 2  # exit code of a location that cannot be read (docs/cli.md)


# ---- reading what the user typed


def location(text: str) -> tuple[str, int]:
    """`FILE:LINE` as given: the file's text and the line."""
    file, sep, line = text.rpartition(":")
    if not sep or not file or not line.isdigit() or int(line) < 1:
        raise Failed(f"'{text}' is not FILE:LINE (a line from 1 on)", BAD_OPTION)
    return file, int(line)


def _project(args: argparse.Namespace) -> Path | None:
    if args.project is not None:
        if not (args.project / "padt.toml").is_file():
            raise Failed(f"{args.project} is no project folder (no padt.toml)", BAD_OPTION)
        return Path(args.project)
    here = Path.cwd()
    return here if (here / "padt.toml").is_file() else None


def source_file(args: argparse.Namespace, text: str) -> str:
    """The artifact's name of the file the user named: a path relative to the current
    folder or to the project, else the artifact's name itself."""
    project = _project(args)
    given = Path(text)
    if project is not None:
        for path in (given, project / given):
            if path.is_file():
                try:
                    return source_name(project, path)
                except ValueError:
                    raise Failed(f"{text} is not in the project {project}", BAD_OPTION) from None
    return given.as_posix().removeprefix("./")


# ---- what the user reads


def _json(shown: dict[str, Any]) -> None:
    print(json.dumps(shown, indent=2))


def stopped_line(pause: p.DebugPause, frames: list[p.DebugFrame]) -> str:
    """`Main stopped at main.st:17 in Counter (instance Main.b), breakpoint 1`."""
    if pause.line == 0:
        return f"{pause.program} stopped at the end of its program cycle"
    name, instance = pause.pou, None
    if frames:
        name = frames[0].name
        if frames[0].kind != "program":
            instance = frames[0].instance
    shown = f" (instance {instance})" if instance else ""
    why = pause.reason if pause.breakpoint is None else f"{pause.reason} {pause.breakpoint}"
    return f"{pause.program} stopped at {pause.file}:{pause.line} in {name}{shown}, {why}"


def _where(point: p.ArmedBreakpoint) -> str:
    line = point.line or point.requested
    moved = f" (asked {point.requested})" if point.line and point.line != point.requested else ""
    return f"{point.file}:{line}{moved}"


def _for(spec: p.BreakpointSpec) -> str:
    return " ".join(x for x in (spec.program, spec.instance) if x) or "all"


def _state(point: p.ArmedBreakpoint) -> str:
    return "armed" if point.verified else f"not armed: {point.message}"


def breakpoint_line(point: p.ArmedBreakpoint) -> str:
    spec = point.spec
    kind = "logpoint" if spec.log is not None else "breakpoint"
    text = f"{kind} {point.id} at {_where(point)}"
    if spec.program or spec.instance:
        text += f" for {_for(spec)}"
    if spec.condition:
        text += f" if {spec.condition}"
    if spec.hit_count:
        text += f" from hit {spec.hit_count}"
    if spec.log is not None:
        text += f" logs {', '.join(spec.log)}"
    return text + ("" if point.verified else f": not armed, {point.message}")


def state_lines(state: p.DebugState) -> list[str]:
    rows = [
        [str(x.id), _where(x), _for(x.spec), x.spec.condition or "", str(x.spec.hit_count or ""),
         str(x.hits), ", ".join(x.spec.log or ()), _state(x)]
        for x in state.breakpoints
    ]  # fmt: skip
    header = ["id", "at", "for", "condition", "hit count", "hits", "logs", "state"]
    lines = table(header, rows) if rows else ["no breakpoints"]
    if state.paused is not None:
        lines.append(stopped_line(state.paused, []))
    lines.append(
        f"a silent client: the program continues after {state.timeout_s} s "
        f"(silent for {state.silent_s:.0f} s)"
    )
    return lines


def frame_lines(frames: list[p.DebugFrame]) -> list[str]:
    rows = [
        [str(f.index), f.name, f.kind, f.instance or "", f"{f.file}:{f.line}" if f.line else "-"]
        for f in frames
    ]
    return table(["#", "frame", "kind", "instance", "at"], rows)


def _value(variable: p.DebugVariable) -> str:
    if variable.children:
        return "[...]" if variable.type.upper().startswith("ARRAY") else "{...}"
    return format_value(variable.value, variable.type)


def variable_lines(variables: list[p.DebugVariable]) -> list[str]:
    rows = [[v.name, v.type, _value(v), v.path or "(local)"] for v in variables]
    return table(["name", "type", "value", "path"], rows) if rows else ["no variables"]


# ---- the verbs


@contextmanager
def _session(args: argparse.Namespace) -> Iterator[DebugSession]:
    with resource_client(args) as client:
        yield DebugSession(client)


def _verb(name: str, args: argparse.Namespace, act: Callable[[DebugSession], int]) -> int:
    def body() -> int:
        with _session(args) as session:
            return act(session)

    return run(f"debug {name}", args, body)


def _still_here(session: DebugSession) -> p.DebugState:
    """The state, read as a keep-alive where the user's level allows it: a person reading
    the stack and the variables at a terminal is still debugging (the resource's timeout
    for a silent client counts from the last debug command that needs read-write)."""
    try:
        return session.state(keep=True)
    except Refusal as refused:
        if refused.code != "forbidden":
            raise
        return session.state()


def _stood(session: DebugSession, state: p.DebugState, as_json: bool) -> int:
    """After a command that lets a program run: where it stands now, if it does."""
    if as_json:
        _json(encode(state))
        return 0
    pause = state.paused
    if pause is None:
        print("no program in BKPT")
    else:
        frames = session.stack(pause.program) if pause.line else []
        print(stopped_line(pause, frames))
    return 0


def set_(args: argparse.Namespace) -> int:
    """Adds a breakpoint to its file's (one at the same line for the same program and
    instance is replaced): the resource takes a file's breakpoints whole."""

    def act(session: DebugSession) -> int:
        text, line = location(args.location)
        file = source_file(args, text)
        spec = p.BreakpointSpec(
            line, args.program, args.instance, args.condition, args.hit_count, args.log
        )
        kept = [
            x.spec
            for x in session.state().breakpoints
            if x.file == file
            and (x.spec.line, x.spec.program, x.spec.instance)
            != (line, spec.program, spec.instance)
        ]
        state = session.set_breakpoints(file, [*kept, spec])
        ours = [x for x in state.breakpoints if x.file == file][-1]
        if args.json:
            _json(encode(state))
        else:
            print(breakpoint_line(ours))
        if not ours.verified:
            raise Failed(f"not armed: {ours.message} (padt debug clear {file}:{line} removes it)")
        return 0

    return _verb("set", args, act)


def list_(args: argparse.Namespace) -> int:
    def act(session: DebugSession) -> int:
        state = _still_here(session)
        if args.json:
            _json(encode(state))
        else:
            print("\n".join(state_lines(state)))
        return 0

    return _verb("list", args, act)


def clear(args: argparse.Namespace) -> int:
    """Every breakpoint, a file's, or those at one line of a file."""

    def act(session: DebugSession) -> int:
        if args.location is None:
            state = session.clear_all()
            told = "every breakpoint cleared"
        else:
            text, _, line = args.location.rpartition(":")
            if text and line.isdigit():
                file, at = source_file(args, text), int(line)
                points = [x for x in session.state().breakpoints if x.file == file]
                kept = [x.spec for x in points if at not in (x.spec.line, x.line)]
                if len(kept) == len(points):
                    raise Failed(f"no breakpoint at {file}:{at}")
                told = f"breakpoints at {file}:{at} cleared"
            else:
                file, kept = source_file(args, args.location), []
                told = f"breakpoints of {file} cleared"
            state = session.set_breakpoints(file, kept)
        if args.json:
            _json(encode(state))
        else:
            print(told)
        return 0

    return _verb("clear", args, act)


def continue_(args: argparse.Namespace) -> int:
    def act(session: DebugSession) -> int:
        state = session.continue_(args.program)
        if args.json:
            _json(encode(state))
        else:
            print(f"{args.program} continues")
        return 0

    return _verb("continue", args, act)


def step(args: argparse.Namespace) -> int:
    def act(session: DebugSession) -> int:
        return _stood(session, session.step(args.program, args.kind), args.json)

    return _verb("step", args, act)


def run_to(args: argparse.Namespace) -> int:
    def act(session: DebugSession) -> int:
        text, line = location(args.location)
        file = source_file(args, text)
        state = session.run_to(args.program, file, line)
        if args.json:
            _json(encode(state))
        elif state.paused is None:
            print(f"{args.program} runs to {file}:{line} (padt debug wait: until it is there)")
        else:
            _stood(session, state, False)
        return 0

    return _verb("run-to", args, act)


def stack(args: argparse.Namespace) -> int:
    def act(session: DebugSession) -> int:
        _still_here(session)
        frames = session.stack(args.program)
        if args.json:
            _json({"frames": encode(frames)})
        else:
            print("\n".join(frame_lines(frames)))
        return 0

    return _verb("stack", args, act)


def vars_(args: argparse.Namespace) -> int:
    def act(session: DebugSession) -> int:
        _still_here(session)
        variables = session.variables(args.program, args.frame, args.path)
        if args.json:
            _json({"variables": encode(variables)})
        else:
            print("\n".join(variable_lines(variables)))
        return 0

    return _verb("vars", args, act)


def wait(args: argparse.Namespace) -> int:
    """Until a program stands in BKPT (at once if one does); the session is kept alive
    meanwhile (read-write), so the resource's silent-client timeout does not run out."""

    def act(session: DebugSession) -> int:
        try:
            session.start()
            pause = _next_pause(session, args.timeout)
            if pause is None:
                raise Failed(f"no program entered BKPT within {args.timeout} s")
            frames = session.stack(pause.program) if pause.line else []
        finally:
            session.close()
        if args.json:
            _json({"paused": encode(pause), "frames": encode(frames)})
        else:
            print(stopped_line(pause, frames))
        return 0

    return _verb("wait", args, act)


def _next_pause(session: DebugSession, timeout_s: float | None) -> p.DebugPause | None:
    """The stop told by the status, or asked for each second: a stop between the first
    question and the status that tells it is not missed."""
    deadline = None if timeout_s is None else time.monotonic() + timeout_s
    while True:
        pause = session.state().paused
        if pause is not None:
            return pause
        left = 1.0 if deadline is None else min(1.0, deadline - time.monotonic())
        if left <= 0:
            return None
        pause = session.wait_for_stop(left)
        if pause is not None:
            return pause


def timeout(args: argparse.Namespace) -> int:
    def act(session: DebugSession) -> int:
        state = session.set_timeout(args.seconds)
        if args.json:
            _json(encode(state))
        else:
            print(
                f"a program in BKPT continues by itself after {state.timeout_s} s without "
                "a debug command"
            )
        return 0

    return _verb("timeout", args, act)
