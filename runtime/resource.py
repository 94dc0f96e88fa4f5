"""A resource: one controller with its loaded configuration, its states and its CPU cycle.

The resource holds the state machine of spec section 4 and runs the CPU cycle in the
order of section 5: (1) read inputs, (2) apply forces, (3) run user programs by priority,
each in its time slice, (4) publish globals, apply forces, write outputs; housekeeping is
the cycle driver's. Its parts own their state: the variables of the configuration
(`variables`), the process image (`io`), forcing (`forcing`), online values (`online`),
the program scheduler (`scheduler`), sessions (`access`) and the event log (`recorder`).
Operations that span several parts live in modules of their own: program control
(`program_control.py`), reload (`reload_switch.py`), warm start (`restart.py`), online
parameters (`online_parameters.py`).

Only the cycle thread calls it (commands reach it through the cycle driver's queue), so it
needs no locks.
"""

from __future__ import annotations

import logging
from typing import TYPE_CHECKING, Any, Protocol

from runtime.clock import Clock
from runtime.code.instances import Instances, instantiate, instantiated
from runtime.code.intrinsics import EMERGENCY_STOPS, SystemView
from runtime.code.native.tier import NativeReport, NativeTier
from runtime.code.user_program import UserProgram
from runtime.commissioning import SetupSecret
from runtime.configuration_store import ConfigurationStore
from runtime.contract.accounts import AccessControl, Challenge, Proven
from runtime.contract.artifact import Artifact, ResourceConfig
from runtime.contract.protocol import ProgramState, ProgramStatus, ResourceState, Status
from runtime.contract.recording import LoggedHit
from runtime.contract.refusal import Refusal
from runtime.cycle_core import CycleCore, cycle_core
from runtime.cycle_stats import CycleStats
from runtime.debugging.debugger import Debugger
from runtime.event_log import EventLog
from runtime.event_recorder import LONG_TERM_SHARES as SHARES
from runtime.event_recorder import EventRecorder
from runtime.force_table import GLOBAL
from runtime.forcing import Forcing
from runtime.identity import Identity
from runtime.image_switch import enter_image, leave_image, may_enter, must_leave
from runtime.login_audit import LoginAudit
from runtime.online_values import OnlineValues
from runtime.process_image import ProcessImage
from runtime.scheduler import Scheduler
from runtime.transfer import IncomingArtifact
from runtime.variables import Variables

if TYPE_CHECKING:
    from runtime.field_io import FieldIo

log = logging.getLogger(__name__)

_RUNNING = (ResourceState.RUN, ResourceState.RUN_UP_STOP)
MAX_SESSIONS_PER_ACCOUNT = 64  # the oldest of an account's sessions end beyond it


class CycleRecorder(Protocol):
    """What the CPU cycle tells the recordings (runtime/recorder.py)."""

    @property
    def active(self) -> bool: ...

    def before_programs(self, resource: Resource) -> None: ...

    def idle(self, resource: Resource) -> None:
        """A cycle in which no program runs (STOP, ERROR STOP)."""

    def cycled(
        self,
        resource: Resource,
        begin_ns: int,
        before: list[tuple[str, Any]],
        after: list[tuple[str, Any]],
    ) -> None: ...

    def logged(self, hit: LoggedHit) -> None:
        """A logpoint hit the debugger logged, inside a program."""


