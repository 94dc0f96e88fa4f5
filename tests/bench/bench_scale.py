"""A resource of 100,000 variables (issue 16): how long loading it, reading all its values
(the online test's `values`), a watch set of 20,000 of them, taking and saving its context,
a warm start and a reload of one small POU take (and how long its preparation, beside the
cycles, holds the interpreter lock with the compile worker and without), beside the same
for 10,000 variables measured in the same run. Each figure says whether it runs on the
cycle thread (between two cycles: it delays the next one) or elsewhere. Last, the figures
issue 34 (variables in native memory) must keep or better, the reload pause and online read
at 10,000 variables and the context save at 100,000, beside the code before issue 34, each
in a process of its own (tests/bench/baseline.py).

Run with `python -m tests.bench.bench_scale`; it prints figures and asserts nothing.
"""

from __future__ import annotations

import sys
import tempfile
import threading
import time
from collections.abc import Callable
from contextlib import AbstractContextManager
from pathlib import Path
from unittest.mock import patch

from backend.compiler.pipeline import compile_sources
from backend.compiler.source import SourceFile
from runtime import reload_switch
from runtime.clock import VirtualClock
from runtime.code.compile_worker import COMPILE_WORKER, compile_here
from runtime.collector import COLLECTOR
from runtime.context import encode_context, save_context
from runtime.contract.artifact import Artifact, ProgramConfig, ResourceConfig
from runtime.contract.protocol import MAX_SET_VARIABLES, ValuesReply, encode_reply
from runtime.cycle_driver import SWITCH_INTERVAL_S
from runtime.reload_switch import reload
from runtime.resource import Resource
from runtime.restart import take_context, warm_start
from runtime.watch_sets import WatchSet
from tests.bench.baseline import ISSUE_34_COMMIT, REPO, Replies, alternate, baseline, probe
from tests.bench.cycle_probe import BEST_OF, STATE_ROUNDS, best_ms, scale_source

SIZES = (10_000, 100_000)
ROUNDS = BEST_OF


def compiled(variables: int, step: int = 1) -> tuple[Artifact, float]:
    config = ResourceConfig(name="R", target_cycle_ms=10, watchdog_ms=60_000)
    started = time.process_time()
    result = compile_sources(
        [SourceFile("scale.st", scale_source(variables, step))],
        resource=config,
        programs=[ProgramConfig("Small", "Small", 1)],
    )
    assert result.artifact is not None, [str(d) for d in result.diagnostics]
    return result.artifact, time.process_time() - started


def longest_wait_ms(work: Callable[[], object]) -> float:
    """The longest a thread that asks for the GIL every 0.5 ms waits beyond that while
    `work` runs, at the runtime's switch interval: what the cycle thread would wait for
    the work's longest hold of it."""
    switch = sys.getswitchinterval()
    sys.setswitchinterval(SWITCH_INTERVAL_S)
    done = threading.Event()
    longest = [0.0]

    def ticker() -> None:
        last = time.perf_counter()
        while not done.is_set():
            time.sleep(0.0005)
            now = time.perf_counter()
            longest[0] = max(longest[0], now - last - 0.0005)
            last = now

    thread = threading.Thread(target=ticker)
    thread.start()
    try:
        work()
    finally:
        done.set()
        thread.join()
        sys.setswitchinterval(switch)
    return longest[0] * 1000


def compiled_in_this_process() -> AbstractContextManager[object]:
    """A reload's code compiled as it was before the compile worker: in this process."""
    return patch.object(COMPILE_WORKER, "compile", compile_here)


