"""Reload benchmark, for a program with 10,000 variables: the time to compute the reload
plan, and for each kind of change the switch-over pause inside the cycle, the longest
cycle during a reload versus the normal cycle (a ratio; with cycles back to back, and at a
10 ms fixed target cycle), whether the budget check accepts the reload at a 10 ms fixed
target cycle with the default parameters, and the runtime's estimate next to the measured
pause. The kinds of change: one small POU's code; one small
POU gaining a variable (its instance and the program holding it are copied, the rest
adopted); the large program's code (every instance adopted, the code the cycle runs new);
every instance migrated (every type gains a variable: every value copied). The baselines
of the same run: the same switch-over with every value copied (what the runtime did before
it adopted objects, with today's grouped copying), the same without warming up the new
code (runtime/code/code_warmup.py), and the median cycle; then the same back to back with the
bodies as C, the runtime's default (runtime/code/native/). Last, the cycles after a reload
of one small POU in a program of 1,000 straight-line statements, whose code the reload
kept: copied and warmed up, against the running code kept as it was.

Run with `python -m tests.bench.bench_reload`. It prints figures and asserts nothing about
time (machines are shared and noisy).
"""

from __future__ import annotations

import statistics
import sys
import tempfile
import threading
import time
import traceback
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

from backend.compiler.pipeline import compile_sources
from backend.compiler.source import SourceFile
from runtime import reload as reload_module
from runtime import reload_switch
from runtime.adoption import Adopted, Adoption
from runtime.clock import RealClock, VirtualClock
from runtime.code import code_image, code_warmup
from runtime.code.instances import instantiate
from runtime.code.intrinsics import SystemView
from runtime.code.native.tier import NativeTier
from runtime.collector import COLLECTOR
from runtime.contract.artifact import Artifact, ResourceConfig
from runtime.contract.parameters import RESOURCE_BY_NAME
from runtime.contract.protocol import ProgramState, ReloadOutcome, ResourceState
from runtime.contract.refusal import Refusal
from runtime.cycle_driver import SWITCH_INTERVAL_S
from runtime.disposal import DISPOSAL, STEP_NS
from runtime.event_log import EventLog
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
from tests.bench.bench_language import thousand_statements
from tests.bench.bench_runtime import mean_and_best_ms, ten_thousand_paths

PLAN_ROUNDS = 5
RELOADS = 6  # alternating old -> new -> old ...
CYCLES_BETWEEN = 40  # normal CPU cycles before each reload
WARMUP_CYCLES = 20
FIXED_TARGET_MS = 10  # the jitter benchmark's target cycle, for the budget check
# the refusals a higher watchdog (or target cycle time) for the reload can overcome
BUDGET_CODES = ("budget", "interrupted")
CLOCK = RealClock()
DISPOSAL_STEP_US = STEP_NS / 1000

# a small function block inside the 10,000-variable program
SMALL = """FUNCTION_BLOCK Small
VAR_INPUT x : DINT; END_VAR
VAR_OUTPUT y : DINT; END_VAR
y := x * 2;
END_FUNCTION_BLOCK
"""
# (anchor in the program, what replaces it): the program with a Small instance
WITH_SMALL = (
    ("  i : DINT;", "  i : DINT;\n  small : Small;"),
    ("END_FOR;", "END_FOR;\nsmall(x := i);"),
)
# the kinds of change, each as edits of the program with a Small instance
CHANGES: dict[str, tuple[tuple[str, str], ...]] = {
    "one small POU's code": (("y := x * 2;", "y := x * 3;"),),
    "one small POU gains a variable": (
        ("y := x * 2;", "y := x * 3;"),
        ("VAR_OUTPUT y : DINT; END_VAR", "VAR_OUTPUT y : DINT; END_VAR VAR z : DINT; END_VAR"),
    ),
    # the program itself: the code a cycle spends its time in is new (and all instances kept)
    "the large program's code": (("points[i].name := 'p';", "points[i].name := 'q';"),),
    "every instance migrated": (
        ("name : STRING[16]; END_STRUCT", "name : STRING[16]; z : DINT; END_STRUCT"),
        ("VAR_GLOBAL points", "VAR_GLOBAL added : DINT; points"),
        ("  i : DINT;", "  i : DINT;\n  added : DINT := 7;"),
        ("points[i].name := 'p';", "points[i].name := 'q';"),
    ),
}


