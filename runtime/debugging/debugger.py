"""The debugger of one resource: its breakpoints and logpoints, the program that stands in
BKPT and where, the step under way, and how long the debugging client has been silent.
Commands call it between two cycles; the tracer calls it at each traced statement."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from types import FrameType
from typing import Any, Protocol

from runtime.clock import Clock
from runtime.code.user_program import UserProgram
from runtime.contract.artifact import ResourceConfig
from runtime.contract.protocol import (
    BreakpointSpec,
    DebugFrame,
    DebugPause,
    DebugState,
    DebugVariable,
    ProgramState,
)
from runtime.contract.recording import LoggedHit
from runtime.contract.refusal import Refusal
from runtime.debugging import frames as stack
from runtime.debugging.breakpoints import Breakpoint, Resolution, resolve
from runtime.debugging.condition import evaluate, literal_of, locate
from runtime.debugging.entry_points import TracedEntries
from runtime.debugging.scope import FrameScope, Typed, VariableTable
from runtime.debugging.statements import StatementMap
from runtime.debugging.tracer import DebugRun, ProgramTracer, TraceState
from runtime.event_recorder import EventRecorder
from runtime.forcing import Forcing
from runtime.image_switch import leave_image, must_leave
from runtime.process_image import ProcessImage
from runtime.scheduler import Scheduler
from runtime.variables import Variables


class Resource(Protocol):
    """What the debugger needs of its resource (runtime/resource.py)."""

    clock: Clock
    recorder: EventRecorder
    variables: Variables
    scheduler: Scheduler
    forcing: Forcing
    io: ProcessImage
    params: ResourceConfig

    @property
    def programs(self) -> list[UserProgram]: ...

    @property
    def cycle_count(self) -> int: ...

    @property
    def recordings(self) -> Recordings | None: ...

    @property
    def cycle_ns(self) -> int: ...


class Recordings(Protocol):
    """Where logpoint hits go besides the event log (runtime/recorder.py)."""

    @property
    def active(self) -> bool: ...

    def logged(self, hit: LoggedHit) -> None: ...


DEFAULT_TIMEOUT_S = 120


@dataclass
class Pause:
    program: UserProgram
    frame: FrameType | None  # None: at the end of its program cycle
    file: str
    pou: str
    line: int
    reason: str
    breakpoint: int | None

    def info(self) -> DebugPause:
        return DebugPause(
            self.program.name, self.pou, self.file, self.line, self.reason, self.breakpoint
        )

    def where(self) -> str:
        if self.frame is None:
            return "end of the program cycle"
        return f"{self.file}:{self.line} (POU {self.pou})"


@dataclass(frozen=True)
class Stepping:
    program: UserProgram  # the program that steps (others run through)
    kind: str  # "over", "into", "out", "cycle", "to"
    depth: int  # frames of generated code on the stack where the step began
    target: tuple[frozenset[str], int] | None = None  # "to": the code files and ST line


class _Code:
    """What the debugger reads of the loaded configuration (rebuilt after a load or a
    reload)."""

    def __init__(self, resource: Resource) -> None:
        code = resource.variables.code
        assert code is not None
        self.statements = StatementMap(code.units)
        classes = code.classes()
        self.table = VariableTable(
            {
                classes[unit.class_name]: unit.variables
                for unit in code.units.values()
                if unit.class_name in classes
            }
        )
        self.lines = {name: unit.st_lines for name, unit in code.units.items()}


class _Roots:
    """Names at the top of the resource: its programs, then its globals."""

    def __init__(self, resource: Resource, table: VariableTable) -> None:
        self.table, self._resource = table, resource

    def lookup(self, name: str) -> Typed:
        for program in self._resource.programs:
            if program.name.upper() == name.upper():
                return Typed(program.instance, program.config.pou, program.name)
        view = self._resource.variables.code.globals if self._resource.variables.code else None
        if view is not None:
            return self.table.member(Typed(view, "", ""), name)
        raise Refusal("unknown_variable", f"no program or global '{name}'")


class Debugger:
    # slots: the CPU cycle in C reads them at their offsets (padt_cycle.c)
    __slots__ = (
        "_at",
        "_code",
        "_entries",
        "_files",
        "_next_id",
        "_pause",
        "_resource",
        "_trace",
        "active",
        "heard_ns",
        "points",
        "stepping",
        "timeout_s",
    )

    def __init__(self) -> None:
        self.points: dict[str, list[Breakpoint]] = {}  # by ST file
        self._pause: Pause | None = None
        # something to watch each cycle: armed points or a program in BKPT (an attribute
        # the CPU cycle reads, kept by `pause`'s setter and `rearm`)
        self.active = False
        self.stepping: Stepping | None = None
        self.timeout_s = DEFAULT_TIMEOUT_S
        self.heard_ns = 0  # when a debug command last came
        self._next_id = 1
        self._code: _Code | None = None
        self._at: dict[tuple[str, int], list[Breakpoint]] = {}  # by (code file, ST line)
        self._files: set[str] = set()  # code files with an armed breakpoint
        self._resource: Resource | None = None
        self._trace = TraceState()  # shared with the debug runs and the traced entries
        self._entries = TracedEntries()

    # ---- state

    @property
    def pause(self) -> Pause | None:
        """The program standing in BKPT, and where."""
        return self._pause

    @pause.setter
    def pause(self, pause: Pause | None) -> None:
        self._pause = pause
        self.active = bool(self._at) or pause is not None

    def state(self, now_ns: int) -> DebugState:
        points = [p.info() for file in sorted(self.points) for p in self.points[file]]
        paused = self.pause.info() if self.pause is not None else None
        silent = (now_ns - self.heard_ns) / 1e9 if self.active else 0.0
        return DebugState(points, paused, self.timeout_s, round(max(0.0, silent), 3))

    def where(self, program: UserProgram) -> str | None:
        pause = self.pause
        return pause.where() if pause is not None and pause.program is program else None

    def heard(self, resource: Resource) -> None:
        self.heard_ns = resource.clock.now_ns()

    # ---- commands

    def set_file(self, resource: Resource, file: str, specs: list[BreakpointSpec]) -> None:
        if specs and resource.params.safety_operation:
            raise Refusal("safety_operation", "no breakpoints in safety operation")
        if specs and resource.variables.code is None:
            raise Refusal("state", "the resource has no configuration to debug")
        user = resource.recorder.acting_user
        kept = list(self.points.get(file, []))
        points = []
        for spec in specs:
            same = next((point for point in kept if point.spec == spec), None)
            if same is not None:  # sent again unchanged: its id and hits stay
                kept.remove(same)
                points.append(same)
                continue
            points.append(Breakpoint(self._next_id, file, spec, user))
            self._next_id += 1
        if points:
            self.points[file] = points
        else:
            self.points.pop(file, None)
        self.rearm(resource)
        lines = ", ".join(f"{p.line}" + (" (log)" if p.logpoint else "") for p in points if p.armed)
        armed = f"lines {lines}" if lines else "none"
        resource.recorder.record("debug", f"breakpoints of {file}: {armed}", file=file)

    def clear(self, resource: Resource, why: str = "breakpoints cleared") -> None:
        had = self.active
        self.points.clear()
        self.rearm(resource)
        if self.pause is not None:
            self._continue(resource, self.pause)
        if had:
            resource.recorder.record("debug", why)

    def continue_(self, resource: Resource, name: str) -> None:
        self._continue(resource, self._paused(name))

    def step(self, resource: Resource, name: str, kind: str) -> None:
        pause = self._paused(name)
        program = pause.program
        if pause.frame is None:  # at the end of a cycle: to the first statement of the next
            self.stepping = Stepping(program, "cycle" if kind == "cycle" else "into", 0)
        else:
            depth = len(stack.code_frames(pause.frame, self._loaded().statements))
            self.stepping = Stepping(program, kind, depth)
        self.pause = None
        program.state = ProgramState.RUN
        program.last_start_ns = None  # its time advances one cycle, as in single step
        ran = resource.scheduler.guarded(
            lambda: resource.scheduler.run_to_end(program, resource.cycle_ns)
        )
        self.stepping = None
        if not ran:  # the watchdog or an Emergency Stop: the resource stopped
            return
        if program.state is ProgramState.RUN:  # the program cycle ended
            program.state = ProgramState.BKPT
            self.pause = Pause(program, None, "", program.config.pou, 0, "cycle end", None)
        resource.variables.publish([program])
        resource.forcing.apply()
        resource.io.write_outputs(safe=False)
        where = self.pause.where() if self.pause is not None else program.state
        resource.recorder.record(
            "debug", f"program {program.name} stepped ({kind}): now at {where}", program=name
        )

    def run_to(self, resource: Resource, name: str, file: str, line: int) -> None:
        pause = self._paused(name)
        statements = self._loaded().statements
        at = statements.statement_at(file, line)
        if at == 0:
            raise Refusal("bad_value", f"no statement at or after {file}:{line}")
        self.stepping = Stepping(pause.program, "to", 0, (statements.code_files(file, at), at))
        self._continue(resource, pause, f"runs to {file}:{at}")

    def set_timeout(self, resource: Resource, seconds: int) -> None:
        self.timeout_s = seconds
        resource.recorder.record(
            "debug", f"a silent debugging client: the program continues after {seconds} s"
        )

    def frames(self, name: str) -> list[DebugFrame]:
        pause = self._paused(name)
        code = self._loaded()
        found = stack.code_frames(pause.frame, code.statements)
        return stack.describe(found, code.statements, self._instance_paths(code))

    def variables(self, name: str, frame: int, path: str) -> list[DebugVariable]:
        pause = self._paused(name)
        code = self._loaded()
        found = stack.code_frames(pause.frame, code.statements)
        if pause.frame is None:  # at the end of the cycle: the program's own variables
            owner = Typed(pause.program.instance, pause.program.config.pou, pause.program.name)
            if path:
                owner = locate(path, _Roots(self._resource_of(), code.table))
            return stack.variables_below(owner, code.table)
        if not 0 <= frame < len(found):
            raise Refusal("bad_value", f"frame {frame} is not on the stack ({len(found)} frames)")
        paths = self._instance_paths(code)
        scope = self._scope(found[frame].frame, pause.program, code, paths)
        return stack.variables(scope, path)

    # ---- the resource's life

    def rearm(self, resource: Resource) -> None:
        """Resolve every point against the loaded code and trace the programs they may
        stop (after a change of points, a load or a reload)."""
        self._resource = resource
        if resource.variables.code is None:
            self._code = None
            self._at, self._files = {}, set()
            self.active = self._pause is not None
            return
        code = self._code = _Code(resource)
        where = Resolution(
            code.statements,
            {p.name.upper() for p in resource.programs},
            lambda path: locate(path, _Roots(resource, code.table)).value,
        )
        at: dict[tuple[str, int], list[Breakpoint]] = {}
        for points in self.points.values():
            for point in points:
                resolve(point, where)
                if point.armed:
                    for filename in point.code_files:
                        at.setdefault((filename, point.line), []).append(point)
        self._at, self._files = at, {filename for filename, _ in at}
        self.active = bool(self._at) or self._pause is not None
        armed = [p for file in self.points.values() for p in file if p.armed]
        for program in resource.programs:
            wanted = any(
                p.spec.program is None or p.spec.program.upper() == program.name.upper()
                for p in armed
            )
            paused = self.pause is not None and self.pause.program is program
            program.debug_run = self._run_for(program, code) if wanted or paused else None
        code_image = resource.variables.code
        self._entries.remove()
        code_image.run_as_python(bool(armed) or self.pause is not None)
        if must_leave(resource.variables):  # debugged on objects (else at the next tier-up)
            leave_image(resource.variables)
        self._entries.install(code_image, self._files, self._trace)
        if self._at and not self.heard_ns:
            self.heard(resource)

    def watch(self, resource: Resource, now_ns: int) -> None:
        """Each cycle while active: a client silent for longer than the timeout has gone;
        its breakpoints go with it and the program continues by itself."""
        if now_ns - self.heard_ns > self.timeout_s * 1_000_000_000:
            self.clear(
                resource,
                f"no debug command for {self.timeout_s} s: breakpoints cleared, "
                "the program continues",
            )

    def forget(self, resource: Resource, why: str = "the resource stopped") -> None:
        """The resource stopped (or loaded another configuration): no program stands at a
        breakpoint any more; the points stay for the next start."""
        if self.pause is not None:
            resource.recorder.record("debug", f"program {self.pause.program.name} left BKPT: {why}")
        self.pause, self.stepping = None, None

    def refuse_reload(self) -> None:
        if self.pause is not None:
            raise Refusal(
                "state",
                f"program {self.pause.program.name} stands at a breakpoint: continue it "
                "before an online change",
            )

    # ---- the tracer's questions (on the cycle thread, inside a program's debug run)

    def traced(self, filename: str) -> bool:
        return self.stepping is not None or filename in self._files

    def stepping_program(self, program: UserProgram) -> bool:
        return self.stepping is not None and self.stepping.program is program

    def statement(self, program: UserProgram, frame: FrameType, filename: str, line: int) -> bool:
        if self.pause is not None:  # another program stands in BKPT: one at a time
            return False
        stepping = self.stepping if self.stepping_program(program) else None
        stop: tuple[str, int | None] | None = None
        if stepping is not None and stepping.kind != "cycle":
            stop = self._step_ends(stepping, frame, filename, line)
        if stepping is None or stepping.kind != "cycle":
            for point in self._at.get((filename, line), ()):
                if self._hit(point, program, frame):
                    stop = stop or ("breakpoint", point.id)
        if stop is None:
            return False
        self._stop(program, frame, filename, line, *stop)
        return True

    # ---- inside

    def _step_ends(
        self, stepping: Stepping, frame: FrameType, filename: str, line: int
    ) -> tuple[str, int | None] | None:
        if stepping.kind == "to":
            assert stepping.target is not None
            files, at = stepping.target
            return ("run to", None) if filename in files and line == at else None
        if stepping.kind == "into":
            return ("step", None)
        depth = len(stack.code_frames(frame, self._loaded().statements))
        if depth <= stepping.depth if stepping.kind == "over" else depth < stepping.depth:
            return ("step", None)
        return None

    def _hit(self, point: Breakpoint, program: UserProgram, frame: FrameType) -> bool:
        """Whether `point` stops here; a logpoint records and never stops."""
        spec = point.spec
        if spec.program is not None and spec.program.upper() != program.name.upper():
            return False
        if point.instance is not None and frame.f_locals.get("s") is not point.instance:
            return False
        if point.condition is not None:
            try:
                holds = evaluate(point.condition, self._scope(frame, program, self._loaded()))
            except Refusal as refused:
                point.message = f"condition: {refused.message}"
                return True  # stop and show why, as a debugger does
            if holds is not True:
                return False
        point.hits += 1
        if point.logpoint:
            self._log(self._resource_of(), point, frame, program)
            return False
        return spec.hit_count is None or point.hits >= spec.hit_count

    def _log(
        self, resource: Resource, point: Breakpoint, frame: FrameType, program: UserProgram
    ) -> None:
        now_ns = resource.clock.now_ns()
        if not point.may_log(now_ns):  # over the rate: a counter, nothing evaluated
            return
        scope = self._scope(frame, program, self._loaded())
        shown: list[str] = []
        values: dict[str, str] = {}
        errors: dict[str, str] = {}
        for text, node in point.logged:
            try:
                values[text] = literal_of(node, scope)
                shown.append(f"{text} = {values[text]}")
            except Refusal as refused:
                errors[text] = refused.message
                shown.append(f"{text}: {refused.message}")
        unlogged, point.unlogged = point.unlogged, 0
        more = f" ({unlogged} more hits not logged)" if unlogged else ""
        resource.recorder.record(
            "log",
            f"{point.file}:{point.line} in {program.name}: {', '.join(shown)}{more}",
            user=point.user,
            long_term=False,
            program=program.name,
            file=point.file,
            line=point.line,
        )
        recordings = resource.recordings
        if recordings is not None and recordings.active:  # and into the recordings running
            hit = LoggedHit(
                point.id,
                program.name,
                point.file,
                point.line,
                values,
                errors,
                unlogged,
                cycle=resource.cycle_count + 1,  # the cycle under way: counted when it ends
                clock_ns=now_ns,
            )
            recordings.logged(hit)

    def _stop(
        self,
        program: UserProgram,
        frame: FrameType,
        filename: str,
        line: int,
        reason: str,
        point: int | None,
    ) -> None:
        code = self._loaded()
        unit = code.statements.units[filename]
        self.pause = Pause(program, frame, unit.file, unit.name, line, reason, point)
        self.stepping = None
        program.state = ProgramState.BKPT
        program.cpu_cycles = 0  # its program watchdog is held while it stands
        self._trace.throughout = True  # the rest of its cycle is traced, callers too
        # what it wrote so far reaches the others and the outputs; the rest waits for it
        self._resource_of().variables.publish([program])
        run = program.run
        if isinstance(run, DebugRun):
            run.tracer.trace_stack(frame)
        if reason == "breakpoint":
            resource = self._resource_of()
            owner = next((p.user for f in self.points.values() for p in f if p.id == point), None)
            resource.recorder.record(
                "debug",
                f"program {program.name} in BKPT at {unit.file}:{line} (POU {unit.name})",
                user=owner,
                program=program.name,
                file=unit.file,
                line=line,
            )

    def _continue(self, resource: Resource, pause: Pause, how: str = "continues") -> None:
        program = pause.program
        self.pause = None
        if program.state is ProgramState.BKPT:
            program.state = ProgramState.RUN
            program.last_start_ns = None  # its time resumes where it stood
        self.rearm(resource)
        resource.recorder.record("debug", f"program {program.name} {how}", program=program.name)

    def _paused(self, name: str) -> Pause:
        pause = self.pause
        if pause is None or pause.program.name.upper() != name.upper():
            raise Refusal("state", f"program {name} is not in BKPT")
        return pause

    def _loaded(self) -> _Code:
        if self._code is None:
            raise Refusal("state", "the resource has no configuration to debug")
        return self._code

    def _resource_of(self) -> Resource:
        assert self._resource is not None
        return self._resource

    def _scope(
        self,
        frame: FrameType,
        program: UserProgram,
        code: _Code,
        paths: dict[int, str] | None = None,
    ) -> FrameScope:
        """The names of a frame; `paths` (of instances) where variables are shown with
        their paths, not needed to evaluate a condition."""
        instance = frame.f_locals.get("s")
        path = paths.get(id(instance)) if paths is not None and instance is not None else None
        return FrameScope(frame, code.table, path, program.view)

    def _instance_paths(self, code: _Code) -> dict[int, str]:
        resource = self._resource_of()
        roots: list[tuple[str, Any]] = [(p.name, p.instance) for p in resource.programs]
        if resource.variables.code is not None and resource.variables.code.globals is not None:
            roots.append(("", resource.variables.code.globals))
        paths = stack.instance_paths(roots, code.table)
        for program in resource.programs:
            paths[id(program.instance)] = program.name
        return paths

    def _run_for(self, program: UserProgram, code: _Code) -> Callable[[Any], DebugRun]:
        tracer = ProgramTracer(_ProgramStatements(self, program), code.lines)
        state = self._trace
        return lambda body: DebugRun(body, tracer, state)


@dataclass(frozen=True)
class _ProgramStatements:
    """The tracer's questions for one program, put to the debugger."""

    debugger: Debugger
    program: UserProgram

    def traced(self, filename: str) -> bool:
        return self.debugger.traced(filename)

    def statement(self, frame: FrameType, filename: str, line: int) -> bool:
        return self.debugger.statement(self.program, frame, filename, line)

    def stepping(self) -> bool:
        return self.debugger.stepping_program(self.program)
