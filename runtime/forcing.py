"""Forcing as the resource does it (spec section 11): force values prepared per variable,
forcing started per level (global, or one program's local level) with an optional time
limit, refused in safety operation and while Force Deactivation is ON, and every change an
event. The force table (`force_table.py`) holds what is forced; this applies it."""

from __future__ import annotations

from typing import Any, Protocol

from runtime.clock import Clock
from runtime.code.intrinsics import SystemView
from runtime.contract.artifact import ResourceConfig
from runtime.contract.protocol import ForceInfo, ForcingState
from runtime.contract.refusal import Refusal
from runtime.contract.values import format_value
from runtime.event_recorder import EventRecorder
from runtime.force_table import GLOBAL, ForceEntry, ForceTable
from runtime.variables import Variables


class ForcingSettings(Protocol):
    """What forcing needs to know of its resource."""

    @property
    def params(self) -> ResourceConfig: ...

    @property
    def system(self) -> SystemView: ...

    def running(self) -> bool: ...


class Forcing:
    # slots: the CPU cycle in C reads them at their offsets (padt_cycle.c)
    __slots__ = (
        "_clock",
        "_recorder",
        "_settings",
        "_variables",
        "deactivated",
        "table",
    )

    def __init__(
        self,
        settings: ForcingSettings,
        variables: Variables,
        recorder: EventRecorder,
        clock: Clock,
    ) -> None:
        self._settings, self._variables = settings, variables
        self._recorder, self._clock = recorder, clock
        self.table = ForceTable()
        self.deactivated = False  # Force Deactivation as last seen (its OFF -> ON ends forcing)

    def reset(self) -> None:
        """A download ends forcing, and its entries lose their meaning."""
        self.table = ForceTable()

    # ---- commands
    def force(self, name: str, value: Any, switch: bool = True) -> None:
        """Prepare a force value and its switch; it acts while forcing runs at its level."""
        bound = self._variables.lookup_to_write(name)
        level = GLOBAL if bound.program is None else bound.program.name
        self._check_allowed(level)
        stored = self._variables.checked(bound, value)
        old = self._variables.read(bound)
        self.table.set(ForceEntry(bound.path.path, level, stored, switch))
        if self.table.is_forced(bound.path.path):
            self._variables.store(bound, stored)
        self._recorder.record(
            "force",
            f"{bound.path.path} forced to {format_value(stored, bound.path.type)} "
            f"(switch {'ON' if switch else 'OFF'})",
            variable=bound.path.path,
            old=old,
            new=stored,
        )

    def unforce(self, name: str) -> None:
        bound = self._variables.lookup(name)
        if self.table.remove(bound.path.path) is None:
            raise Refusal("not_forced", f"'{bound.path.path}' has no force value")
        self._recorder.record("force", f"{bound.path.path} force value removed")

    def start(self, program: str | None = None, timeout_ns: int | None = None) -> None:
        level = GLOBAL if program is None else self._variables.program(program).name
        self._check_allowed(level)
        if not self._settings.running():
            raise Refusal("state", "forcing starts only while the resource runs")
        self.table.start(level, self._clock.now_ns(), timeout_ns)
        self.apply()
        limit = f"{timeout_ns / 1e9:g} s" if timeout_ns is not None else "no time limit"
        self._recorder.record("force", f"{_level_name(level)} started ({limit})")

    def stop(self, program: str | None = None) -> None:
        level = GLOBAL if program is None else self._variables.program(program).name
        if self.table.stop(level):
            self._recorder.record("force", f"{_level_name(level)} stopped")

    def state(self) -> ForcingState:
        now = self._clock.now_ns()
        started = self.table.started_levels()
        return ForcingState(
            started=started,
            remaining_ms={
                level or "global": (r / 1e6 if (r := self.table.remaining_ns(level, now)) else None)
                for level in started
            },
            entries=[
                ForceInfo(
                    e.path, e.level or "global", e.value, e.switch, self.table.is_forced(e.path)
                )
                for e in self.table.entries()
            ],
        )

    # ---- in the cycle
    def apply(self) -> None:
        """Write the values in force (after reading inputs, before writing outputs)."""
        for entry in self.table.active():
            bound = self._variables.find(entry.path)
            if bound is not None:
                self._variables.store(bound, entry.value)

    def expire(self, now_ns: int) -> list[str]:
        """Stop the levels whose time limit ran out; the levels, for their reactions."""
        expired = self.table.expired(now_ns)
        for level in expired:
            self.table.stop(level)
        return expired

    def check_deactivation(self) -> None:
        """Force Deactivation OFF -> ON ends all forcing at once (ON also blocks it)."""
        now_on = bool(self._settings.system.FORCE_DEACTIVATION)
        if now_on and not self.deactivated:
            self.end_all("Force Deactivation ON")
        self.deactivated = now_on

    def end_all(self, why: str) -> None:
        for level in self.table.stop_all():
            self._recorder.record("force", f"{_level_name(level)} ended: {why}", long_term=True)

    def end_program(self, program: str) -> None:
        """A program stop ends its local forcing."""
        if self.table.stop(program):
            self._recorder.record("force", f"local forcing of {program} ended: program stop")

    def keep_after_reload(self, programs_removed: tuple[str, ...]) -> None:
        """Forcing survives a reload where its variable and its program do."""
        for entry in self.table.entries():
            if self._variables.find(entry.path) is None:
                self.table.remove(entry.path)
        for name in programs_removed:
            self.table.stop(name)

    def _check_allowed(self, level: str) -> None:
        params = self._settings.params
        if params.safety_operation:
            raise Refusal("safety_operation", "no forcing in safety operation")
        if self._settings.system.FORCE_DEACTIVATION:
            raise Refusal("force_deactivated", "Force Deactivation is ON")
        if level == GLOBAL:
            if not params.global_forcing_allowed:
                raise Refusal("not_allowed", "Global Forcing Allowed is OFF")
        elif not self._variables.program(level).config.local_forcing_allowed:
            raise Refusal("not_allowed", f"Local Forcing Allowed of {level} is OFF")


def _level_name(level: str) -> str:
    return "global forcing" if level == GLOBAL else f"local forcing of {level}"