def _edited(text: str, edits: tuple[tuple[str, str], ...]) -> str:
    for anchor, replacement in edits:
        if text.count(anchor) != 1:
            raise RuntimeError(f"the benchmark program no longer has one {anchor!r}")
        text = text.replace(anchor, replacement)
    return text


def versions() -> dict[str, str]:
    """The 10,000-variable program of the runtime benchmark with a small FB in it (under
    "before"), and a changed copy per kind of change."""
    before = _edited(SMALL + ten_thousand_paths(), WITH_SMALL)
    return {"before": before} | {name: _edited(before, edits) for name, edits in CHANGES.items()}


def _compile(text: str, config: ResourceConfig) -> Artifact:
    result = compile_sources([SourceFile("bench.st", text)], resource=config)
    assert result.artifact is not None, [str(d) for d in result.diagnostics]
    return result.artifact


_FOLDER = tempfile.TemporaryDirectory(prefix="padt-bench-reload-")  # removed at exit
NATIVE = NativeTier(Path(_FOLDER.name) / "native")  # the compiled bodies, built once


def _event_log(clock: RealClock) -> EventLog:
    """A long-term event log on disk, written behind, as `padt runtime` keeps it: each
    reload records its outcome there from the cycle thread."""
    path = Path(tempfile.mkdtemp(dir=_FOLDER.name)) / "events.jsonl"
    return EventLog(clock.wall_ns, long_path=path, write_behind=True)


def _running(artifact: Artifact, native: NativeTier | None = None) -> Resource:
    """The resource as `padt runtime` runs it; with `native`, its bodies as C in place."""
    clock = RealClock()
    resource = Resource("R", clock, _event_log(clock))
    resource.native = native
    resource.load(artifact)
    resource.tier_up(wait=True)
    resource.start()
    for _ in range(WARMUP_CYCLES):
        resource.cycle()
    COLLECTOR.manage()  # as the runtime process does before its first cycle
    DISPOSAL.deferred = True  # as the cycle driver does while it runs
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
        f"  estimate without the running instances (every value copied): "
        f"{plan.estimate_ns / 1e3:,.0f} us "
        f"({SWITCH_NS_PER_VALUE:,} ns x {plan.count(KEPT) + plan.count(CONVERTED):,} values)"
    )


# ---- 2. the switch-over inside a running cycle loop, per kind of change -----------------------


@dataclass
class Run:
    """What a loop of CPU cycles with reloads between them saw."""

    starts_ns: list[int] = field(default_factory=list)  # when each cycle() began
    work_ns: list[int] = field(default_factory=list)  # time inside each cycle()
    reload_after: dict[int, int] = field(default_factory=dict)  # cycle index -> reload index
    pauses_us: list[float] = field(default_factory=list)  # the reload's pause_us
    carried: list[int] = field(default_factory=list)
    estimates_ns: list[int] = field(default_factory=list)  # the runtime's plan estimate
    copied: list[int] = field(default_factory=list)  # values copied (the rest adopted)
    preparing: set[int] = field(default_factory=set)  # cycles while a worker prepared
    disposing: set[int] = field(default_factory=set)  # cycles followed by a disposal step
    target_ns: int = 0  # a fixed target cycle: each cycle waits for its planned start
    planned_ns: int = 0

    def cycle(self, resource: Resource) -> None:
        if self.target_ns:  # what the previous period leaves, slept (after housekeeping)
            CLOCK.sleep_until(self.planned_ns)
        started = CLOCK.now_ns()
        if self.target_ns:  # as the cycle driver plans, never racing to catch up
            self.planned_ns = max(self.planned_ns + self.target_ns, started)
        self.starts_ns.append(started)
        resource.cycle()
        self.work_ns.append(CLOCK.now_ns() - started)
        if DISPOSAL.pending:
            self.disposing.add(len(self.starts_ns) - 1)
            DISPOSAL.step()  # as the cycle driver does after a cycle


