"""Reload benchmark, for a program with 10,000 variables: the time to compute the reload
plan, the switch-over pause inside the cycle, and the longest cycle during a reload versus
the normal cycle, as a ratio; the measured cost per carried value next to the estimate the
budget check uses (`SWITCH_NS_PER_VALUE`).

Run with `python -m tests.bench.bench_reload`. It prints figures and asserts nothing about
time (machines are shared and noisy).
"""

from __future__ import annotations

import statistics
import threading
import time
import traceback
from collections.abc import Callable
from dataclasses import dataclass, field

from backend.compiler.pipeline import compile_sources
from backend.compiler.source import SourceFile
from runtime import reload_switch
from runtime.clock import RealClock
from runtime.contract.artifact import Artifact, ResourceConfig
from runtime.contract.parameters import RESOURCE_BY_NAME
from runtime.contract.protocol import ProgramState, ReloadOutcome, ResourceState
from runtime.contract.refusal import Refusal
from runtime.instances import instantiate
from runtime.intrinsics import SystemView
from runtime.reload_plan import (
    CONVERTED,
    DELETED,
    INITIALISED,
    KEPT,
    NEW,
    SWITCH_NS_PER_VALUE,
    ReloadPlan,
    plan_reload,
)
from runtime.resource import Resource
from tests.bench.bench_runtime import mean_and_best_ms, ten_thousand_paths

PLAN_ROUNDS = 5
RELOADS = 10  # alternating old -> new -> old ...
CYCLES_BETWEEN = 40  # normal CPU cycles before each reload
WARMUP_CYCLES = 20
FIXED_TARGET_MS = 10  # the jitter benchmark's target cycle, for the budget check
# the refusals a higher watchdog (or target cycle time) for the reload can overcome
BUDGET_CODES = ("budget", "interrupted")

# the "new" version: one more variable, one statement changed; everything else is kept
OLD_DECLARATION = "  i : DINT;"
NEW_DECLARATION = "  i : DINT;\n  added : DINT := 7;"
OLD_STATEMENT = "points[i].name := 'p';"
NEW_STATEMENT = "points[i].name := 'q';"


def versions() -> tuple[str, str]:
    """The 10,000-variable program of the runtime benchmark, and a slightly changed copy."""
    old = ten_thousand_paths()
    for anchor in (OLD_DECLARATION, OLD_STATEMENT):
        if old.count(anchor) != 1:
            raise RuntimeError(f"ten_thousand_paths() no longer has one {anchor!r}")
    new = old.replace(OLD_DECLARATION, NEW_DECLARATION).replace(OLD_STATEMENT, NEW_STATEMENT)
    return old, new


def _compile(text: str, config: ResourceConfig) -> Artifact:
    result = compile_sources([SourceFile("bench.st", text)], resource=config)
    assert result.artifact is not None, [str(d) for d in result.diagnostics]
    return result.artifact


def _pair(config: ResourceConfig) -> tuple[Artifact, Artifact]:
    old, new = versions()
    return _compile(old, config), _compile(new, config)


def _running(artifact: Artifact) -> Resource:
    resource = Resource("R", RealClock())
    resource.load(artifact)
    resource.start()
    for _ in range(WARMUP_CYCLES):
        resource.cycle()
    return resource


def _summary(plan: ReloadPlan) -> str:
    counts = ", ".join(f"{a} {plan.count(a):,}" for a in (KEPT, CONVERTED, INITIALISED, NEW))
    return f"{counts}, {DELETED} {plan.count(DELETED):,}"