def measure(variables: int) -> dict[str, float]:
    artifact, compile_s = compiled(variables)
    changed, _ = compiled(variables, step=2)
    figures = {"compile (CPU, PADT)": compile_s * 1000}
    resource = Resource("R", VirtualClock())
    figures["load: instances (STOP)"] = best_ms(lambda: resource.load(artifact))
    resource.start()
    for _ in range(20):  # past Python's warm-up of new code
        resource.cycle()
    COLLECTOR.manage()  # as the runtime process does before its first cycle
    figures["CPU cycle of the small program"] = best_ms(resource.cycle)
    figures["values: every variable, read (cycle thread)"] = best_ms(resource.variables.read_values)
    values = resource.variables.read_values()

    def reply() -> object:
        return encode_reply(ValuesReply(values(), 1))

    figures["values: reply built + encoded (files thread)"] = best_ms(reply)
    figures["  longest wait of another thread meanwhile "] = longest_wait_ms(reply)
    paths = tuple(b.path.path for b in resource.variables.bound)[:MAX_SET_VARIABLES]
    watch_set = WatchSet("w", paths, 100_000_000)
    table = resource.forcing.table

    def watched() -> object:
        return resource.online.snapshot(watch_set, 1, True, table).message()

    figures["watch set (all, at most 20,000): read + encode"] = best_ms(watched)
    context = take_context(resource)
    assert context is not None
    figures["take_context, whole tree (before)"] = best_ms(lambda: take_context(resource))
    figures["take_context, periodic save (cycle thread)"] = best_ms(
        lambda: take_context(resource, deferred=True)
    )
    deferred = take_context(resource, deferred=True)
    assert deferred is not None
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "context.json"
        figures["encode + save context (saver thread)"] = best_ms(
            lambda: save_context(path, deferred)
        )
        figures["  longest wait of another thread meanwhile"] = longest_wait_ms(
            lambda: save_context(path, deferred)
        )
        size = len(encode_context(deferred))
    resource.stop()

    def warm() -> None:
        fresh = Resource("R", VirtualClock())
        fresh.load(artifact)
        started = time.perf_counter()
        warm_start(fresh, context)
        warm.ms = (time.perf_counter() - started) * 1000  # type: ignore[attr-defined]

    warm()
    figures["warm start: restore (STOP)"] = warm.ms  # type: ignore[attr-defined]
    resource.start()

    prepared: list[object] = []

    def prepare() -> None:  # what the runtime's worker thread does while cycles go on
        job = reload_switch.begin_preview(resource, changed, {})
        job.prepare()
        # kept: freeing it here would count in the wait; the cycle driver takes it apart
        # between cycles (runtime/disposal.py)
        prepared.append(job)

    COLLECTOR.between_cycles(running=False)  # the warm start loaded another configuration
    waits = [longest_wait_ms(prepare) for _ in range(ROUNDS)]
    figures["reload preparation: longest wait of another thread"] = min(waits)
    with compiled_in_this_process():
        waits = [longest_wait_ms(prepare) for _ in range(ROUNDS)]
        figures["  the same, compiled in this process (before)"] = min(waits)
    prepared.clear()
    outcome = reload(resource, changed, {})
    figures["reload of the small program: pause (cycle thread)"] = outcome.pause_us / 1000
    figures["context size (MB)"] = size / 1e6
    return figures


# what issue 34 (variables in native memory) must keep or better: (probe figure, label)
KEPT_FIGURES = {
    10_000: (
        ("pause_ms", "reload pause (cycle thread)"),
        ("read_ms", "online read of every value (cycle thread)"),
        ("values_ms", "online read with the values built"),
    ),
    100_000: (
        ("take_ms", "context save: taken (cycle thread)"),
        ("save_ms", "context save: encoded + saved (saver thread)"),
    ),
}


# the moves of the values between the memory image and objects (cycle thread), which a
# reload's job and the debugger cost on the native tier besides the figures above
IMAGE_MOVES = (
    ("leave_ms", "values out of the image (a reload's start)"),
    ("enter_ms", "values into the image (the next tier-up)"),
)


def bench_against_issue_34(rounds: int = 2) -> None:
    """The figures of KEPT_FIGURES, today's code beside the code before issue 34, each in
    processes of its own, alternately (tests/bench/baseline.py); per figure the best.
    Today's code twice: on Python objects as the baseline, and on the native tier with the
    values in its memory image."""
    other = baseline(ISSUE_34_COMMIT)
    print(
        f"beside the baseline of issue 34 ({other.name if other else 'none'}), {rounds} "
        f"processes each, alternately, best of {rounds} x {STATE_ROUNDS} (ms; ratio: today / "
        "baseline; then today with the variables in native memory):"
    )
    width = max(
        len(label) for figures in (*KEPT_FIGURES.values(), IMAGE_MOVES) for _, label in figures
    )
    with tempfile.TemporaryDirectory(prefix="padt-bench-native-") as cache:
        for variables, figures in KEPT_FIGURES.items():
            reloads = any(key == "pause_ms" for key, _ in figures)
            request = {"state_variables": variables, "reload": reloads}
            now, before = alternate(request, rounds, ISSUE_34_COMMIT)
            native = {**request, "state_native_cache": cache}
            in_image = [probe(REPO, native) for _ in range(rounds)]
            for key, label in figures:
                best = _best(now, key)
                line = f"  {variables:>7,} variables, {label + ':':<{width + 1}} {best:8.2f}"
                if before:
                    was = _best(before, key)
                    line += f"   baseline {was:8.2f}   ratio {best / was:5.2f}"
                print(f"{line}   native memory {_best(in_image, key):8.2f}")
            for key, label in IMAGE_MOVES:
                best = _best(in_image, key)
                print(f"  {variables:>7,} variables, {label + ':':<{width + 1}} {best:8.2f}")


def _best(replies: Replies, key: str) -> float:
    return min(float(reply[key]) for reply in replies)


def main() -> None:
    print("scale benchmark: a resource of 10,000 and of 100,000 variables, best of 3 (ms)")
    compiled(10)  # the compiler's own start-up (grammar, imports) counts in neither
    results = {n: measure(n) for n in SIZES}
    small, large = results[SIZES[0]], results[SIZES[1]]
    width = max(len(name) for name in large)
    print(f"  {'':{width}}  {'10,000':>10}  {'100,000':>10}  ratio")
    for name, value in large.items():
        ratio = value / small[name] if small[name] else float("nan")
        print(f"  {name:{width}}  {small[name]:10.2f}  {value:10.2f}  {ratio:5.1f}x")
    bench_against_issue_34()


if __name__ == "__main__":
    main()