class Reloader:
    """A reload with the configured parameters first; when the budget refuses, once more
    (and from then on) with the watchdog (and target cycle) raised for it."""

    def __init__(self, resource: Resource) -> None:
        self.resource = resource
        self.watchdog_ms: int | None = None  # raised for the reload, once refused
        self.target_cycle_ms: int | None = None
        self.refusal: str | None = None  # the first refusal with the default parameters

    def raised(self) -> str:
        return f"watchdog_ms={self.watchdog_ms}, target_cycle_ms={self.target_cycle_ms}"

    def __call__(self, artifact: Artifact, run: Run) -> ReloadOutcome:
        """As the runtime process reloads: the job prepares on a worker thread while the
        cycles go on, and switches over between two cycles."""
        if self.refusal is None:
            try:
                return self._reload(artifact, run)
            except Refusal as refused:
                if refused.code not in BUDGET_CODES:
                    raise
                self.refusal = f"[{refused.code}] {refused.message}"
                params = self.resource.params
                self.watchdog_ms = _raised_ms(params)
                if params.target_cycle_ms and params.target_cycle_mode in ("fixed", "dynamic"):
                    self.target_cycle_ms = self.watchdog_ms
        return self._reload(artifact, run)

    def _reload(self, artifact: Artifact, run: Run) -> ReloadOutcome:
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
            run.preparing.add(len(run.starts_ns))
            run.cycle(self.resource)
        worker.join()
        run.cycle(self.resource)  # the cycle after which the driver finds the job prepared
        assert job.plan is not None and job.prepared is not None
        run.estimates_ns.append(job.plan.estimate_ns)
        run.copied.append(job.prepared.copied)
        return reload_switch.finish(self.resource, job)


def drive(
    old: Artifact,
    new: Artifact,
    reloads: int = RELOADS,
    target_ms: int = 0,
    native: NativeTier | None = None,
) -> tuple[Run, Reloader]:
    """Cycles back to back on a RealClock, as the driver runs a resource without a target
    cycle time (or every `target_ms`, as in the 'fixed' mode); after every CYCLES_BETWEEN
    cycles a reload, between two cycles as the driver does it in its housekeeping. With
    `native`, the bodies run as C, and each reload prepares the new ones."""
    resource = _running(old, native)
    reloader = Reloader(resource)
    run = Run(target_ns=target_ms * 1_000_000)
    switch_interval = sys.getswitchinterval()
    sys.setswitchinterval(SWITCH_INTERVAL_S)  # as the cycle driver runs
    try:
        _reloads(resource, reloader, run, old, new, reloads)
    finally:
        sys.setswitchinterval(switch_interval)
    return run, reloader


def _reloads(
    resource: Resource, reloader: Reloader, run: Run, old: Artifact, new: Artifact, reloads: int
) -> None:
    for n in range(reloads):
        for _ in range(CYCLES_BETWEEN):
            run.cycle(resource)
        outcome = reloader(new if n % 2 == 0 else old, run)
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


@contextmanager
def copying_everything() -> Iterator[None]:
    """The baseline: the switch-over with nothing adopted, every value copied."""
    adopt = getattr(reload_module, "plan_adoption")  # noqa: B009 (replaced for a while)
    setattr(reload_module, "plan_adoption", lambda old, new, plan: (Adoption(), Adopted()))  # noqa: B010
    try:
        yield
    finally:
        setattr(reload_module, "plan_adoption", adopt)  # noqa: B010


@contextmanager
def without_warm_up() -> Iterator[None]:
    """The baseline of the first periods on new code: no warm-up when it is compiled, so
    CPython 3.11 quickens it only at its eighth call."""
    calls = code_warmup.CALLS_BEFORE_QUICKENING
    code_warmup.CALLS_BEFORE_QUICKENING = 0
    try:
        yield
    finally:
        code_warmup.CALLS_BEFORE_QUICKENING = calls


def _periods(run: Run) -> list[int]:
    return [b - a for a, b in zip(run.starts_ns, run.starts_ns[1:], strict=False)]


