"""Debugging benchmarks (docs/debugging.md): what the debugger costs the CPU cycle.

1. The 1,000-statement program per CPU cycle with nothing armed, beside the same figure of
   the commit before the debugger (each in a process of its own: tests/bench/baseline.py's
   probe), then with a breakpoint armed that never stops (in a POU the program never calls;
   in the program's own hot line with a condition that never holds) and with a logpoint.
2. Under the real cycle driver at a 10 ms target, two programs: the period of the one that
   keeps running, with the other running, in BKPT, and with a logpoint hit 1,000 times a
   second.

Run with `python -m tests.bench.bench_debugging`; it prints figures and asserts nothing
about time (machines are shared and noisy)."""

from __future__ import annotations

import atexit
import functools
import shutil
import subprocess
import tempfile
import time
from collections.abc import Callable
from itertools import pairwise
from pathlib import Path

from backend.compiler.pipeline import compile_sources
from backend.compiler.source import SourceFile
from backend.engineering.resource_client import ResourceClient
from runtime.clock import RealClock
from runtime.collector import COLLECTOR
from runtime.commands import HANDLERS
from runtime.contract import protocol as p
from runtime.contract.artifact import Artifact, ProgramConfig, ResourceConfig
from runtime.contract.session import open_client
from runtime.resource import Resource
from tests.bench.baseline import REPO, probe
from tests.bench.bench_language import thousand_statements
from tests.bench.bench_runtime import (
    TARGET_MS,
    TARGET_NS,
    LoggedResource,
    Spread,
    _cycle_us,
    driven,
)

# main just before the debugger came (issue 32): the cycle with nothing armed against it
BEFORE_DEBUGGER = "e1a6e69"
FILE = "bench.st"
IDLE = "FUNCTION_BLOCK NeverCalled\nVAR x : INT; END_VAR\nx := x + 1;\nEND_FUNCTION_BLOCK\n"
# a loop of 10 passes: at a 10 ms cycle, a logpoint in it is hit 1,000 times a second
OTHER = """\
PROGRAM Other
VAR i, sum : DINT; END_VAR
sum := 0;
FOR i := 1 TO 10 DO
  sum := sum + i;
END_FOR;
END_PROGRAM
"""


def _artifact(text: str, programs: list[ProgramConfig], target_ms: int = 100) -> Artifact:
    config = ResourceConfig(
        name="R", watchdog_ms=5_000, target_cycle_ms=target_ms, safety_operation=False
    )
    result = compile_sources([SourceFile(FILE, text)], resource=config, programs=programs)
    assert result.artifact is not None, [str(d) for d in result.diagnostics]
    return result.artifact


def _line_of(text: str, start: str) -> int:
    return next(n for n, line in enumerate(text.splitlines(), 1) if line.startswith(start))


def _ask(resource: Resource, command: p.Command[p.DebugReply]) -> p.DebugState:
    reply: p.DebugReply = HANDLERS[type(command)](resource, command)
    return reply.debug


@functools.cache
def _before_debugger() -> Path | None:
    archive = subprocess.run(
        ["git", "-C", str(REPO), "archive", BEFORE_DEBUGGER, "runtime", "backend"],
        capture_output=True,
        check=False,
    )
    if archive.returncode != 0:
        return None
    tree = Path(tempfile.mkdtemp(prefix="padt-before-debugger-"))
    atexit.register(shutil.rmtree, tree, ignore_errors=True)
    subprocess.run(["tar", "-x", "-C", str(tree)], input=archive.stdout, check=True)
    return tree


def bench_nothing_armed(cycles: int = 2_000, rounds: int = 3) -> None:
    text = thousand_statements()
    request = {"program": text, "cycles": cycles, "check_cycles": 10}
    before = _before_debugger()
    now, then = [], []
    for _ in range(rounds):  # alternately: the machine's load falls on both
        now.append(float(probe(REPO, request)["program_us"]))
        if before is not None:
            then.append(float(probe(before, request)["program_us"]))
    line = f"  nothing armed (Python tier, own process): {min(now):,.1f} us per cycle"
    if then:
        line += f"; before the debugger ({BEFORE_DEBUGGER}): {min(then):,.1f} us"
        line += f" ({min(now) / min(then):.3f}x)"
    else:
        line += f" (commit {BEFORE_DEBUGGER} not in this clone: no figure before)"
    print(line)


def _measured(text: str, program: str, arm: Callable[[Resource], object], cycles: int) -> float:
    resource = Resource("R", RealClock())
    resource.load(_artifact(text, [ProgramConfig(name=program, pou=program, program_id=1)]))
    resource.start()
    arm(resource)
    return _cycle_us(resource, cycles, warmup=200).p50


