"""A reload (online change, spec section 9) on its way through the resource: checked at
once, prepared where it may take long (new instances, the plan, the list of values to
move; on a worker thread in the runtime process, while cycles go on), switched over
between two cycles, all or nothing, within the time the cycle leaves."""

from __future__ import annotations

import time
import weakref
from dataclasses import replace

from runtime.code.code_image import reusing
from runtime.code.compile_worker import COMPILE_WORKER
from runtime.code.instances import Instances, instantiate
from runtime.code.intrinsics import SystemView
from runtime.code.native.tier import NativeTier
from runtime.collector import COLLECTOR
from runtime.configuration_store import ConfigurationStore, Staged
from runtime.contract.artifact import Artifact
from runtime.contract.protocol import ProgramState, ReloadOutcome
from runtime.contract.refusal import Refusal
from runtime.disposal import DISPOSAL
from runtime.image_switch import leave_image
from runtime.reload import (
    SwitchOver,
    SwitchOverTooLong,
    live_state,
    prepare_switch_over,
    switch_over,
)
from runtime.reload_plan import LiveState, ReloadPlan, plan_reload
from runtime.resource import Resource


class ReloadJob:
    """Made by `begin` or `begin_preview`; `prepare` touches nothing of the running
    configuration, so it may run on another thread; `finish` switches between cycles."""

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
        self.old, self.old_artifact, self.system = old, old_artifact, system
        self.live = live
        self.watchdog_ms: int | None = None
        self.target_cycle_ms: int | None = None
        self.user: str | None = None
        self.instances: Instances | None = None
        self.plan: ReloadPlan | None = None
        self.prepared: SwitchOver | None = None
        self.failure: Refusal | None = None  # why preparing failed
        self.preview = False  # only the plan is wanted
        self.expected_crc: str | None = None  # the configuration the user previewed against
        self.store: ConfigurationStore | None = None  # where a reload that happens is kept
        self.staged: Staged | None = None
        self.native: NativeTier | None = None  # the resource's native tier, if it has one

    def let_go(self) -> list[object]:
        """What is left once the job is done, taken out of it: the replaced configuration
        (a preview's new one, never taken), the switch-over list, the old charts' state."""
        held: list[object] = [self.old, self.prepared, self.live]
        if self.preview:
            held.append(self.instances)
            self.instances = None
        del self.old, self.live
        self.prepared = None
        return held

    def prepare(self) -> None:
        """New instances, the plan, the switch-over list, and the new configuration written
        beside the stored one (off the cycle thread); never raises. No collection runs
        meanwhile, and what the switch-over takes is frozen before it (runtime/collector.py)."""
        with COLLECTOR.held_back():
            self._prepare()

    def _prepare(self) -> None:
        try:
            # the units that changed compiled in the worker process (a compile holds the
            # interpreter lock the cycle thread needs for as long as it runs), the others
            # the running code
            compile_units = reusing(self.old.image, COMPILE_WORKER.compile)
            self.instances = instantiate(
                self.artifact, self.system, compile_units, native=self.native
            )
            # native from the first cycle on: the classes are not running yet
            self.instances.image.tier_up(wait=True)
            self.plan = plan_reload(
                self.old_artifact,
                self.artifact,
                self.renames,
                self.live,
                [b.path for b in self.old.bound],
                [b.path for b in self.instances.bound],
            )
            if not self.plan.refusals:
                self.prepared = prepare_switch_over(
                    self.old, self.instances, self.plan, self.renames
                )
                # what this switch-over costs, knowing which objects are adopted; a reload
                # needs no change per variable any more: they are freed here, on the worker
                # thread, rather than by the cycle thread after the switch-over
                changes = self.plan.changes if self.preview else ()
                self.plan = replace(
                    self.plan, estimate_ns=self.prepared.estimate_ns, changes=changes
                )
                if self.store is not None and not self.preview:
                    self.staged = self.store.stage(self.artifact)
        except Refusal as refused:  # the disk
            self.failure = refused
        except Exception as exc:  # generated code that fails while it is set up
            cause = f"{type(exc).__name__}: {exc}"
            self.failure = Refusal("reload_failed", f"the new configuration failed: {cause}")


def begin_preview(resource: Resource, artifact: Artifact, renames: dict[str, str]) -> ReloadJob:
    """A job that only plans (`prepare` may run on another thread)."""
    if resource.artifact is None:
        raise Refusal("state", "no configuration is loaded: use a download")
    job = _job(resource, artifact, renames)
    job.preview = True
    return job


def preview(resource: Resource, artifact: Artifact, renames: dict[str, str]) -> ReloadPlan:
    """The reload plan against the running state, in one go; changes nothing."""
    job = begin_preview(resource, artifact, renames)
    job.prepare()
    if job.plan is None:
        assert job.failure is not None
        raise job.failure
    return job.plan


def begin(
    resource: Resource,
    artifact: Artifact,
    renames: dict[str, str],
    watchdog_ms: int | None = None,
    target_cycle_ms: int | None = None,
    user: str | None = None,
    expected_crc: str | None = None,
) -> ReloadJob:
    """Check what can be checked at once; the job then prepares (anywhere)."""
    try:
        _check(resource)
        _budget(resource, watchdog_ms, target_cycle_ms)  # refuses a lowering now
    except Refusal as refused:
        resource.refused("reload", refused.message, artifact.crc)
        raise
    job = _job(resource, artifact, renames)
    job.watchdog_ms, job.target_cycle_ms, job.user = watchdog_ms, target_cycle_ms, user
    job.expected_crc, job.store = expected_crc, resource.store
    return job