def _first_periods(run: Run) -> list[int]:
    """The period of each first cycle on new instances and code."""
    periods = _periods(run)
    return [periods[i + 1] for i in sorted(run.reload_after) if i + 1 < len(periods)]


def _us(values: list[float]) -> str:
    return f"median {statistics.median(values):8.0f} us   max {max(values):8.0f} us"


def report(name: str, run: Run, reloader: Reloader, baseline: Run, cold: Run) -> None:
    periods = _periods(run)
    with_reload = [periods[i] for i in sorted(run.reload_after)]
    after = {i + 1 for i in run.reload_after}  # the first cycle on the new instances
    special = run.reload_after.keys() | after | run.preparing | run.disposing
    normal = [p for i, p in enumerate(periods) if i not in special]
    preparing = [periods[i] for i in sorted(run.preparing) if i < len(periods)]
    disposing = [
        periods[i] for i in sorted(run.disposing - after - run.preparing) if i < len(periods)
    ]
    copied = f"{min(run.copied):,}-{max(run.copied):,}"
    print(f"  {name} ({max(run.carried):,} values carried, {copied} of them copied):")
    print(
        f"    pause:                      {_us(run.pauses_us)}   vs copying everything "
        f"{statistics.median(baseline.pauses_us):8.0f} us   (ratio "
        f"{statistics.median(run.pauses_us) / statistics.median(baseline.pauses_us):.2f})"
    )
    longest = max(with_reload)
    # medians: the baseline has fewer reloads, and a longest of more is longer by chance
    first = statistics.median(_first_periods(run))
    first_cold = statistics.median(_first_periods(cold))
    if normal:
        normal_period = statistics.median(normal)
        print(
            f"    longest period with a reload {longest / 1e3:8.0f} us   vs median period "
            f"{normal_period / 1e3:8.0f} us   (ratio {longest / normal_period:.2f})"
        )
        print(
            f"    first period on the new code {first / 1e3:8.0f} us   (ratio "
            f"{first / normal_period:.2f}, median)   vs without the warm-up "
            f"{first_cold / 1e3:6.0f} us   (ratio {first_cold / normal_period:.2f})"
        )
    else:  # the disposal of a replaced configuration (or a preparation) took every cycle
        print(
            f"    no cycle outside every reload's preparation and disposal ({len(periods)} "
            "periods): no median period, and no ratios to it"
        )
        print(f"    longest period with a reload {longest / 1e3:8.0f} us")
        print(
            f"    first period on the new code {first / 1e3:8.0f} us   (median)   vs without "
            f"the warm-up {first_cold / 1e3:6.0f} us"
        )
    if preparing:
        print(
            f"    periods while preparing (a worker thread, {len(preparing)} of them): median "
            f"{statistics.median(preparing) / 1e3:8.0f} us   max {max(preparing) / 1e3:8.0f} us"
        )
    else:  # the worker thread ended before the loop looked at it
        print("    periods while preparing: none, every preparation was done before a cycle")
    if disposing:
        print(
            f"    periods while the replaced configuration is freed ({len(disposing)} of them, "
            f"{DISPOSAL_STEP_US:.0f} us steps): median "
            f"{statistics.median(disposing) / 1e3:8.0f} us   max {max(disposing) / 1e3:8.0f} us"
        )
    ratios = [e / 1e3 / p for e, p in zip(run.estimates_ns, run.pauses_us, strict=True)]
    print(
        f"    estimate / measured pause:  min {min(ratios):.2f}   max {max(ratios):.2f}   "
        f"(estimate median {statistics.median(run.estimates_ns) / 1e3:,.0f} us)"
    )
    if reloader.refusal is not None:
        print(f"    REFUSED with the default parameters: {reloader.refusal}")


def bench_switch_over(artifacts: dict[str, Artifact]) -> None:
    print(
        f"2. switch-over (RealClock, cycles back to back, {RELOADS} reloads alternating "
        "before/after per kind of change; baselines: the same reloads copying every value, "
        "and without the warm-up of new code):"
    )
    before = artifacts["before"]
    for name in CHANGES:
        run, reloader = drive(before, artifacts[name])
        with copying_everything():
            baseline, _ = drive(before, artifacts[name], reloads=2)
        with without_warm_up():
            cold, _ = drive(before, artifacts[name], reloads=2)
        report(name, run, reloader, baseline, cold)


