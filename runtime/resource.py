"""A resource: one controller with its loaded configuration, user programs and states.

Only the cycle thread calls its methods (commands reach it through the cycle driver's
queue), so it needs no locks. The CPU cycle (`cycle`) follows the order of the spec:
(1) read inputs, (2) apply forces, (3) run user programs by priority, each in its time
slice, (4) publish globals, apply forces, write outputs; housekeeping is the driver's.
"""

from __future__ import annotations

import dataclasses
import logging
import time
from collections.abc import Callable
from dataclasses import dataclass
from enum import StrEnum
from typing import Any

from runtime.access import AccessControl, AccessDenied, Session
from runtime.clock import Clock
from runtime.code_image import CodeImage, VariablePath, read_path, write_path
from runtime.context import Context, ContextMismatch, restore, snapshot
from runtime.contract.artifact import Artifact, ResourceConfig
from runtime.contract.keyspace import valid_watch_id
from runtime.contract.parameters import RESOURCE_BY_NAME, ParameterError, resource_consistency
from runtime.contract.system_variables import SYSTEM_VARIABLES
from runtime.contract.values import ValueRejected, jsonable, representation
from runtime.cycle_stats import CycleStats
from runtime.event_log import EventLog
from runtime.forcing import GLOBAL, ForceEntry, ForceTable
from runtime.intrinsics import ProgramFault, SystemView, no_tick
from runtime.reload import (
    SwitchOver,
    SwitchOverTooLong,
    live_state,
    prepare_switch_over,
    switch_over,
)
from runtime.reload_plan import LiveState, ReloadPlan, plan_reload
from runtime.slicing import SliceMeter
from runtime.transfer import IncomingArtifact
from runtime.user_program import ProgramState, UserProgram, share_globals
from runtime.watch_sets import MAX_PERIOD_MS, MIN_PERIOD_MS, WatchSet, WatchSets, WatchSnapshot
from runtime.watchdog import Watchdog, WatchdogExpired, process_watchdog

log = logging.getLogger(__name__)

EMERGENCY_STOPS = tuple(v.name for v in SYSTEM_VARIABLES if v.name.startswith("EMERGENCY_STOP"))


class ResourceState(StrEnum):
    STOP_INVALID = "STOP/INVALID CONFIGURATION"
    STOP_VALID = "STOP/VALID CONFIGURATION"
    RUN = "RUN"
    RUN_UP_STOP = "RUN/UP STOP"  # running, but no user program runs
    ERROR_STOP = "ERROR STOP"


class CommandRefused(Exception):
    """A command that is not possible in the current state; the reply says why."""

    def __init__(self, code: str, message: str) -> None:
        super().__init__(message)
        self.code = code
        self.message = message


@dataclass(frozen=True)
class BoundVariable:
    """A variable path with what it belongs to: a user program, or the globals."""

    program: UserProgram | None  # None: a global
    path: VariablePath


def default_value(type_name: str) -> Any:
    """The safe value of an output: 0 / FALSE / empty (de-energise to trip)."""
    name = type_name.upper()
    if name == "BOOL":
        return False
    if name in ("REAL", "LREAL"):
        return 0.0
    if name.startswith(("STRING", "WSTRING", "CHAR", "WCHAR")):
        return ""
    return 0


@dataclass
class Instances:
    """The executable side of a configuration: its code, program and global instances,
    and every elementary variable bound to its owner."""

    image: CodeImage
    programs: list[UserProgram]  # by priority, then Program ID
    globals: Any
    bound: list[BoundVariable]
    by_name: dict[str, BoundVariable]


def instantiate(artifact: Artifact, system: SystemView) -> Instances:
    """Fresh instances of everything: every variable at its initial value."""
    image = CodeImage(artifact, system)
    configs = sorted(artifact.programs, key=lambda p: (p.priority, p.program_id))
    # a program needs its own view of the globals when another program could change them
    # during its program cycle, or when its cycle spans several CPU cycles
    private = len(configs) > 1 or any(c.max_duration_us for c in configs)
    programs = []
    for config in configs:
        instance = image.new_instance(config.pou)
        # `prog();` in ST reaches the user program of that POU (the first by priority), so
        # a program called from another one is the same instance the task runs
        image.register_program(config.pou, instance)
        view = image.new_globals() if private and image.globals is not None else image.globals
        programs.append(
            UserProgram(config, instance, image.variable_paths(config.name, config.pou), view)
        )
    for pou in artifact.pous:  # a PROGRAM that is no user program still has one instance
        if pou.kind == "PROGRAM":
            image.register_program(pou.name, image.new_instance(pou.name))
    bound = [
        *(BoundVariable(p, path) for p in programs for path in p.paths),
        *(BoundVariable(None, path) for path in image.global_paths()),
    ]
    return Instances(image, programs, image.globals, bound, index(bound))


def index(bound: list[BoundVariable]) -> dict[str, BoundVariable]:
    """Variables by upper-case path (ST names are case-insensitive); the first wins."""
    by_name: dict[str, BoundVariable] = {}
    for variable in bound:
        by_name.setdefault(variable.path.path.upper(), variable)
    return by_name


class ReloadJob:
    """A reload on its way: made by `Resource.begin_reload`, prepared by `prepare` (which
    touches nothing of the running configuration, so it may run on another thread while
    cycles go on), switched by `Resource.finish_reload` between two cycles."""

    def __init__(
        self,
        artifact: Artifact,
        renames: dict[str, str],
        old: Instances,
        old_artifact: Artifact,
        system: SystemView,
        live: LiveState,
    ) -> None:
        self.artifact, self.renames = artifact, renames
        # the programs as they were (a list of its own: a restart replaces one)
        self.old, self.old_artifact, self.system = old, old_artifact, system
        self.live = live
        self.watchdog_ms: int | None = None
        self.target_cycle_ms: int | None = None
        self.user: str | None = None
        self.instances: Instances | None = None
        self.plan: ReloadPlan | None = None
        self.prepared: SwitchOver | None = None
        self.failure: str | None = None
        self.preview = False  # only the plan is wanted
        self.expected_crc: str | None = None  # the configuration the user previewed against

    def prepare(self) -> None:
        """New instances, the plan and the switch-over list; never raises."""
        try:
            self.instances = instantiate(self.artifact, self.system)
            self.plan = plan_reload(
                self.old_artifact,
                self.artifact,
                self.renames,
                self.live,
                [b.path for b in self.old.bound],
                [b.path for b in self.instances.bound],
            )
            if not self.plan.refusals and not self.preview:
                self.prepared = prepare_switch_over(
                    self.old, self.instances, self.plan, self.renames
                )
        except Exception as exc:  # generated code that fails while it is set up
            self.failure = f"{type(exc).__name__}: {exc}"


