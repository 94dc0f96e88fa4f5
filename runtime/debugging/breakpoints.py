"""Breakpoints and logpoints as the runtime holds them: a client's `BreakpointSpec` checked
and resolved against the loaded code (the statement it stands at, its condition and logged
expressions parsed, its FB instance found)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from runtime.contract.protocol import ArmedBreakpoint, BreakpointSpec
from runtime.contract.refusal import Refusal
from runtime.debugging.condition import Node, parse
from runtime.debugging.statements import StatementMap

LOG_BURST = 20  # logpoint records one hit may make at once ...
LOG_PER_SECOND = 20  # ... and on average: a logpoint in a hot loop costs a counter


@dataclass
class Breakpoint:
    id: int
    file: str
    spec: BreakpointSpec
    user: str | None  # who set it: hits are events in their name
    line: int = 0
    code_files: frozenset[str] = frozenset()
    condition: Node | None = None
    logged: tuple[tuple[str, Node], ...] = ()
    instance: Any = None  # the FB instance it is for (spec.instance), resolved
    message: str | None = None  # why it is not armed
    hits: int = 0
    tokens: float = LOG_BURST
    refilled_ns: int = 0
    unlogged: int = 0  # logpoint hits over the rate since the last record

    @property
    def armed(self) -> bool:
        return self.message is None and self.line > 0

    @property
    def logpoint(self) -> bool:
        return self.spec.log is not None

    def info(self) -> ArmedBreakpoint:
        return ArmedBreakpoint(
            id=self.id,
            file=self.file,
            requested=self.spec.line,
            line=self.line,
            verified=self.armed,
            message=self.message,
            spec=self.spec,
            hits=self.hits,
        )

    def may_log(self, now_ns: int) -> bool:
        """A token bucket: at most LOG_BURST at once, LOG_PER_SECOND on average."""
        elapsed = max(0, now_ns - self.refilled_ns)
        self.tokens = min(LOG_BURST, self.tokens + elapsed * LOG_PER_SECOND / 1e9)
        self.refilled_ns = now_ns
        if self.tokens >= 1:
            self.tokens -= 1
            return True
        self.unlogged += 1
        return False


@dataclass
class Resolution:
    """What resolving a breakpoint needs of the resource."""

    statements: StatementMap
    programs: set[str]  # upper-case names
    find_instance: Any  # (path) -> object or Refusal
    unsupported: set[str] = field(default_factory=set)


def resolve(point: Breakpoint, where: Resolution) -> None:
    """Fill in where `point` stands, or its `message` saying why it is not armed."""
    spec = point.spec
    point.message, point.line, point.code_files = None, 0, frozenset()
    try:
        if spec.program is not None and spec.program.upper() not in where.programs:
            raise Refusal("unknown_program", f"no program '{spec.program}'")
        point.condition = parse(spec.condition) if spec.condition else None
        point.logged = tuple((text, parse(text)) for text in spec.log or ())
        point.instance = where.find_instance(spec.instance) if spec.instance else None
    except Refusal as refused:
        point.message = refused.message
        return
    line = where.statements.statement_at(point.file, spec.line)
    if line == 0:
        known = point.file in where.statements.files()
        point.message = (
            f"no statement at or after line {spec.line} of {point.file}"
            if known
            else f"{point.file} has no code in the running configuration"
        )
        return
    point.line = line
    point.code_files = where.statements.code_files(point.file, line)