def finish(resource: Resource, job: ReloadJob) -> ReloadOutcome:
    """The switch-over, between two cycles; refused if anything changed meanwhile."""
    try:
        return _switch(resource, job)
    except Refusal as refused:
        if job.staged is not None:
            job.staged.discard()
        resource.refused("reload", refused.message, job.artifact.crc)
        raise


def reload(
    resource: Resource,
    artifact: Artifact,
    renames: dict[str, str],
    watchdog_ms: int | None = None,
    target_cycle_ms: int | None = None,
) -> ReloadOutcome:
    """Replace the running configuration between two cycles, values carried over by name,
    in one go (the runtime process prepares on a worker thread instead)."""
    job = begin(
        resource, artifact, renames, watchdog_ms, target_cycle_ms, resource.recorder.acting_user
    )
    job.prepare()
    return finish(resource, job)


def _job(resource: Resource, artifact: Artifact, renames: dict[str, str]) -> ReloadJob:
    """A job against the running configuration and its live chart state."""
    assert resource.artifact is not None
    if resource.variables.image is not None:
        # the job plans against the objects (adoption): the values go back to them and
        # stay there while the job lives
        leave_image(resource.variables)
    old = resource.variables.instances()
    live = live_state(resource.artifact, old)
    job = ReloadJob(artifact, renames, old, resource.artifact, resource.system, live)
    job.native = resource.native
    resource.variables.image_held = weakref.ref(job)
    return job


def _check(resource: Resource) -> None:
    if resource.artifact is None:
        raise Refusal("state", "no configuration is loaded: use a download")
    if not resource.running():
        raise Refusal("state", "reload needs the resource running; in STOP, download")
    if not resource.params.reload_allowed:
        raise Refusal("not_allowed", "Reload Allowed is OFF")
    if resource.system.RELOAD_DEACTIVATION:
        raise Refusal("reload_deactivated", "Reload Deactivation is ON")
    resource.refuse_read_only("reload")
    resource.debugger.refuse_reload()


def _switch(resource: Resource, job: ReloadJob) -> ReloadOutcome:
    _check(resource)
    if job.expected_crc is not None and job.old_artifact.crc != job.expected_crc:
        raise Refusal(
            "changed", f"the resource runs {job.old_artifact.crc}, not {job.expected_crc}"
        )
    if job.failure is not None:
        raise job.failure
    plan, instances, prepared = job.plan, job.instances, job.prepared
    assert plan is not None and instances is not None
    if plan.refusals:
        raise Refusal("needs_download", "needs STOP and download: " + "; ".join(plan.refusals))
    assert prepared is not None
    if job.old.programs != resource.programs or resource.artifact is not job.old_artifact:
        raise Refusal("busy", "the configuration changed while the reload prepared")
    busy = [p.name for p in resource.programs if p.in_progress]
    if busy:
        raise Refusal("busy", f"program {busy[0]} is in the middle of its program cycle; try again")
    budget = _budget(resource, job.watchdog_ms, job.target_cycle_ms)
    if plan.estimate_ns > budget:
        raise Refusal(
            "budget",
            f"the switch-over needs about {plan.estimate_ns / 1000:.0f} us but the cycle "
            f"leaves {max(0, budget) / 1000:.0f} us: raise the watchdog (and in the fixed "
            "and dynamic modes the target cycle time) for the reload, or reload less at once",
        )
    begin_ns = time.perf_counter_ns()
    deadline = None if resource.clock.virtual else begin_ns + budget
    try:
        carried = switch_over(prepared, instances, deadline)
    except SwitchOverTooLong:
        raise Refusal(
            "interrupted",
            f"the switch-over took longer than the {budget / 1000:.0f} us the cycle leaves; "
            "the old configuration runs on",
        ) from None
    old_crc = job.old_artifact.crc
    running = resource.running()
    for program in instances.programs:
        if program.name in plan.programs_added:
            start = running and program.config.start_allowed
            program.state = ProgramState.RUN if start else ProgramState.STOP
    artifact = job.artifact
    resource.take(artifact, instances)
    resource.forcing.keep_after_reload(plan.programs_removed)
    pause_ns = time.perf_counter_ns() - begin_ns
    outcome = ReloadOutcome(old_crc, artifact.crc, pause_ns / 1000, carried)
    resource.recorder.record(
        "reload",
        f"reload done: {old_crc} -> {artifact.crc}, {carried} values carried over",
        job.user,
        old_crc=old_crc,
        new_crc=artifact.crc,
        pause_us=outcome.pause_us,
        carried=carried,
    )
    if job.staged is not None and not job.staged.commit():
        resource.recorder.record(
            "error", "the reloaded configuration could not be kept for power-up"
        )
    # taken apart between cycles (runtime/disposal.py): freed here in one go, 10,000
    # variables' worth took 2-3 ms
    DISPOSAL.dispose(job.let_go())
    return outcome


def _budget(resource: Resource, watchdog_ms: int | None, target_cycle_ms: int | None) -> int:
    """The time the switch-over may add to a cycle: what the watchdog leaves after the last
    cycle, and in the fixed and dynamic modes what the target cycle leaves."""
    params = resource.params
    for name, value, configured in (
        ("watchdog_ms", watchdog_ms, params.watchdog_ms),
        ("target_cycle_ms", target_cycle_ms, params.target_cycle_ms),
    ):
        if value is not None and value < configured:
            raise Refusal("bad_value", f"{name} for a reload may only raise it (now {configured})")
    watchdog = (watchdog_ms or params.watchdog_ms) * 1_000_000
    limit = watchdog
    target = (target_cycle_ms or params.target_cycle_ms) * 1_000_000
    if target and params.target_cycle_mode in ("fixed", "dynamic"):
        limit = min(limit, target)
    return limit - resource.stats.last_ns