def _armed(
    line: int, condition: str | None = None, log: list[str] | None = None
) -> Callable[[Resource], object]:
    spec = p.BreakpointSpec(line, condition=condition, log=log)
    return lambda resource: _ask(resource, p.DebugSet(FILE, [spec]))


def bench_armed(cycles: int = 2_000) -> None:
    text = thousand_statements() + IDLE
    statement = _line_of(text, "END_VAR") + 1  # the program's first statement

    def measured(arm: Callable[[Resource], object]) -> float:
        return _measured(text, "Bench", arm, cycles)

    plain = measured(lambda r: None)
    elsewhere = measured(_armed(_line_of(text, "x := x + 1")))
    never = measured(_armed(statement, condition="FALSE"))
    print(f"  nothing armed (Python tier, this process):            {plain:8,.1f} us per cycle")
    print(
        f"  a breakpoint armed in a POU it never calls:           {elsewhere:8,.1f} us "
        f"({elsewhere / plain:.2f}x: nothing traced until it enters that POU)"
    )
    print(
        f"  a breakpoint on one of its lines, condition FALSE:    {never:8,.1f} us "
        f"({never / plain:.2f}x: every statement of the program traced)"
    )
    passes = 100
    loop = OTHER.replace("TO 10 DO", f"TO {passes} DO")
    body = _line_of(loop, "  sum := sum + i;")
    never_runs = _line_of(loop, "sum := 0;")  # a line of the same POU, before the loop

    def looped(arm: Callable[[Resource], object]) -> float:
        return _measured(loop, "Other", arm, cycles)

    traced = looped(_armed(never_runs, condition="FALSE"))
    logged = looped(_armed(body, log=["i", "sum"]))
    print(
        f"  a logpoint hit {passes} times a cycle: {logged:,.1f} us per cycle against "
        f"{traced:,.1f} us traced without it: {(logged - traced) / passes:.2f} us per hit "
        "(20 a second recorded, the rest counted)"
    )


def _periods(resource: LoggedResource, seconds: float) -> Spread:
    start = len(resource.log.starts_ns)
    time.sleep(seconds)
    starts = resource.log.starts_ns[start:]
    return Spread.of([b - a for a, b in pairwise(starts)])


def bench_other_programs(seconds: float = 5.0) -> None:
    text = thousand_statements() + OTHER
    loop = _line_of(text, "  sum := sum + i;")
    programs = [
        ProgramConfig(name="Bench", pou="Bench", program_id=1),
        ProgramConfig(name="Other", pou="Other", program_id=2, priority=1),
    ]
    clock = RealClock()
    resource = LoggedResource("R", clock)
    resource.load(_artifact(text, programs, TARGET_MS))
    resource.start()
    COLLECTOR.manage()  # as a runtime process keeps the collector off the cycle's path
    first = _line_of(text, "END_VAR") + 1
    print(
        f"  under the cycle driver, target {TARGET_MS} ms, {seconds:g} s each; the period "
        "of the CPU cycle (the program that runs on):"
    )
    with driven(resource, clock) as endpoint:
        session = open_client(endpoint)
        try:
            client = ResourceClient(session, "R")
            client.wait_until_answering()
            client.ask(p.DebugOptions(3600))
            quiet = _periods(resource, seconds)
            client.ask(p.DebugSet(FILE, [p.BreakpointSpec(first, program="Bench")]))
            time.sleep(0.5)
            state = client.ask(p.DebugGet(keep=True)).debug
            stopped = _periods(resource, seconds)
            assert state.paused is not None, "Bench did not stop"
            client.ask(p.DebugClear())
            client.ask(p.DebugSet(FILE, [p.BreakpointSpec(loop, log=["i", "sum"])]))
            logging = _periods(resource, seconds)
            client.ask(p.DebugClear())
        finally:
            session.close()
            COLLECTOR.release()
    for label, spread in (
        ("both programs running", quiet),
        ("Bench in BKPT", stopped),
        ("a logpoint hit 1,000 times a second", logging),
    ):
        print(
            f"    {label:<38} p50 {spread.p50 / 1e6:6.3f} ms   p99 {spread.p99 / 1e6:6.3f} ms"
            f"   max {spread.max / 1e6:6.3f} ms   p99 jitter "
            f"{abs(spread.p99 - TARGET_NS) / 1e6:.3f} ms"
        )


def main() -> None:
    print("debugging: the 1,000-statement program per CPU cycle")
    bench_nothing_armed()
    bench_armed()
    bench_other_programs()


if __name__ == "__main__":
    main()
