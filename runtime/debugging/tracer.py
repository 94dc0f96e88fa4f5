"""The line tracer of one program's debug run: it sees each ST statement of generated code
begin (the first generated line of a different ST line in the same frame) and asks the
debugger whether to stop there; to stop it switches from the program's greenlet back to
whoever resumed it (the CPU cycle, or a step command), which resumes it later.

Tracing is on only inside the POUs with an armed point (their entry points turn it on:
`traced_entry`), and for a whole program cycle once it has stopped or while it steps; a
frame gets a line tracer only when a point is armed in its unit or a step is under way."""

from __future__ import annotations

import functools
import sys
from collections.abc import Callable
from dataclasses import dataclass
from types import FrameType
from typing import Any, Protocol

import greenlet

from runtime.slicing import ProgramRun

BREAK = object()  # what a stopped debug run hands to the greenlet that resumed it


class StatementHandler(Protocol):
    """What the tracer asks at each statement (the debugger, for one program)."""

    def traced(self, filename: str) -> bool:
        """Whether frames of this code file are to be traced now."""
        ...

    def statement(self, frame: FrameType, filename: str, line: int) -> bool:
        """A statement at ST `line` begins in `frame`: True to stop before it."""
        ...

    def stepping(self) -> bool:
        """Whether this program steps: all its code is to be traced."""
        ...


class LineTracer:
    """The local trace function of one frame; it remembers the ST line it last saw."""

    __slots__ = ("_filename", "_handler", "_lines", "last")

    def __init__(
        self, handler: StatementHandler, filename: str, lines: tuple[int, ...], last: int = 0
    ) -> None:
        self._handler, self._filename, self._lines, self.last = handler, filename, lines, last

    def __call__(self, frame: FrameType, event: str, arg: Any) -> LineTracer:
        if event == "line":
            index = frame.f_lineno - 1
            line = self._lines[index] if 0 <= index < len(self._lines) else 0
            if line and line != self.last:
                self.last = line
                if self._handler.statement(frame, self._filename, line):
                    greenlet.getcurrent().parent.switch(BREAK)
        return self


class ProgramTracer:
    """The global trace function while one program's debug run runs."""

    def __init__(self, handler: StatementHandler, lines: dict[str, tuple[int, ...]]) -> None:
        self._handler = handler
        self._lines = lines  # the ST line of each generated line, by code file name

    def __call__(self, frame: FrameType, event: str, arg: Any) -> LineTracer | None:
        filename = frame.f_code.co_filename
        lines = self._lines.get(filename)
        if lines is None or not self._handler.traced(filename):
            return None
        return LineTracer(self._handler, filename, lines)

    def stepping(self) -> bool:
        return self._handler.stepping()

    def trace_stack(self, frame: FrameType) -> None:
        """Trace every frame of generated code on the stack from `frame` outwards (frames
        entered while nothing was armed in their code have no local tracer; a step out of
        them needs one). Each starts from the ST line it stands at, so that it stops at its
        next statement, not at the rest of the one in progress."""
        current: FrameType | None = frame
        while current is not None:
            filename = current.f_code.co_filename
            lines = self._lines.get(filename)
            if lines is not None and not isinstance(current.f_trace, LineTracer):
                index = current.f_lineno - 1
                line = lines[index] if 0 <= index < len(lines) else 0
                current.f_trace = LineTracer(self._handler, filename, lines, line)
            current = current.f_back


@dataclass
class TraceState:
    """Which program's debug run runs now (its tracer), and whether all of it is traced:
    once it has stopped or while it steps. Otherwise only the POUs with an armed point
    trace themselves (`traced_entry`)."""

    running: ProgramTracer | None = None
    throughout: bool = False


class DebugRun(ProgramRun):
    """A program cycle that may stop (`resume` returns False) at a breakpoint or a step's
    end, as a time slice does when it is used up."""

    def __init__(
        self, body: Callable[[], object], tracer: ProgramTracer, state: TraceState
    ) -> None:
        super().__init__(body)
        self.tracer, self._state = tracer, state
        self.stopped = False  # it has stopped in this program cycle: traced to its end

    def resume(self) -> bool:
        state, previous = self._state, sys.gettrace()
        state.running = self.tracer
        state.throughout = self.stopped or self.tracer.stepping()
        if state.throughout:
            sys.settrace(self.tracer)
        try:
            done = super().resume()
            self.stopped = self.stopped or not done
            return done
        finally:
            sys.settrace(previous)
            state.running, state.throughout = None, False

    def abandon(self) -> None:
        """Dropped while it stands (a stop): its frames unwind under no tracer of theirs,
        and the thread's tracer is left as it was."""
        previous = sys.gettrace()
        try:
            super().abandon()
        finally:
            sys.settrace(previous)


def traced_entry(code: Callable[..., Any], state: TraceState) -> Callable[..., Any]:
    """`code` (a block's body or method, a FUNCTION) tracing itself and what it calls while
    a debug run runs: a breakpoint in a POU costs the programs only inside that POU."""

    @functools.wraps(code)
    def entry(*args: Any, **kwargs: Any) -> Any:
        tracer = state.running
        if tracer is None or sys.gettrace() is not None:
            return code(*args, **kwargs)
        sys.settrace(tracer)
        try:
            return code(*args, **kwargs)
        finally:  # a stop inside: the caller's statements are traced from here on (not
            # when the run was dropped meanwhile: nothing of it may stay traced)
            sys.settrace(tracer if state.throughout and state.running is tracer else None)

    return entry