def bench_switch_over_native(artifacts: dict[str, Artifact]) -> None:
    """Section 2 with the bodies as C, the runtime's default: the new code runs as C from
    its first cycle, so CPython's first-call specializing of new code does not come in."""
    if not NATIVE.available:
        print("2b. with native code: no C compiler or no Python.h here, skipped")
        return
    before = artifacts["before"]
    started = time.perf_counter()
    report = _running(before, NATIVE).variables.code
    assert report is not None and report.native is not None
    print(
        f"2b. the same with native code, the runtime's default ({report.native.summary()}; "
        f"built in {time.perf_counter() - started:.1f} s, then from the cache):"
    )
    for name in CHANGES:
        run, _ = drive(before, artifacts[name], native=NATIVE)
        periods = _periods(run)
        with_reload = max(periods[i] for i in run.reload_after)
        special = run.reload_after.keys() | run.preparing | run.disposing
        special |= {i + 1 for i in run.reload_after}
        normal = [p for i, p in enumerate(periods) if i not in special]
        first = statistics.median(_first_periods(run))
        head = (
            f"  {name + ':':<32} pause median {statistics.median(run.pauses_us):5.0f} us; "
            f"longest period with a reload {with_reload / 1e3:5.0f} us"
        )
        if not normal:
            print(
                f"{head}; first period on the new code {first / 1e3:.0f} us (median); no cycle "
                "outside every reload's preparation and disposal: no median period, no ratios"
            )
            continue
        median = statistics.median(normal)
        print(
            f"{head} (ratio {with_reload / median:.2f} to the median {median / 1e3:.0f} us); "
            f"first period on the new code ratio {first / median:.2f}"
        )


# ---- 3. the periods at a fixed target cycle time ---------------------------------------------


def bench_fixed_periods(texts: dict[str, str]) -> None:
    """With the 'fixed' mode the switch-over and the disposal steps happen in the time the
    cycle leaves; what a user sees is the period of the cycle containing the reload."""
    config = ResourceConfig(name="R", target_cycle_ms=FIXED_TARGET_MS, target_cycle_mode="fixed")
    before = _compile(texts["before"], config)
    print(
        f"3. periods at a {FIXED_TARGET_MS} ms fixed target cycle ({RELOADS} reloads per kind "
        "of change, the worker preparing while the cycles go on):"
    )
    for name in CHANGES:
        run, _ = drive(before, _compile(texts[name], config), target_ms=FIXED_TARGET_MS)
        periods = [b - a for a, b in zip(run.starts_ns, run.starts_ns[1:], strict=False)]
        median = statistics.median(periods)
        with_reload = max(periods[i] for i in run.reload_after)
        print(
            f"  {name + ':':<32} longest period with a reload {with_reload / 1e6:6.2f} ms "
            f"(ratio {with_reload / median:.2f} to the median {median / 1e6:.2f} ms); "
            f"longest of all {max(periods) / 1e6:6.2f} ms"
        )


# ---- 4. the budget check with a fixed target cycle time ---------------------------------------


def bench_budget(texts: dict[str, str]) -> None:
    """With a target cycle in the 'fixed' mode the budget is what the target cycle leaves
    after the last cycle."""
    config = ResourceConfig(name="R", target_cycle_ms=FIXED_TARGET_MS, target_cycle_mode="fixed")
    before = _compile(texts["before"], config)
    resource = _running(before)
    print(
        f"4. budget check, target cycle {config.target_cycle_ms} ms '{config.target_cycle_mode}', "
        f"watchdog {config.watchdog_ms} ms, default parameters (last cycle "
        f"{resource.stats.last_ns / 1e6:.2f} ms):"
    )
    for name in CHANGES:
        for label, artifact in ((name, _compile(texts[name], config)), ("and back", before)):
            try:
                outcome = reload_switch.reload(resource, artifact, {})
                result = f"done, pause {outcome.pause_us:,.0f} us"
            except Refusal as refused:
                result = f"REFUSED [{refused.code}] {refused.message}"
            print(f"  {label + ':':<34} {result}")