class Resource:
    # slots: the CPU cycle in C reads them at their offsets (padt_cycle.c)
    __slots__ = (
        "_boot_ns",
        "_core",
        "_first_cycle",
        "_last_start_ns",
        "access",
        "artifact",
        "clock",
        "cycle_count",
        "debugger",
        "error",
        "events",
        "field_io",
        "forcing",
        "host",
        "identity",
        "incoming",
        "io",
        "last_start",
        "login_audit",
        "name",
        "native",
        "online",
        "params",
        "recorder",
        "recordings",
        "scheduler",
        "setup",
        "start_kind",
        "state",
        "stats",
        "store",
        "system",
        "variables",
        "zenoh_id",
    )

    def __init__(
        self,
        name: str,
        clock: Clock,
        events: EventLog | None = None,
        identity: Identity | None = None,
    ) -> None:
        self.name = name
        self.clock = clock
        self.events = events if events is not None else EventLog(clock.wall_ns, shares=SHARES)
        self.recorder = EventRecorder(self.events)
        self.state = ResourceState.STOP_INVALID
        self.error: str | None = None  # why the resource is in ERROR STOP
        self.artifact: Artifact | None = None
        self.params = ResourceConfig(name=name)  # the loaded ones, with online changes
        self.stats = CycleStats()
        self.cycle_count = 0  # CPU cycles that ran, single steps included
        self.system = SystemView()
        self.variables = Variables(name)
        self.io = ProcessImage(self.variables)
        self.forcing = Forcing(self, self.variables, self.recorder, clock)
        self.online = OnlineValues(self.variables)
        self.scheduler = Scheduler(self, self.variables, self.recorder, clock)
        self.debugger = Debugger()  # breakpoints, BKPT, steps (runtime/debugging)
        # the key its publications are signed with (made fresh when none is given)
        self.identity = identity if identity is not None else Identity.fresh()
        self.access = AccessControl((), clock.now_ns, realm=name)  # the loaded accounts
        self.login_audit = LoginAudit()
        # until the first configuration, in a runtime process: its only account is `setup`
        self.setup: SetupSecret | None = None
        self.incoming = IncomingArtifact()  # a configuration arriving for load or reload
        # where it runs, as its status tells (runtime/main.py sets them in a process)
        self.host: str | None = None
        self.zenoh_id: str | None = None
        self.start_kind: str | None = "cold"  # what the next first cycle is: cold | warm
        self.last_start = ""  # how the resource last started: cold | warm | continued
        self._first_cycle = False  # the next CPU cycle is the first after a start
        self._last_start_ns: int | None = None
        self._boot_ns = clock.now_ns()
        # where every new configuration (load or reload) is kept for the next power-up
        self.store: ConfigurationStore | None = None
        self.field_io: FieldIo | None = None  # the field I/O drivers, in a runtime process
        # the recordings (runtime/recorder.py), in a runtime process with a state folder
        self.recordings: CycleRecorder | None = None
        # the native tier (runtime/code/native/), when the runtime was started with it
        self.native: NativeTier | None = None
        # the usual CPU cycle in C, once the native tier has put code in place
        self._core: CycleCore | None = None

    @property
    def programs(self) -> list[UserProgram]:
        return self.variables.programs

    @property
    def cycle_ns(self) -> int:
        """The interval a single step advances time by: the target cycle time, or the
        mean CPU cycle so far when there is none (at least 1 ms)."""
        if self.params.target_cycle_ms:
            return self.params.target_cycle_ms * 1_000_000
        return max(1_000_000, self.stats.mean_ns)

    def running(self) -> bool:
        return self.state in _RUNNING

    def commission(self, setup: SetupSecret) -> None:
        """No configuration yet: nobody but the holder of the setup secret, logged in as
        `setup`, may act (runtime/commissioning.py)."""
        self.setup = setup
        self.access.replace_users((setup.account(),))

    def begin_login(self, name: str, client_nonce: str, source: str) -> Challenge:
        """The challenge of a login (runtime/contract/scram.py)."""
        try:
            known = any(account.name == name for account in self.access.users)
            if known and not self.login_audit.may_begin(name, self.clock.now_ns()):
                raise Refusal("busy", f"too many logins of '{name}' at once: try again shortly")
            return self.access.begin(name, client_nonce, source)
        except Refusal as denied:
            self._login_refused(name, source, denied)
            raise

    def finish_login(self, name: str, nonce: str, proof: bytes, source: str) -> Proven:
        """A session for a proof that holds. Failed logins are short-term events,
        aggregated per name and interval with the sources they claimed (`login_audit.py`)."""
        try:
            proven = self.access.finish(name, nonce, proof, self.identity.public_key, source)
        except Refusal as denied:
            self._login_refused(name, source, denied)
            raise
        earlier = self.login_audit.succeeded(name)
        if earlier.earlier:
            message = f"login of '{name}' refused{_more(earlier.earlier)}"
            self.recorder.record(
                "login", message, name, long_term=False, source=source, sources=earlier.sources
            )
        logins = self.login_audit.logged_in(name, self.clock.now_ns())
        if logins is not None:
            message = f"{name} logged in ({proven.session.level}){_logins(logins)}"
            counted = {"logins": logins} if logins else {}
            self.recorder.record("login", message, name, None, **counted)
        self._bound_sessions(name)
        return proven

    def _bound_sessions(self, name: str) -> None:
        """At most MAX_SESSIONS_PER_ACCOUNT sessions of one account: its oldest end, so
        that a flood of logins holds no memory for the 8 hours a session lasts."""
        sessions = self.access.sessions
        tokens = [token for token, session in sessions.items() if session.user == name]
        for token in tokens[:-MAX_SESSIONS_PER_ACCOUNT]:
            del sessions[token]

    def _login_refused(self, name: str, source: str, denied: Refusal) -> None:
        failures = self.login_audit.failed(name, source, self.clock.now_ns())
        if failures is not None:
            message = f"login of '{name}' refused: {denied.message}{_more(failures.earlier)}"
            # the sources are what the requests claimed (login_audit.py)
            self.recorder.record(
                "login", message, name, long_term=False, source=source, sources=failures.sources
            )

    def reset_stats(self) -> None:
        self.stats = CycleStats()
        self._last_start_ns = None
        self.recorder.record("stats", "cycle statistics reset")

    # ---- configurations
    def refused(self, what: str, message: str, new_crc: str | None = None) -> None:
        """A load or reload that did not happen is an event too, with both CRCs."""
        old_crc = self.artifact.crc if self.artifact else None
        self.recorder.record(what, f"{what} refused: {message}", old_crc=old_crc, new_crc=new_crc)

    def transferred(self, what: str) -> Artifact:
        """The artifact the transfer brought; a failed transfer is a refused load / reload."""
        try:
            return self.incoming.complete()
        except Refusal as refusal:
            self.refused(what, refusal.message)
            raise

    def load(self, artifact: Artifact) -> None:
        """Take a whole configuration (only in STOP); a cold start state follows."""
        try:
            if self.running():
                raise Refusal("state", "a download is only possible in STOP")
            if self.state == ResourceState.ERROR_STOP:
                raise Refusal("state", "ERROR STOP: INIT first")
            if self.artifact is not None and not self.params.load_allowed:
                raise Refusal("not_allowed", "Load Allowed is OFF")
            # everything that can fail before anything changes: the code, then the disk
            instances = instantiated(artifact, self.system, self.native)
            staged = self.store.stage(artifact) if self.store is not None else None
        except Refusal as refused:
            self.refused("load", refused.message, artifact.crc)
            raise
        old_crc = self.artifact.crc if self.artifact else None
        self.forcing.reset()
        self.take(artifact, instances)
        self.state = ResourceState.STOP_VALID
        self.start_kind = "cold"
        self.io.write_outputs(safe=True)
        if staged is not None and not staged.commit():
            self.recorder.record("error", "the loaded configuration could not be kept for power-up")
        self.recorder.record(
            "load",
            f"configuration {artifact.project} loaded, CRC {artifact.crc} (cold start)",
            old_crc=old_crc,
            new_crc=artifact.crc,
        )

    def take(self, artifact: Artifact, instances: Instances) -> None:
        """A new configuration (download or reload) with its instances: parameters, safe
        values, accounts and the system variables that describe it follow it."""
        self.debugger.forget(self)
        self.variables.adopt(instances)
        self.debugger.rearm(self)  # the breakpoints by file and line, in the new code
        self.variables.access = {a.name.upper(): a for a in artifact.access_paths}
        self.artifact, self.params = artifact, artifact.resource
        self.io.configure(artifact)
        if self.setup is not None:  # the first configuration: the setup account and its
            self.setup.spend()  # session end, whatever accounts the configuration brings
            self.setup = None
            self.access.replace_users(())
        self.access.replace_users(artifact.users)  # sessions of removed accounts end
        self.system.CONFIGURATION_CRC = int(artifact.crc, 16)
        self.system.WATCHDOG_TIME = self.scheduler.watchdog_ns

    def tier_up(self, wait: bool = False) -> None:
        """The native bodies of the running code in place once they are made (between two
        cycles; `wait`: until they are), with an event that says what runs as C; and the
        values moved into the memory image, or out of it, as the code's state wants
        (runtime/image_switch.py)."""
        code = self.variables.code
        report = code.tier_up(wait) if code is not None else None
        if report is not None:
            if self._core is None:
                self._core = self._cycle_core()
            self.recorder.record(
                "native",
                report.summary(cycle_in_c=self._core is not None),
                native=list(report.bodies),
                python=[f"{pou}: {reason}" for pou, reason in report.left],
            )
        if must_leave(self.variables):  # debugged: a sliced program's cycle has ended
            leave_image(self.variables)
        plan = may_enter(self.variables)
        if plan is not None and code is not None:
            try:
                enter_image(self.variables, plan)
            except (TypeError, ValueError, OverflowError) as refused:
                # a value no checked writer stores (a view refuses it): nothing moved, and
                # this code's values stay on objects
                code.image = None
                self.recorder.record("native", f"the variables stay on Python objects: {refused}")

    def _cycle_core(self) -> CycleCore | None:
        """The usual CPU cycle in C, where the native tier's job built it."""
        if self.native is None or not self.native.available:
            return None
        built = self.native.cycle_built
        if isinstance(built, str):
            self.recorder.record("native", f"the CPU cycle stays Python: {built}")
            return None
        return cycle_core(built, self)

    @property
    def native_report(self) -> NativeReport | None:
        """What of the running code runs as C, and why the rest does not (None: all of it
        runs as Python, the native tier not asked for, not available or not ready)."""
        code = self.variables.code
        return code.native if code is not None else None

    def instantiate(self) -> None:
        """Fresh instances of everything: every variable at its initial value."""
        assert self.artifact is not None
        self.debugger.forget(self)
        self.variables.adopt(instantiate(self.artifact, self.system, native=self.native))
        self.debugger.rearm(self)

    # ---- states
    def init(self) -> None:
        """INIT: leave ERROR STOP for STOP; the next start is a cold start."""
        if self.state != ResourceState.ERROR_STOP:
            raise Refusal("state", "INIT leaves ERROR STOP; the resource is not in it")
        self.state, self.error = ResourceState.STOP_VALID, None
        self.instantiate()
        self.start_kind = "cold"
        for name in EMERGENCY_STOPS:
            setattr(self.system, name, False)
        self.recorder.record("state", "INIT: ERROR STOP left for STOP (cold start next)")

    def cold_start(self) -> None:
        """Every variable to its initial value (in STOP); the next start is a cold start."""
        self.require_stop("a cold start")
        self.instantiate()
        self.start_kind = "cold"
        self.recorder.record("state", "cold start prepared: all variables at their initial values")

    def start(self) -> None:
        if self.state == ResourceState.STOP_INVALID:
            raise Refusal("state", "no valid configuration is loaded")
        if self.state == ResourceState.ERROR_STOP:
            raise Refusal("state", f"ERROR STOP ({self.error}): INIT first")
        if self.running():
            return
        if not self.params.start_allowed:
            raise Refusal("not_allowed", "Start Allowed is OFF")
        self.refuse_read_only("start")
        self.state = ResourceState.RUN
        self.forcing.end_all("resource start")
        for program in self.programs:
            if program.state == ProgramState.STOP and program.config.start_allowed:
                if program.held:  # stopped before the power failure: stays stopped
                    continue
                program.state = ProgramState.RUN
            program.last_start_ns = None
        self._first_cycle = True
        self._last_start_ns = None
        self.last_start = self.start_kind or "continued"
        self.recorder.record("start", f"resource started ({self.start_kind or 'continuing'})")

    def stop(self, reason: str = "stop command") -> None:
        if not self.running():
            return
        if reason == "stop command":
            self.refuse_read_only("stop")
        self.state = ResourceState.STOP_VALID
        self._halt_programs()
        self.forcing.end_all("resource stop")
        self.io.write_outputs(safe=True)
        self.recorder.record("stop", f"resource stopped ({reason})")

    def error_stop(self, cause: str) -> None:
        """ERROR STOP: programs halted, outputs safe at once; only INIT leaves it."""
        self.state, self.error = ResourceState.ERROR_STOP, cause
        self._halt_programs()
        self.forcing.table.stop_all()
        self.io.write_outputs(safe=True)
        self.recorder.record("error", f"ERROR STOP: {cause}", long_term=True)
        log.error("resource %s: ERROR STOP, %s", self.name, cause)

    def _halt_programs(self) -> None:
        self.debugger.forget(self)  # a program in BKPT stops with the others
        for program in self.programs:
            program.abandon()
            if program.state in (ProgramState.RUN, ProgramState.RUN_FREEZE, ProgramState.BKPT):
                program.state = ProgramState.STOP

    def emergency_stopped(self) -> bool:
        """ERROR STOP for the first Emergency Stop switch that is on (the scheduler asks
        only when one is: `emergency_switches`)."""
        for number, name in enumerate(EMERGENCY_STOPS, 1):
            if getattr(self.system, name) and self.state != ResourceState.ERROR_STOP:
                self.error_stop(f"Emergency Stop {number} set")
                return True
        return False

    @property
    def shown_state(self) -> ResourceState:
        """RUN/UP STOP when the resource runs but none of its programs does (one held by
        single step or at a breakpoint counts as running)."""
        if self.state == ResourceState.RUN and not any(
            p.state in (ProgramState.RUN, ProgramState.RUN_FREEZE, ProgramState.BKPT)
            for p in self.programs
        ):
            return ResourceState.RUN_UP_STOP
        return self.state

    def require_stop(self, what: str) -> None:
        if self.state != ResourceState.STOP_VALID:
            raise Refusal("state", f"{what} is only possible in STOP")

    def refuse_read_only(self, what: str) -> None:
        if self.state == ResourceState.RUN and self.system.READ_ONLY_IN_RUN:
            raise Refusal("read_only", f"Read-only in RUN is ON: no {what}")

    # ---- the CPU cycle
    def cycle(self) -> None:
        """One CPU cycle; in STOP only inputs are read (outputs stay safe). Written out for
        the usual cycle, whose every Python call is a fiftieth of an empty one: what it
        does not need (inputs from the I/O, outputs, forcing, recording, debugging, the tap
        of outside stores) costs a test each."""
        core = self._core
        if core is not None and core.cycle():  # a usual cycle, in C (cycle_core.py)
            return
        clock, stats, recordings, io = self.clock, self.stats, self.recordings, self.io
        begin = clock.now_ns()
        if io.delivered:  # inputs from the I/O since the last cycle (none without I/O)
            io.read_inputs()
        recording = recordings is not None and recordings.active
        if self.state not in _RUNNING:
            if recording:
                assert recordings is not None
                recordings.idle(self)
            return
        last_start = self._last_start_ns
        if last_start is not None:
            stats.record_period(begin - last_start, self.params.target_cycle_ms * 1_000_000)
        self._last_start_ns = begin
        # the system variables the programs read in this cycle
        system, first = self.system, self._first_cycle
        if first or system.START_CYCLE:  # set in a start's first cycle, cleared in its second
            system.START_CYCLE = first
            system.COLDSTART = first and self.start_kind == "cold"
            system.WARMSTART = first and self.start_kind == "warm"
        system.CYCLE_TIME_LAST = stats.last_ns
        system.CYCLE_TIME_MIN = stats.min_ns
        system.CYCLE_TIME_MAX = stats.max_ns
        system.CYCLE_TIME_MEAN = stats.mean_ns
        system.SYSTEM_TICK = ((begin - self._boot_ns) // 1_000_000) & 0xFFFFFFFF
        system.DATE_AND_TIME = clock.wall_ns()
        forcing = self.forcing
        if forcing.table.levels:  # forcing started: time limits, values in force
            system.FORCE_TIME_REMAINING = forcing.table.remaining_ns(GLOBAL, begin) or 0
            self._react_to_force_timeouts(begin)
            forcing.apply()
        else:
            system.FORCE_TIME_REMAINING = 0
        if self.debugger.active:  # a silent debugging client: the program continues
            self.debugger.watch(self, begin)
        variables = self.variables
        tapped = variables.tap is not None  # stores from outside, for a recording
        before = variables.tapped() if tapped else []
        if recording:
            assert recordings is not None
            recordings.before_programs(self)
        if not self.run_programs(begin):
            return
        after = variables.tapped() if tapped else []
        if variables.outputs or io.outputs:  # an output image to write
            io.write_outputs(safe=False)
        if self._first_cycle:
            self._first_cycle = False
            self.start_kind = None
        self.cycle_count += 1
        if clock.virtual:  # what the programs used, counted in loop passes
            stats.record(self.scheduler.used_ns)
        else:
            stats.record(clock.now_ns() - begin)
        if recordings is not None and recordings.active:
            recordings.cycled(self, begin, before, after)

    def run_programs(self, begin: int) -> bool:
        """The user programs of a CPU cycle and what follows them up to the outputs (an
        exact replay runs just this, its inputs taken from a recording). False when the
        resource halted."""
        finished: list[UserProgram] = []
        if not self.scheduler.run(begin, finished):
            return False
        self.variables.publish(finished)
        if self.system.FORCE_DEACTIVATION or self.forcing.deactivated:  # ON, or just OFF
            self.forcing.check_deactivation()
        if self.forcing.table.levels:
            self.forcing.apply()
        return True

    def step(self) -> None:
        """In STOP: one CPU cycle of every program, time advancing one interval."""
        if self.state != ResourceState.STOP_VALID:
            raise Refusal("state", "single step of the resource needs it in STOP")
        runnable = [p for p in self.programs if p.state != ProgramState.ERROR]

        def run_all() -> None:
            for program in runnable:
                self.scheduler.run_to_end(program, self.cycle_ns)

        self.scheduler.guarded(run_all)
        self.variables.publish(runnable)
        self.cycle_count += 1
        self.recorder.record(
            "state", f"resource stepped one cycle in STOP (cycle {self.cycle_count})"
        )

    def _react_to_force_timeouts(self, now: int) -> None:
        """Force time limits: stop forcing, or stop the resource / program."""
        for level in self.forcing.expire(now):
            if level == GLOBAL:
                reaction = self.params.global_force_timeout_reaction
                self.recorder.record(
                    "force", f"global force time expired: {reaction}", long_term=True
                )
                if reaction == "stop-resource":
                    self.stop(reason="global force time expired")
            else:
                program = self.variables.program(level)
                reaction = program.config.local_force_timeout_reaction
                self.recorder.record(
                    "force", f"force time of {level} expired: {reaction}", long_term=True
                )
                if reaction == "stop-program":
                    program.abandon()
                    program.state = ProgramState.STOP

    def status(self) -> Status:
        return Status(
            resource=self.name,
            state=self.shown_state,
            crc=self.artifact.crc if self.artifact else None,
            error=self.error,
            project=self.artifact.project if self.artifact else None,
            cycle=self.cycle_count,
            cycle_ms=self.cycle_ns / 1e6,
            stats=self.stats.info(),
            forcing=self.forcing.table.started_levels() != [],
            access="setup" if self.setup else "open" if self.access.open else "users",
            start=self.start_kind if self.state == ResourceState.STOP_VALID else self.last_start,
            programs=[
                ProgramStatus(
                    name=p.name,
                    id=p.config.program_id,
                    priority=p.config.priority,
                    state=p.state,
                    crc=p.config.crc,
                    cycles=p.stats.count,
                    cpu_cycles_max=p.stats.max_cpu_cycles,
                    error=p.error,
                    paused_at=self.debugger.where(p),
                )
                for p in self.programs
            ],
            io=self.field_io.status() if self.field_io is not None else None,
            host=self.host,
            zenoh_id=self.zenoh_id,
        )


def _more(count: int) -> str:
    return f" ({count} more refused since the last report)" if count else ""


def _logins(count: int) -> str:
    return f" ({count} more logins of this account since the last report)" if count else ""