class Resource:
    def __init__(self, name: str, clock: Clock, events: EventLog | None = None) -> None:
        self.name = name
        self.clock = clock
        self.events = events if events is not None else EventLog(clock.wall_ns)
        self.state = ResourceState.STOP_INVALID
        self.artifact: Artifact | None = None
        self.params = ResourceConfig(name=name)  # the loaded ones, with online changes
        self.programs: list[UserProgram] = []  # by priority, then Program ID
        self.stats = CycleStats()
        self.cycle_count = 0  # CPU cycles that ran, single steps included
        self.system = SystemView()
        self.globals: Any = None  # the globals as all programs see them between cycles
        self.error: str | None = None  # why the resource is in ERROR STOP
        self.forces = ForceTable()
        self.watchdog: Watchdog = process_watchdog()
        self.meter = SliceMeter(virtual=clock.virtual)
        self.start_kind: str | None = "cold"  # what the next first cycle is: cold | warm
        self.last_start = ""  # how the resource last started: cold | warm | continued
        self.outputs: dict[str, Any] = {}  # the output image as last written to the field
        self._safe_values: dict[str, Any] = {}  # configured safe values by upper-case path
        self._image: CodeImage | None = None
        self._bound: list[BoundVariable] = []
        self._by_name: dict[str, BoundVariable] = {}
        self._output_points: list[BoundVariable] = []
        self.meter_total_ns = 0  # program execution time in the current CPU cycle
        self._inputs: dict[str, Any] = {}  # input image: what the I/O last delivered
        self._first_cycle = False  # the next CPU cycle is the first after a start
        self._last_start_ns: int | None = None
        self._boot_ns = clock.now_ns()
        self._force_deactivation = False
        # told every new configuration (load or reload), to keep it for the next power-up
        self.on_configuration: Callable[[Artifact], None] | None = None
        self.incoming = IncomingArtifact()  # a configuration arriving for load or reload
        self.watches = WatchSets()  # what the clients view
        self.access = AccessControl((), clock.now_ns)  # accounts of the loaded configuration
        self.acting_user: str | None = None  # who sent the command being carried out

    # ---- parameters
    @property
    def cycle_ns(self) -> int:
        """The interval a single step advances time by: the target cycle time, or the
        mean CPU cycle so far when there is none (at least 1 ms)."""
        if self.params.target_cycle_ms:
            return self.params.target_cycle_ms * 1_000_000
        return max(1_000_000, self.stats.mean_ns)

    @property
    def watchdog_ns(self) -> int:
        return self.params.watchdog_ms * 1_000_000

    def set_parameter(self, name: str, value: Any) -> None:
        """An online change of a resource parameter (section 6)."""
        spec = RESOURCE_BY_NAME.get(name)
        if spec is None:
            raise CommandRefused("unknown_parameter", f"no resource parameter '{name}'")
        if not spec.online:
            raise CommandRefused("not_online", f"{name} changes only with a download")
        if name != "allow_online_settings" and not self.params.allow_online_settings:
            raise CommandRefused("not_allowed", "Allow Online Settings is OFF")
        try:
            checked = spec.check(value)
        except ParameterError as exc:
            raise CommandRefused("bad_value", str(exc)) from None
        changed = dataclasses.replace(self.params, **{name: checked})
        problems = resource_consistency(changed.__dict__)
        if problems:
            raise CommandRefused("bad_value", problems[0])
        sliced = sum(p.config.max_duration_us for p in self.programs)
        if sliced > changed.watchdog_ms * 1000:
            raise CommandRefused(
                "bad_value", f"the programs' time slices ({sliced} us) exceed that watchdog"
            )
        old = getattr(self.params, name)
        self.params = changed
        self.system.WATCHDOG_TIME = self.watchdog_ns
        self._event("parameter", f"{name} changed from {old} to {checked}", name=name, old=old)

    def login(self, name: str, password: str) -> tuple[str, Session]:
        """A session token; a failed login is an event (without the password)."""
        try:
            token, session = self.access.login(name, password)
        except AccessDenied as denied:
            self._event("login", f"login of '{name}' refused: {denied.message}", name)
            raise CommandRefused(denied.code, denied.message) from None
        self._event("login", f"{name} logged in ({session.level})", name)
        return token, session

    def reset_stats(self) -> None:
        self.stats = CycleStats()
        self._last_start_ns = None
        self._event("stats", "cycle statistics reset")

    # ---- download and states
    def refused(self, what: str, message: str, new_crc: str | None = None) -> None:
        """A load or reload that did not happen is an event too, with both CRCs."""
        old_crc = self.artifact.crc if self.artifact else None
        self._event(what, f"{what} refused: {message}", old_crc=old_crc, new_crc=new_crc)

    def load(self, artifact: Artifact) -> None:
        """Take a whole configuration (only in STOP); a cold start state follows."""
        try:
            self._load(artifact)
        except CommandRefused as refused:
            self.refused("load", refused.message, artifact.crc)
            raise

    def _load(self, artifact: Artifact) -> None:
        if self.state in (ResourceState.RUN, ResourceState.RUN_UP_STOP):
            raise CommandRefused("state", "a download is only possible in STOP")
        if self.state == ResourceState.ERROR_STOP:
            raise CommandRefused("state", "ERROR STOP: INIT first")
        if self.artifact is not None and not self.params.load_allowed:
            raise CommandRefused("not_allowed", "Load Allowed is OFF")
        old_crc = self.artifact.crc if self.artifact else None
        self.forces = ForceTable()  # a download ends forcing, and its entries lose meaning
        self._take(artifact, instantiate(artifact, self.system))
        self.state = ResourceState.STOP_VALID
        self.start_kind = "cold"
        self._write_outputs(safe=True)
        self._event(
            "load",
            f"configuration {artifact.project} loaded, CRC {artifact.crc} (cold start)",
            old_crc=old_crc,
            new_crc=artifact.crc,
        )
        if self.on_configuration is not None:
            self.on_configuration(artifact)

    def _take(self, artifact: Artifact, instances: Instances) -> None:
        """A new configuration (download or reload) with its instances: parameters, safe
        values, accounts and the system variables that describe it follow it."""
        self._adopt(instances)
        self.artifact, self.params = artifact, artifact.resource
        self._safe_values = {name.upper(): value for name, value in artifact.safe_values}
        self.access.replace_users(artifact.users)  # sessions of removed accounts end
        self.system.CONFIGURATION_CRC = int(artifact.crc, 16)
        self.system.WATCHDOG_TIME = self.watchdog_ns

    def _instantiate(self, artifact: Artifact) -> None:
        """Fresh instances of everything: every variable at its initial value."""
        self._adopt(instantiate(artifact, self.system))

    def _adopt(self, instances: Instances) -> None:
        self._image, self.programs, self.globals = (
            instances.image,
            instances.programs,
            instances.globals,
        )
        self._set_bound(instances.bound)

    def _set_bound(self, bound: list[BoundVariable]) -> None:
        self._bound, self._by_name = bound, index(bound)
        # the output image's points (located %Q variables), listed once, not every cycle
        self._output_points = [
            b for b in bound if b.path.location and b.path.location.upper().startswith("%Q")
        ]

    def init(self) -> None:
        """INIT: leave ERROR STOP for STOP; the next start is a cold start."""
        if self.state != ResourceState.ERROR_STOP:
            raise CommandRefused("state", "INIT leaves ERROR STOP; the resource is not in it")
        assert self.artifact is not None
        self.state, self.error = ResourceState.STOP_VALID, None
        self._instantiate(self.artifact)
        self.start_kind = "cold"
        self._reset_system_inputs()
        self._event("state", "INIT: ERROR STOP left for STOP (cold start next)")

    def cold_start(self) -> None:
        """Every variable to its initial value (in STOP); the next start is a cold start."""
        self._require_stop("a cold start")
        assert self.artifact is not None
        self._instantiate(self.artifact)
        self.start_kind = "cold"
        self._event("state", "cold start prepared: all variables at their initial values")

    def start(self) -> None:
        if self.state == ResourceState.STOP_INVALID:
            raise CommandRefused("state", "no valid configuration is loaded")
        if self.state == ResourceState.ERROR_STOP:
            raise CommandRefused("state", f"ERROR STOP ({self.error}): INIT first")
        if self.state in (ResourceState.RUN, ResourceState.RUN_UP_STOP):
            return
        if not self.params.start_allowed:
            raise CommandRefused("not_allowed", "Start Allowed is OFF")
        self._refuse_read_only("start")
        self.state = ResourceState.RUN
        self._end_forcing("resource start")
        for program in self.programs:
            if program.state == ProgramState.STOP and program.config.start_allowed:
                if program.held:  # stopped before the power failure: stays stopped
                    continue
                program.state = ProgramState.RUN
            program.last_start_ns = None
        self._first_cycle = True
        self._last_start_ns = None
        self.last_start = self.start_kind or "continued"
        self._event("start", f"resource started ({self.start_kind or 'continuing'})")

    def stop(self, reason: str = "stop command") -> None:
        if self.state not in (ResourceState.RUN, ResourceState.RUN_UP_STOP):
            return
        if reason == "stop command":
            self._refuse_read_only("stop")
        self.state = ResourceState.STOP_VALID
        for program in self.programs:
            program.abandon()
            if program.state in (ProgramState.RUN, ProgramState.RUN_FREEZE):
                program.state = ProgramState.STOP
        self._end_forcing("resource stop")
        self._write_outputs(safe=True)
        self._event("stop", f"resource stopped ({reason})")

    def error_stop(self, cause: str) -> None:
        """ERROR STOP: programs halted, outputs safe at once; only INIT leaves it."""
        self.state, self.error = ResourceState.ERROR_STOP, cause
        for program in self.programs:
            program.abandon()
            if program.state in (ProgramState.RUN, ProgramState.RUN_FREEZE):
                program.state = ProgramState.STOP
        self.forces.stop_all()
        self._write_outputs(safe=True)
        self._event("error", f"ERROR STOP: {cause}", long_term=True)
        log.error("resource %s: ERROR STOP, %s", self.name, cause)

    @property
    def shown_state(self) -> ResourceState:
        """RUN/UP STOP when the resource runs but none of its programs does."""
        if self.state == ResourceState.RUN and not any(
            p.state in (ProgramState.RUN, ProgramState.RUN_FREEZE) for p in self.programs
        ):
            return ResourceState.RUN_UP_STOP
        return self.state

    def _require_stop(self, what: str) -> None:
        if self.state not in (ResourceState.STOP_VALID,):
            raise CommandRefused("state", f"{what} is only possible in STOP")

    def _refuse_read_only(self, what: str) -> None:
        if self.state == ResourceState.RUN and self.system.READ_ONLY_IN_RUN:
            raise CommandRefused("read_only", f"Read-only in RUN is ON: no {what}")

    # ---- reload (online change)
    def preview_reload(self, artifact: Artifact, renames: dict[str, str]) -> ReloadPlan:
        """The reload plan against the running state; changes nothing."""
        job = self.begin_preview(artifact, renames)
        job.prepare()
        if job.plan is None:
            raise CommandRefused("reload_failed", f"the new configuration failed: {job.failure}")
        return job.plan

    def begin_preview(self, artifact: Artifact, renames: dict[str, str]) -> ReloadJob:
        """A job that only plans (`prepare` may run on another thread)."""
        if self.artifact is None or self._image is None:
            raise CommandRefused("state", "no configuration is loaded: use a download")
        job = self._job(artifact, renames)
        job.preview = True
        return job

    def _job(self, artifact: Artifact, renames: dict[str, str]) -> ReloadJob:
        """A job against the running configuration and its live chart state."""
        assert self.artifact is not None and self._image is not None
        old = Instances(self._image, list(self.programs), self.globals, self._bound, self._by_name)
        return ReloadJob(
            artifact, renames, old, self.artifact, self.system, live_state(self.artifact, old)
        )

    def reload(
        self,
        artifact: Artifact,
        renames: dict[str, str],
        watchdog_ms: int | None = None,
        target_cycle_ms: int | None = None,
    ) -> dict[str, Any]:
        """Replace the running configuration between two cycles, values carried over by
        name; all or nothing. `watchdog_ms` / `target_cycle_ms` raise the budget for this
        reload (never below the configured values). The runtime process prepares on a
        worker thread instead (`begin_reload`, `ReloadJob.prepare`, `finish_reload`)."""
        job = self.begin_reload(artifact, renames, watchdog_ms, target_cycle_ms, self.acting_user)
        job.prepare()
        return self.finish_reload(job)

    def begin_reload(
        self,
        artifact: Artifact,
        renames: dict[str, str],
        watchdog_ms: int | None = None,
        target_cycle_ms: int | None = None,
        user: str | None = None,
        expected_crc: str | None = None,
    ) -> ReloadJob:
        """Check what can be checked at once; the job then prepares (anywhere)."""
        try:
            self._check_reload()
            self._reload_budget(watchdog_ms, target_cycle_ms)  # refuses a lowering now
        except CommandRefused as refused:
            self.refused("reload", refused.message, artifact.crc)
            raise
        job = self._job(artifact, renames)
        job.watchdog_ms, job.target_cycle_ms, job.user = watchdog_ms, target_cycle_ms, user
        job.expected_crc = expected_crc
        return job

    def finish_reload(self, job: ReloadJob) -> dict[str, Any]:
        """The switch-over, between two cycles; refused if anything changed meanwhile."""
        try:
            return self._switch(job)
        except CommandRefused as refused:
            self.refused("reload", refused.message, job.artifact.crc)
            raise

    def _check_reload(self) -> None:
        if self.artifact is None or self._image is None:
            raise CommandRefused("state", "no configuration is loaded: use a download")
        if self.state not in (ResourceState.RUN, ResourceState.RUN_UP_STOP):
            raise CommandRefused("state", "reload needs the resource running; in STOP, download")
        if not self.params.reload_allowed:
            raise CommandRefused("not_allowed", "Reload Allowed is OFF")
        if self.system.RELOAD_DEACTIVATION:
            raise CommandRefused("reload_deactivated", "Reload Deactivation is ON")
        self._refuse_read_only("reload")

    def _switch(self, job: ReloadJob) -> dict[str, Any]:
        self._check_reload()
        if job.expected_crc is not None and job.old_artifact.crc != job.expected_crc:
            raise CommandRefused(
                "changed", f"the resource runs {job.old_artifact.crc}, not {job.expected_crc}"
            )
        if job.failure is not None:
            raise CommandRefused("reload_failed", f"the new configuration failed: {job.failure}")
        plan, instances, prepared = job.plan, job.instances, job.prepared
        assert plan is not None and instances is not None
        if plan.refusals:
            raise CommandRefused(
                "needs_download", "needs STOP and download: " + "; ".join(plan.refusals)
            )
        assert prepared is not None
        if job.old.programs != self.programs or self.artifact is not job.old_artifact:
            raise CommandRefused("busy", "the configuration changed while the reload prepared")
        busy = [p.name for p in self.programs if p.in_progress]
        if busy:
            raise CommandRefused(
                "busy", f"program {busy[0]} is in the middle of its program cycle; try again"
            )
        budget = self._reload_budget(job.watchdog_ms, job.target_cycle_ms)
        if plan.estimate_ns > budget:
            raise CommandRefused(
                "budget",
                f"the switch-over needs about {plan.estimate_ns / 1000:.0f} us but the cycle "
                f"leaves {max(0, budget) / 1000:.0f} us: raise the watchdog (and in the fixed "
                "and dynamic modes the target cycle time) for the reload, or reload less at once",
            )
        begin = time.perf_counter_ns()
        deadline = None if self.clock.virtual else begin + budget
        try:
            carried = switch_over(prepared, instances, deadline)
        except SwitchOverTooLong:
            raise CommandRefused(
                "interrupted",
                f"the switch-over took longer than the {budget / 1000:.0f} us the cycle leaves; "
                "the old configuration runs on",
            ) from None
        old_crc = job.old_artifact.crc
        running = self.state in (ResourceState.RUN, ResourceState.RUN_UP_STOP)
        for program in instances.programs:
            if program.name in plan.programs_added:
                start = running and program.config.start_allowed
                program.state = ProgramState.RUN if start else ProgramState.STOP
        artifact = job.artifact
        self._take(artifact, instances)
        for entry in self.forces.entries():  # forcing survives, where the variable does
            if entry.path.upper() not in self._by_name:
                self.forces.remove(entry.path)
        for name in plan.programs_removed:
            self.forces.stop(name)
        pause_ns = time.perf_counter_ns() - begin
        outcome: dict[str, Any] = {
            "old_crc": old_crc,
            "new_crc": artifact.crc,
            "pause_us": pause_ns / 1000,
            "carried": carried,
        }
        self._event(
            "reload",
            f"reload done: {old_crc} -> {artifact.crc}, {carried} values carried over",
            job.user,
            **outcome,
        )
        if self.on_configuration is not None:
            self.on_configuration(artifact)
        return outcome

    def _reload_budget(self, watchdog_ms: int | None, target_cycle_ms: int | None) -> int:
        """The time the switch-over may add to a cycle: what the watchdog leaves after the
        last cycle, and in the fixed and dynamic modes what the target cycle leaves."""
        params = self.params
        for name, value, configured in (
            ("watchdog_ms", watchdog_ms, params.watchdog_ms),
            ("target_cycle_ms", target_cycle_ms, params.target_cycle_ms),
        ):
            if value is not None and value < configured:
                raise CommandRefused(
                    "bad_value", f"{name} for a reload may only raise it (now {configured})"
                )
        watchdog = (watchdog_ms or params.watchdog_ms) * 1_000_000
        limit = watchdog
        target = (target_cycle_ms or params.target_cycle_ms) * 1_000_000
        if target and params.target_cycle_mode in ("fixed", "dynamic"):
            limit = min(limit, target)
        return limit - self.stats.last_ns

    # ---- context (warm start)
    def context(self) -> Context | None:
        """A consistent image of everything a warm start needs (taken between cycles)."""
        if self.artifact is None:
            return None
        programs = {
            p.name: {"state": p.state.value, "time_ns": p.time_ns, "values": snapshot(p.instance)}
            for p in self.programs
        }
        return Context(
            signature=self.artifact.crc,
            saved_ns=self.clock.wall_ns(),
            resource={"state": self.state.value, "cycle": self.cycle_count},
            programs=programs,
            globals=snapshot(self.globals) if self.globals is not None else None,
        )

    def warm_start(self, context: Context) -> list[str]:
        """Take the values of a valid context (in STOP, after a load): the next start is a
        warm start. Safety-related programs keep their initial values: they always
        cold-start. Returns the programs restored."""
        self._require_stop("a warm start")
        restored = []
        try:
            restore(self.globals, context.globals)
            for program in self.programs:
                saved = context.programs.get(program.name)
                if saved is None or program.config.safety_related:
                    continue
                restore(program.instance, saved["values"])
                # timers and step times hold absolute program time: it comes back too
                program.time_ns = int(saved["time_ns"])
                program.held = saved["state"] in (ProgramState.STOP, ProgramState.ERROR)
                restored.append(program.name)
        except (ContextMismatch, KeyError, TypeError, ValueError) as exc:
            assert self.artifact is not None
            self._instantiate(self.artifact)  # nothing half-restored
            self._event("state", f"cold start: the saved context does not fit ({exc})")
            return []
        share_globals(self.globals, self.programs)
        self.start_kind = "warm"
        self._event("state", f"warm start prepared from the context saved at {context.saved_ns}")
        return restored

    # ---- user programs
    def program(self, name: str) -> UserProgram:
        for program in self.programs:
            if program.name.upper() == name.upper():
                return program
        raise CommandRefused("unknown_program", f"resource {self.name} has no program '{name}'")

    def start_program(self, name: str) -> None:
        program = self.program(name)
        if self.state not in (ResourceState.RUN, ResourceState.RUN_UP_STOP):
            raise CommandRefused("state", "a program starts only while the resource runs")
        if not program.config.start_allowed:
            raise CommandRefused("not_allowed", f"Start Allowed of {program.name} is OFF")
        if program.state == ProgramState.ERROR:
            program = self._restart_program_cold(program)
        if program.state != ProgramState.STOP:
            return
        program.state, program.last_start_ns, program.held = ProgramState.RUN, None, False
        self._event("program", f"program {program.name} started", program=program.name)

    def stop_program(self, name: str) -> None:
        program = self.program(name)
        if program.state not in (ProgramState.RUN, ProgramState.RUN_FREEZE):
            return
        self._refuse_read_only("program stop")
        program.abandon()
        program.state = ProgramState.STOP
        if self.forces.stop(program.name):
            self._event("force", f"local forcing of {program.name} ended: program stop")
        self._event("program", f"program {program.name} stopped", program=program.name)

    def _restart_program_cold(self, program: UserProgram) -> UserProgram:
        """A program leaves ERROR by a start: from its initial values (its state after the
        error is not to be trusted)."""
        assert self._image is not None
        fresh = self._image.new_instance(program.config.pou)
        replacement = UserProgram(program.config, fresh, program.paths, program.view)
        self.programs[self.programs.index(program)] = replacement
        self._set_bound(
            [BoundVariable(replacement, b.path) if b.program is program else b for b in self._bound]
        )
        replacement.state = ProgramState.STOP
        return replacement

    def freeze(self, name: str) -> None:
        """Single step on: the program runs one program cycle per `step_program`."""
        program = self.program(name)
        if not program.config.freeze_allowed:
            raise CommandRefused("not_allowed", f"Freeze Allowed of {program.name} is OFF")
        if self.params.safety_operation:
            raise CommandRefused("safety_operation", "no single step in safety operation")
        if self.state != ResourceState.RUN or program.state != ProgramState.RUN:
            raise CommandRefused("state", f"program {program.name} is not running")
        if program.in_progress:
            # finish the program cycle in progress first: a frozen program always stands
            # between two program cycles
            self._run_to_end(program)
        program.state = ProgramState.RUN_FREEZE
        self._event("program", f"program {program.name} frozen (single step)")

    def unfreeze(self, name: str) -> None:
        program = self.program(name)
        if program.state != ProgramState.RUN_FREEZE:
            raise CommandRefused("state", f"program {program.name} is not in single step")
        program.state, program.last_start_ns = ProgramState.RUN, None
        self._event("program", f"program {program.name} leaves single step")

    def step_program(self, name: str, interval_ns: int | None = None) -> None:
        """One whole program cycle of a frozen program; its time advances by one cycle
        interval, so its timers behave as in operation."""
        program = self.program(name)
        if program.state != ProgramState.RUN_FREEZE:
            raise CommandRefused("state", f"program {program.name} is not in single step")
        step = interval_ns if interval_ns is not None else self.cycle_ns
        self._guarded(lambda: self._run_to_end(program, step))
        self._publish([program])
        self._apply_forces()
        self._write_outputs(safe=False)

    def step(self) -> None:
        """In STOP: one CPU cycle of every program, time advancing one interval."""
        if self.state != ResourceState.STOP_VALID:
            raise CommandRefused("state", "single step of the resource needs it in STOP")
        runnable = [p for p in self.programs if p.state != ProgramState.ERROR]

        def run_all() -> None:
            for program in runnable:
                self._run_to_end(program, self.cycle_ns)

        self._guarded(run_all)
        self._publish(runnable)
        self.cycle_count += 1

    # ---- the CPU cycle
    def cycle(self) -> None:
        """One CPU cycle; in STOP only inputs are read (outputs stay safe)."""
        begin = self.clock.now_ns()
        self._read_inputs()
        if self.state not in (ResourceState.RUN, ResourceState.RUN_UP_STOP):
            return
        if self._last_start_ns is not None:
            period = begin - self._last_start_ns
            self.stats.record_period(period, self.params.target_cycle_ms * 1_000_000)
        self._last_start_ns = begin
        self._update_system(begin)
        self._check_force_time(begin)
        self._apply_forces()
        finished: list[UserProgram] = []
        if not self._guarded(lambda: self._run_programs(begin, finished)):
            return
        self._publish(finished)
        self._check_force_deactivation()
        self._apply_forces()
        self._write_outputs(safe=False)
        self._after_first_cycle()
        self.cycle_count += 1
        target = self.params.target_cycle_ms * 1_000_000
        if self.clock.virtual:  # what the programs used, counted in loop passes
            self.stats.record(self.meter_total_ns, target)
        else:
            self.stats.record(self.clock.now_ns() - begin, target)

    def _run_programs(self, begin: int, finished: list[UserProgram]) -> None:
        """Programs by priority, each in its slice; multitasking modes 2 and 3 decide what
        happens with the time a program leaves unused."""
        mode = self.params.multitasking_mode
        self.meter_total_ns = 0
        unused_ns = 0
        for program in list(self.programs):
            if program.state != ProgramState.RUN:
                continue
            budget = program.config.max_duration_us * 1000 or None
            if not program.in_progress:
                program.begin_cycle(self._delta(program, begin), self.globals)
            used, done = self._slice(program, budget)
            if done:
                finished.append(program)
            elif program.state == ProgramState.RUN:
                self._check_program_watchdog(program)
            if budget is not None:
                unused_ns += max(0, budget - used)
                if mode == 3 and used < budget:
                    self._wait(budget - used)  # every cycle as long as the worst case
        if mode == 2:
            for program in list(self.programs):
                if unused_ns <= 0:
                    break
                if program.state == ProgramState.RUN and program.in_progress:
                    used, done = self._slice(program, unused_ns, extra=True)
                    unused_ns -= used
                    if done:
                        finished.append(program)

    def _slice(
        self, program: UserProgram, budget_ns: int | None, extra: bool = False
    ) -> tuple[int, bool]:
        """Run a program on for at most `budget_ns`; (time used, program cycle ended).
        A run-time error puts the program in ERROR; the others go on."""
        assert self._image is not None
        view, meter = program.view, self.meter

        def before() -> None:
            assert self._image is not None
            self.system.now_ns = program.cycle_time_ns
            self._image.use(view, meter.tick if budget_ns is not None else no_tick)
            meter.begin(budget_ns)

        done = False
        try:
            if extra:  # more time for a program in its CPU cycle: not another CPU cycle
                program.cpu_cycles -= 1
            done = program.resume(before)
        except (Exception, RecursionError) as exc:
            self._program_fault(program, exc)
        used = meter.used_ns()
        self.meter_total_ns += used
        self._check_emergency_stop()
        return used, done

    def _run_to_end(self, program: UserProgram, step_ns: int | None = None) -> None:
        """A whole program cycle at once (single step): no slice limit."""
        if not program.in_progress:
            program.begin_cycle(step_ns if step_ns is not None else self.cycle_ns, self.globals)
        while program.in_progress and program.state not in (ProgramState.ERROR,):
            self._slice(program, None)

    def _check_program_watchdog(self, program: UserProgram) -> None:
        """A program cycle may span Max. Cycles CPU cycles of Max. Duration each."""
        config = program.config
        if program.cpu_cycles >= config.max_cycles:
            program.abandon()
            program.state = ProgramState.ERROR
            program.error = (
                f"program watchdog: the program cycle did not end within {config.max_cycles} "
                f"CPU cycle(s) of {config.max_duration_us} us"
            )
            self._event("error", f"program {program.name}: {program.error}", long_term=True)

    def _program_fault(self, program: UserProgram, exc: BaseException) -> None:
        assert self._image is not None
        program.abandon()
        program.state = ProgramState.ERROR
        # a ProgramFault says what went wrong in ST terms; anything else is named by its
        # Python type so that a compiler defect can be told from a program error
        if isinstance(exc, RecursionError):
            cause = "calls nested too deep (recursion)"
        elif isinstance(exc, ProgramFault | ArithmeticError):
            cause = str(exc)
        else:
            cause = f"{type(exc).__name__}: {exc}"
        where = self._image.locate(exc)
        program.error = f"{cause} in {where}" if where is not None else cause
        details: dict[str, Any] = {"program": program.name, "cause": cause}
        if where is not None:
            details.update(pou=where.pou, file=where.file, line=where.line)
        self._event("error", f"program {program.name}: {program.error}", long_term=True, **details)
        log.error("program %s: %s", program.name, program.error)

    def _guarded(self, work: Callable[[], None]) -> bool:
        """Work under the resource watchdog: a CPU cycle longer than the watchdog time (an
        endless loop, say) ends in ERROR STOP, and the runtime still answers. False when
        the resource halted."""
        try:
            with self.watchdog.guard(self.watchdog_ns):
                work()
            return True
        except _Halted:  # an Emergency Stop: already in ERROR STOP
            return False
        except WatchdogExpired:
            running = [p.name for p in self.programs if p.in_progress]
            cause = f"watchdog: the cycle took longer than {self.watchdog_ns // 1_000_000} ms"
            if running:
                cause += f" (in program {running[-1]})"
            self.error_stop(cause)
            return False

    def _delta(self, program: UserProgram, begin: int) -> int:
        """How far a program's time advances at the start of its program cycle: the
        clock's time since its last program cycle started."""
        delta = self.cycle_ns if program.last_start_ns is None else begin - program.last_start_ns
        program.last_start_ns = begin
        return delta

    def _wait(self, duration_ns: int) -> None:
        if self.clock.virtual:
            self.meter_total_ns += duration_ns
        else:
            self.clock.sleep_until(self.clock.now_ns() + duration_ns)

    def _publish(self, finished: list[UserProgram]) -> None:
        """The writes of programs whose program cycle ended become visible to the others
        (in their next program cycle: one CPU cycle later at the earliest)."""
        for program in finished:
            program.publish(self.globals)

    # ---- system variables
    def _update_system(self, begin: int) -> None:
        system = self.system
        system.START_CYCLE = self._first_cycle
        system.COLDSTART = self._first_cycle and self.start_kind == "cold"
        system.WARMSTART = self._first_cycle and self.start_kind == "warm"
        system.CYCLE_TIME_LAST = self.stats.last_ns
        system.CYCLE_TIME_MIN = self.stats.min_ns
        system.CYCLE_TIME_MAX = self.stats.max_ns
        system.CYCLE_TIME_MEAN = self.stats.mean_ns
        system.SYSTEM_TICK = ((begin - self._boot_ns) // 1_000_000) & 0xFFFFFFFF
        remaining = self.forces.remaining_ns(GLOBAL, begin)
        system.FORCE_TIME_REMAINING = remaining or 0
        system.DATE_AND_TIME = self.clock.wall_ns()

    def _after_first_cycle(self) -> None:
        if self._first_cycle:
            self._first_cycle = False
            self.start_kind = None

    def _check_emergency_stop(self) -> None:
        for number, name in enumerate(EMERGENCY_STOPS, 1):
            if getattr(self.system, name) and self.state != ResourceState.ERROR_STOP:
                self.error_stop(f"Emergency Stop {number} set")
                raise _Halted()

    def _reset_system_inputs(self) -> None:
        for name in EMERGENCY_STOPS:
            setattr(self.system, name, False)

    # ---- inputs, forces, outputs
    def set_inputs(self, values: dict[str, Any]) -> None:
        """What the I/O delivered for located inputs; read at the next cycle's start."""
        self._inputs.update(values)

    def _read_inputs(self) -> None:
        for path, value in sorted(self._inputs.items()):
            bound = self._by_name.get(path.upper())
            if bound is not None:
                self._store(bound, value)
        self._inputs.clear()

    def _write_outputs(self, safe: bool) -> None:
        """The output image (located %Q variables) as the I/O sends it to the field."""
        image: dict[str, Any] = {}
        for bound in self._output_points:
            if safe:
                configured = self._safe_values.get(bound.path.path.upper())
                image[bound.path.path] = (
                    configured if configured is not None else default_value(bound.path.type)
                )
            else:
                image[bound.path.path] = self._read_bound(bound)
        self.outputs = image

    def _apply_forces(self) -> None:
        for entry in self.forces.active():
            bound = self._by_name.get(entry.path.upper())
            if bound is not None:
                self._store(bound, entry.value)

    def _store(self, bound: BoundVariable, value: Any) -> None:
        """Write a variable where every reader sees it: a global into the globals and into
        every program's view of them."""
        if bound.program is not None:
            write_path(bound.program.instance, bound.path, value)
            return
        write_path(self.globals, bound.path, value)
        for program in self.programs:
            if program.view is not self.globals:
                write_path(program.view, bound.path, value)

    def _read_bound(self, bound: BoundVariable) -> Any:
        owner = bound.program.instance if bound.program is not None else self.globals
        return read_path(owner, bound.path)

    def _check_force_time(self, now: int) -> None:
        """Force time limits: stop forcing, or stop the resource / program."""
        for level in self.forces.expired(now):
            self.forces.stop(level)
            if level == GLOBAL:
                reaction = self.params.global_force_timeout_reaction
                self._event("force", f"global force time expired: {reaction}", long_term=True)
                if reaction == "stop-resource":
                    self.stop(reason="global force time expired")
            else:
                program = self.program(level)
                reaction = program.config.local_force_timeout_reaction
                self._event("force", f"force time of {level} expired: {reaction}", long_term=True)
                if reaction == "stop-program":
                    program.abandon()
                    program.state = ProgramState.STOP

    def _end_forcing(self, why: str) -> None:
        for level in self.forces.stop_all():
            self._event("force", f"{_forcing_name(level)} ended: {why}", long_term=True)

    def _force_level(self, bound: BoundVariable) -> str:
        return GLOBAL if bound.program is None else bound.program.name

    def _check_forcing_allowed(self, level: str) -> None:
        if self.params.safety_operation:
            raise CommandRefused("safety_operation", "no forcing in safety operation")
        if self.system.FORCE_DEACTIVATION:
            raise CommandRefused("force_deactivated", "Force Deactivation is ON")
        if level == GLOBAL:
            if not self.params.global_forcing_allowed:
                raise CommandRefused("not_allowed", "Global Forcing Allowed is OFF")
        elif not self.program(level).config.local_forcing_allowed:
            raise CommandRefused("not_allowed", f"Local Forcing Allowed of {level} is OFF")

    def force(self, name: str, value: Any, switch: bool = True) -> None:
        """Prepare a force value and its switch; it acts while forcing runs at its level."""
        bound = self._lookup(name)
        level = self._force_level(bound)
        self._check_forcing_allowed(level)
        stored = self._checked(bound, value)
        old = self._read_bound(bound)
        self.forces.set(ForceEntry(bound.path.path, level, stored, switch))
        if self.forces.is_forced(bound.path.path):
            self._store(bound, stored)
        self._event(
            "force",
            f"{bound.path.path} forced to {stored!r} (switch {'ON' if switch else 'OFF'})",
            variable=bound.path.path,
            old=old,
            new=stored,
        )

    def unforce(self, name: str) -> None:
        bound = self._lookup(name)
        if self.forces.remove(bound.path.path) is None:
            raise CommandRefused("not_forced", f"'{bound.path.path}' has no force value")
        self._event("force", f"{bound.path.path} force value removed")

    def start_forcing(self, program: str | None = None, timeout_ns: int | None = None) -> None:
        level = GLOBAL if program is None else self.program(program).name
        self._check_forcing_allowed(level)
        if self.state not in (ResourceState.RUN, ResourceState.RUN_UP_STOP):
            raise CommandRefused("state", "forcing starts only while the resource runs")
        self.forces.start(level, self.clock.now_ns(), timeout_ns)
        self._apply_forces()
        limit = f"{timeout_ns / 1e9:g} s" if timeout_ns is not None else "no time limit"
        self._event("force", f"{_forcing_name(level)} started ({limit})")

    def stop_forcing(self, program: str | None = None) -> None:
        level = GLOBAL if program is None else self.program(program).name
        if self.forces.stop(level):
            self._event("force", f"{_forcing_name(level)} stopped")

    def _check_force_deactivation(self) -> None:
        """Force Deactivation OFF -> ON ends all forcing at once (ON also blocks it)."""
        now_on = bool(self.system.FORCE_DEACTIVATION)
        if now_on and not self._force_deactivation:
            self._end_forcing("Force Deactivation ON")
        self._force_deactivation = now_on

    def forcing(self) -> dict[str, Any]:
        now = self.clock.now_ns()
        return {
            "started": self.forces.started_levels(),
            "remaining_ms": {
                level or "global": (
                    r / 1e6 if (r := self.forces.remaining_ns(level, now)) else None
                )
                for level in self.forces.started_levels()
            },
            "entries": [
                {
                    "variable": e.path,
                    "level": e.level or "global",
                    "value": e.value,
                    "switch": e.switch,
                    "active": self.forces.is_forced(e.path),
                }
                for e in self.forces.entries()
            ],
        }

    # ---- events
    def _event(
        self,
        kind: str,
        message: str,
        user: str | None = None,
        long_term: bool | None = None,
        **details: Any,
    ) -> None:
        # user actions and configuration changes go to the long-term log too
        keep = long_term if long_term is not None else kind != "error"
        plain = {name: jsonable(value) for name, value in sorted(details.items())}
        who = user if user is not None else self.acting_user
        self.events.record(kind, message, user=who, long_term=keep, **plain)

    # ---- views
    def status(self) -> dict[str, Any]:
        return {
            "resource": self.name,
            "state": self.shown_state.value,
            "crc": self.artifact.crc if self.artifact else None,
            "error": self.error,
            "project": self.artifact.project if self.artifact else None,
            "cycle": self.cycle_count,
            "cycle_ms": self.cycle_ns / 1e6,
            "stats": self.stats.as_json(),
            "forcing": self.forces.started_levels() != [],
            "access": "open" if self.access.open else "users",
            "start": self.start_kind if self.state == ResourceState.STOP_VALID else self.last_start,
            "programs": [
                {
                    "name": p.name,
                    "id": p.config.program_id,
                    "priority": p.config.priority,
                    "state": p.state.value,
                    "crc": p.config.crc,
                    "cycles": p.stats.count,
                    "cpu_cycles_max": p.stats.max_cpu_cycles,
                    "error": p.error,
                }
                for p in self.programs
            ],
        }

    def variables(self) -> list[dict[str, str]]:
        return [{"path": bound.path.path, "type": bound.path.type} for bound in self._bound]

    def watch(
        self, watch_id: str, names: list[str], period_ms: int, append: bool = False
    ) -> list[str]:
        """Register what a client views; returns the canonical paths (all names must
        exist: a typo gets an error, not a silently empty field). `append` adds to a set
        (a large set arrives in several requests)."""
        if not valid_watch_id(watch_id):
            raise CommandRefused("bad_request", "a watch id is 1 to 64 of A-Z a-z 0-9 _ -")
        if not MIN_PERIOD_MS <= period_ms <= MAX_PERIOD_MS:
            raise CommandRefused(
                "bad_request", f"period_ms must be from {MIN_PERIOD_MS} to {MAX_PERIOD_MS}"
            )
        if self.watches.full(watch_id):
            raise CommandRefused("too_many", "too many watch sets on this resource")
        paths = tuple(self._lookup(name).path.path for name in names)
        existing = self.watches.get(watch_id) if append else None
        if existing is not None:
            paths = existing.paths + paths
        self.watches.set(WatchSet(watch_id, paths, period_ms * 1_000_000))
        return list(paths)

    def watched(self, watch_set: WatchSet) -> WatchSnapshot:
        """A watch set's values as this cycle left them, each with its quality (live;
        forced; stale when nothing that could change it runs; deleted by a reload). Only
        the reading happens here, between two cycles; `WatchSnapshot.message` builds
        the message elsewhere."""
        running = self.state in (ResourceState.RUN, ResourceState.RUN_UP_STOP)
        forcing = bool(self.forces.started_levels())
        halted = {
            id(p)
            for p in self.programs
            if p.state not in (ProgramState.RUN, ProgramState.RUN_FREEZE)
        }
        entries: list[tuple[str, Any, str]] = []
        for path in watch_set.paths:
            bound = self._by_name.get(path.upper())
            if bound is None:
                entries.append((path, None, "deleted"))
                continue
            if forcing and self.forces.is_forced(path):
                quality = "forced"
            elif not running or (bound.program is not None and id(bound.program) in halted):
                quality = "stale"
            else:
                quality = "live"
            entries.append((path, self._read_bound(bound), quality))
        return WatchSnapshot(self.cycle_count, entries)

    def values(self) -> dict[str, Any]:
        """Every elementary variable: `Program.var`, `Program.fb.var`, globals by their bare
        name; struct and FB members with dots; arrays of elementary values as lists."""
        return {bound.path.path: self._read_bound(bound) for bound in self._bound}

    # ---- online test
    def _lookup(self, name: str) -> BoundVariable:
        bound = self._by_name.get(name.upper())  # ST names are case-insensitive
        if bound is None:
            raise CommandRefused(
                "unknown_variable", f"resource {self.name} has no variable '{name}'"
            )
        return bound

    def variable(self, name: str) -> VariablePath:
        """The elementary variable called `name` (a path as `values()` names it)."""
        return self._lookup(name).path

    def read(self, name: str) -> Any:
        """The value of one variable, as `values()` has it."""
        return self._read_bound(self._lookup(name))

    def _checked(self, bound: BoundVariable, value: Any) -> Any:
        if bound.path.constant:
            raise CommandRefused("constant", f"'{bound.path.path}' is a constant")
        try:
            return representation(bound.path.type, value)
        except ValueRejected as exc:
            raise CommandRefused("bad_value", f"'{bound.path.path}': {exc}") from None

    def write(self, name: str, value: Any) -> None:
        """Write a value once from an OLT field (not forcing): refused in safety
        operation; a forced variable keeps its force value."""
        if self.params.safety_operation:
            raise CommandRefused("safety_operation", "no writes from OLT in safety operation")
        bound = self._lookup(name)
        stored = self._checked(bound, value)
        old = self._read_bound(bound)
        self._store(bound, stored)
        self._event(
            "write",
            f"{bound.path.path} written: {old!r} -> {stored!r}",
            variable=bound.path.path,
            old=old,
            new=stored,
        )

    def simulate(self, name: str, value: Any) -> None:
        """Set a variable as the simulated plant does (`padt sim --set`): no event, and
        allowed in safety operation, since no real plant is behind it."""
        bound = self._lookup(name)
        self._store(bound, self._checked(bound, value))


def _forcing_name(level: str) -> str:
    return "global forcing" if level == GLOBAL else f"local forcing of {level}"


class _Halted(BaseException):
    """Ends the CPU cycle at once (Emergency Stop); caught by nothing but the cycle."""