def _raised_ms(params: ResourceConfig) -> int:
    """The most a reload may be given: the watchdog's upper limit, within half the safety
    time (the consistency rule of the resource parameters)."""
    high = RESOURCE_BY_NAME["watchdog_ms"].high
    return min(high if high is not None else 7_500, params.safety_time_ms // 2)


# ---- 1. the plan ------------------------------------------------------------------------------


def bench_plan(old: Artifact, new: Artifact, rounds: int = PLAN_ROUNDS) -> None:
    plan = plan_reload(old, new)
    print(
        f"1. reload plan, {len(plan.changes):,} variable changes "
        f"(CRC {old.crc} -> {new.crc}), {rounds} runs each:"
    )
    mean, best = mean_and_best_ms(lambda: plan_reload(old, new), rounds)
    print(f"  plan_reload (no live state):      mean {mean:7.1f} ms   best {best:7.1f} ms")
    resource = _running(old)
    mean, best = mean_and_best_ms(lambda: reload_switch.preview(resource, new, {}), rounds)
    print(f"  reload_switch.preview (live):     mean {mean:7.1f} ms   best {best:7.1f} ms")
    # what Resource.reload does after the plan and before the switch-over, also outside
    # the pause but inside the same call (the driver's housekeeping between two cycles)
    mean, best = mean_and_best_ms(lambda: instantiate(new, SystemView()), rounds)
    print(f"  new instances (before the pause): mean {mean:7.1f} ms   best {best:7.1f} ms")
    print(f"  summary: {_summary(plan)}")
    print(
        f"  programs changed {list(plan.programs_changed)}, added {list(plan.programs_added)}, "
        f"removed {list(plan.programs_removed)}; hazards {len(plan.hazards)}; "
        f"possible {plan.possible}"
    )
    print(
        f"  estimated switch-over: {plan.estimate_ns / 1e3:,.0f} us "
        f"({SWITCH_NS_PER_VALUE:,} ns x {plan.count(KEPT) + plan.count(CONVERTED):,} values)"
    )


# ---- 2-4. the switch-over inside a running cycle loop -----------------------------------------


@dataclass
class Run:
    """What a loop of CPU cycles with reloads between them saw."""

    starts_ns: list[int] = field(default_factory=list)  # when each cycle() began
    work_ns: list[int] = field(default_factory=list)  # time inside each cycle()
    reload_after: dict[int, int] = field(default_factory=dict)  # cycle index -> reload index
    pauses_us: list[float] = field(default_factory=list)  # Resource.reload's pause_us
    carried: list[int] = field(default_factory=list)
    calls_ns: list[int] = field(default_factory=list)  # request to switch-over done
    refusals: list[str] = field(default_factory=list)  # with the default parameters

    def cycle(self, resource: Resource) -> None:
        started = time.perf_counter_ns()
        self.starts_ns.append(started)
        resource.cycle()
        self.work_ns.append(time.perf_counter_ns() - started)


class Reloader:
    """Resource.reload with the configured parameters first; when the budget refuses,
    once more (and from then on) with the watchdog (and target cycle) raised for it."""

    def __init__(self, resource: Resource) -> None:
        self.resource = resource
        self.watchdog_ms: int | None = None  # raised for the reload, once refused
        self.target_cycle_ms: int | None = None
        self.refusal: str | None = None  # the first refusal with the default parameters

    def raised(self) -> str:
        return f"watchdog_ms={self.watchdog_ms}, target_cycle_ms={self.target_cycle_ms}"

    def __call__(self, artifact: Artifact, keep_cycling: Callable[[], None]) -> ReloadOutcome:
        """As the runtime process reloads: the job prepares on a worker thread while the
        cycles go on, and switches over between two cycles."""
        if self.refusal is None:
            try:
                return self._reload(artifact, keep_cycling)
            except Refusal as refused:
                if refused.code not in BUDGET_CODES:
                    raise
                self.refusal = f"[{refused.code}] {refused.message}"
                params = self.resource.params
                self.watchdog_ms = _raised_ms(params)
                if params.target_cycle_ms and params.target_cycle_mode in ("fixed", "dynamic"):
                    self.target_cycle_ms = self.watchdog_ms
        return self._reload(artifact, keep_cycling)

    def _reload(self, artifact: Artifact, keep_cycling: Callable[[], None]) -> ReloadOutcome:
        job = reload_switch.begin(
            self.resource,
            artifact,
            {},
            watchdog_ms=self.watchdog_ms,
            target_cycle_ms=self.target_cycle_ms,
        )
        worker = threading.Thread(target=job.prepare)
        worker.start()
        while worker.is_alive():
            keep_cycling()
        worker.join()
        return reload_switch.finish(self.resource, job)


def drive(old: Artifact, new: Artifact, reloads: int = RELOADS) -> tuple[Run, Reloader]:
    """Cycles back to back on a RealClock, as the driver runs a resource without a target
    cycle time; after every CYCLES_BETWEEN cycles a reload, between two cycles as the driver
    does it in its housekeeping."""
    resource = _running(old)
    reloader = Reloader(resource)
    run = Run()
    for n in range(reloads):
        for _ in range(CYCLES_BETWEEN):
            run.cycle(resource)
        started = time.perf_counter_ns()
        outcome = reloader(new if n % 2 == 0 else old, lambda: run.cycle(resource))
        run.calls_ns.append(time.perf_counter_ns() - started)
        run.reload_after[len(run.starts_ns) - 1] = n
        run.pauses_us.append(outcome.pause_us)
        run.carried.append(outcome.carried)
    for _ in range(CYCLES_BETWEEN):
        run.cycle(resource)
    if resource.state not in (ResourceState.RUN, ResourceState.RUN_UP_STOP):
        print(f"  WARNING: resource in {resource.state} ({resource.error}) after the run")
    for program in resource.programs:
        if program.state != ProgramState.RUN:
            print(f"  WARNING: program {program.name} is {program.state}: {program.error}")
    return run, reloader


def _ms(ns: float) -> str:
    return f"{ns / 1e6:8.2f} ms"


def report_pause(run: Run, reloader: Reloader, config: ResourceConfig) -> None:
    print(
        f"2. switch-over pause (Resource.reload pause_us, RealClock), {len(run.pauses_us)} "
        f"reloads alternating old/new; resource watchdog {config.watchdog_ms} ms, "
        f"target cycle {config.target_cycle_ms} ms:"
    )
    if reloader.refusal is not None:
        print(f"  with the default parameters the reload was REFUSED: {reloader.refusal}")
        print(f"  -> reloaded with {reloader.raised()} for the reload")
    else:
        print("  accepted with the default parameters (no raise needed)")
    pauses = run.pauses_us
    low, high = min(run.carried), max(run.carried)
    carried = f"{low:,}" if low == high else f"{low:,}-{high:,}"
    print(
        f"  pause: mean {statistics.fmean(pauses):9.1f} us   max {max(pauses):9.1f} us   "
        f"min {min(pauses):9.1f} us   ({carried} values carried each)"
    )
    calls = run.calls_ns
    print(
        f"  request to done (prepared on a worker thread while cycles ran): mean "
        f"{_ms(statistics.fmean(calls))}   max {_ms(max(calls))}"
    )


def report_cycles(run: Run) -> None:
    periods = [b - a for a, b in zip(run.starts_ns, run.starts_ns[1:], strict=False)]
    with_reload = [periods[i] for i in sorted(run.reload_after)]
    after = {i + 1 for i in run.reload_after}  # the first cycle on the new instances
    normal = [p for i, p in enumerate(periods) if i not in run.reload_after and i not in after]
    normal_period = statistics.median(normal)
    normal_work = statistics.median(
        w for i, w in enumerate(run.work_ns) if i not in run.reload_after and i not in after
    )
    first_work = [run.work_ns[i] for i in sorted(after)]
    switch_only = max(run.work_ns[i] + run.pauses_us[n] * 1e3 for i, n in run.reload_after.items())
    print(
        f"3. longest cycle during a reload vs the normal cycle (cycles back to back, "
        f"{len(periods):,} periods, {len(with_reload)} with a reload):"
    )
    print(f"  normal period (median):                       {_ms(normal_period)}")
    print(
        f"  period containing the reload (longest):       {_ms(max(with_reload))}   "
        f"ratio {max(with_reload) / normal_period:7.1f}   (mean "
        f"{_ms(statistics.fmean(with_reload))})"
    )
    print(
        f"  cycle work + switch-over pause only (longest): {_ms(switch_only)}   "
        f"ratio {switch_only / normal_period:7.1f}"
    )
    print(
        f"  first cycle on the new instances (longest):   {_ms(max(first_work))}   "
        f"vs median cycle work {_ms(normal_work)}"
    )


def report_per_value(run: Run, old: Artifact, new: Artifact) -> None:
    per_value = [p * 1e3 / c for p, c in zip(run.pauses_us, run.carried, strict=True) if c]
    estimate = plan_reload(old, new).estimate_ns
    print("4. switch-over cost per carried value (pause / carried):")
    print(
        f"  measured: mean {statistics.fmean(per_value):7.0f} ns   max {max(per_value):7.0f} ns"
        f"   vs SWITCH_NS_PER_VALUE {SWITCH_NS_PER_VALUE:,} ns   (measured / constant, "
        f"max: {max(per_value) / SWITCH_NS_PER_VALUE:.2f})"
    )
    print(
        f"  plan estimate old -> new {estimate / 1e3:,.0f} us vs measured pause max "
        f"{max(run.pauses_us):,.0f} us"
    )


def bench_switch_over(old: Artifact, new: Artifact, config: ResourceConfig) -> None:
    run, reloader = drive(old, new)
    report_pause(run, reloader, config)
    report_cycles(run)
    report_per_value(run, old, new)


# ---- the budget check with a target cycle time ------------------------------------------------


def _attempt(
    resource: Resource,
    artifact: Artifact,
    watchdog_ms: int | None = None,
    target_cycle_ms: int | None = None,
) -> str:
    try:
        outcome = reload_switch.reload(
            resource, artifact, {}, watchdog_ms=watchdog_ms, target_cycle_ms=target_cycle_ms
        )
    except Refusal as refused:
        return f"REFUSED [{refused.code}] {refused.message}"
    return f"done, pause {outcome.pause_us:,.0f} us, {outcome.carried:,} values carried"


def bench_budget(config: ResourceConfig) -> None:
    """With a target cycle in the 'fixed' mode the budget is what the target cycle leaves
    after the last cycle: the reload needs a raised target cycle time, not only a raised
    watchdog."""
    old, new = _pair(config)
    resource = _running(old)
    raised = _raised_ms(resource.params)
    print(
        f"budget check, target cycle {config.target_cycle_ms} ms '{config.target_cycle_mode}', "
        f"watchdog {config.watchdog_ms} ms (last cycle "
        f"{resource.stats.last_ns / 1e6:.2f} ms, estimate "
        f"{reload_switch.preview(resource, new, {}).estimate_ns / 1e3:,.0f} us):"
    )
    for label, watchdog_ms, target_cycle_ms in (
        ("default parameters", None, None),
        (f"watchdog_ms={raised}", raised, None),
        (f"watchdog_ms={raised}, target_cycle_ms={raised}", raised, raised),
    ):
        running = resource.artifact.crc if resource.artifact is not None else None
        artifact = new if running == old.crc else old
        outcome = _attempt(resource, artifact, watchdog_ms, target_cycle_ms)
        print(f"  {label + ':':<42} {outcome}")


# ---- entry point -------------------------------------------------------------------------------


def _section(work: Callable[[], None]) -> None:
    """A section that fails (a defect of the runtime) is reported, and the others run."""
    try:
        work()
    except Exception:
        print("  FAILED, the runtime raised:")
        traceback.print_exc()


def main() -> None:
    config = ResourceConfig(name="R")  # the defaults: watchdog 200 ms, no target cycle
    started = time.perf_counter()
    old, new = _pair(config)
    print(
        f"reload benchmark: {len(_running(old).variables.values()):,} variables "
        f"(compiled twice in {time.perf_counter() - started:.1f} s)"
    )
    _section(lambda: bench_plan(old, new))
    _section(lambda: bench_switch_over(old, new, config))
    fixed = ResourceConfig(name="R", target_cycle_ms=FIXED_TARGET_MS, target_cycle_mode="fixed")
    _section(lambda: bench_budget(fixed))


if __name__ == "__main__":
    main()