# ---- entry point -------------------------------------------------------------------------------


# ---- 5. the cycles after a reload, on code the reload kept -----------------------------------

AFTER_CYCLES = 120  # past the 50-90 cycles that instructions specialized for old classes miss


def straight_line_versions() -> tuple[Artifact, Artifact]:
    """The 1,000-statement program without its FOR loops (a loop specializes its body anew
    within one cycle) and with a Small instance; the second version changes Small only."""
    lines = thousand_statements().splitlines()
    text = "\n".join(line for line in lines if not line.startswith("FOR ")) + "\n"
    text = _edited(text, (("  k : INT;", "  k : INT;\n  small : Small;"),))
    text = _edited(text, (("END_PROGRAM", "small(x := 7);\nEND_PROGRAM"),))
    config = ResourceConfig(name="R")
    changed = _edited(SMALL, CHANGES["one small POU's code"])
    return _compile(SMALL + text, config), _compile(changed + text, config)


def _cycles_after_reload(before: Artifact, after: Artifact) -> list[float]:
    clock = VirtualClock()
    resource = Resource("R", clock)
    resource.load(before)
    resource.start()
    for _ in range(AFTER_CYCLES):
        resource.cycle()
        clock.advance(10_000_000)
    reload_switch.reload(resource, after, {})
    times = []
    for _ in range(AFTER_CYCLES):
        started = time.perf_counter_ns()
        resource.cycle()
        times.append((time.perf_counter_ns() - started) / 1e3)
        clock.advance(10_000_000)
    return times


@contextmanager
def code_kept_as_it_ran() -> Iterator[None]:
    """The baseline: a reload keeps the running code objects themselves, specialized for
    the classes it replaces, and warms up nothing."""
    names = ("unspecialized", "warm_up")
    kept = {name: getattr(code_image, name) for name in names}
    setattr(code_image, "unspecialized", lambda code: code)  # noqa: B010 (for a while)
    setattr(code_image, "warm_up", lambda codes: None)  # noqa: B010
    try:
        yield
    finally:
        for name, value in kept.items():
            setattr(code_image, name, value)


def bench_cycles_after_reload() -> None:
    before, after = straight_line_versions()
    now = _cycles_after_reload(before, after)
    with code_kept_as_it_ran():
        then = _cycles_after_reload(before, after)
    print(
        f"5. the {AFTER_CYCLES} cycles after a reload that changed only Small, in a program of "
        "1,000 straight-line statements (virtual clock; baseline: the running code kept as "
        "it was):"
    )
    for label, times in (("copied and warmed up", now), ("baseline", then)):
        print(
            f"  {label:<21} first {times[0]:6.0f} us   median of cycles 2-{AFTER_CYCLES // 2} "
            f"{statistics.median(times[1 : AFTER_CYCLES // 2]):6.0f} us   of the last "
            f"{AFTER_CYCLES // 2} {statistics.median(times[AFTER_CYCLES // 2 :]):6.0f} us"
        )
    ratio = statistics.median(then[1 : AFTER_CYCLES // 2]) / statistics.median(
        now[1 : AFTER_CYCLES // 2]
    )
    print(f"  -> cycles 2-{AFTER_CYCLES // 2}: baseline / now {ratio:.2f}")


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
    texts = versions()
    artifacts = {name: _compile(text, config) for name, text in texts.items()}
    print(
        f"reload benchmark: {len(_running(artifacts['before']).variables.values()):,} variables "
        f"({len(texts)} versions compiled in {time.perf_counter() - started:.1f} s)"
    )
    _section(lambda: bench_plan(artifacts["before"], artifacts["every instance migrated"]))
    _section(lambda: bench_switch_over(artifacts))
    _section(lambda: bench_switch_over_native(artifacts))
    _section(lambda: bench_fixed_periods(texts))
    _section(lambda: bench_budget(texts))
    _section(bench_cycles_after_reload)


if __name__ == "__main__":
    main()
