"""Recording benchmark (issue 15): the cost on the cycle thread of recording 100, 1,000 and
10,000 variables every 10 ms CPU cycle, what the writer thread drops, and the file size per
hour; and the same with all inputs on.

One program with 10,000 elementary variables that change like a plant's: set points that
stay constant, counters, noisy analog values (REAL) and states (BOOL) that switch now and
then, and located inputs the bench changes every cycle (the field). The analog values take
their noise from a function: written out for each, it made the program larger than the
compiler takes (150,000 tokens, E0708); the values recorded are the same as before, and
`Resource.cycle` takes some 5 % longer for the calls. The resource runs in this process on
a VirtualClock (10 ms of virtual time per cycle) while the cycles are paced at 10 ms of
real time, so the recording's writer thread has the time and competes for the interpreter
as in a runtime process (the cycle driver's switch interval is set too).

For each set, rounds of 1 s without a recording and 1 s with one (a recording per round),
so that the changing load of a shared machine weighs on both alike: `Resource.cycle` is
timed on its own (perf_counter); the cost is the difference of the means, also as a share
of the 10 ms cycle (the issue's target: under 5 % for 1,000 variables). The time in the
recorder's own calls (reading the values, queueing them) is timed apart; the rest of the
difference is waiting for the interpreter while the writer thread has it. The extra CPU
time of the process (mostly the writer thread: JSON, zstd, the file) is given as a share
of one core. File size per hour is extrapolated from the chunks written.

Run with `python -m tests.bench.bench_recording [--seconds S]`: S seconds with and S
without a recording per set (5 by default). It prints figures and asserts nothing about
time (machines are shared and noisy).
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from mcap.reader import make_reader

from backend.compiler.pipeline import compile_sources
from backend.compiler.source import SourceFile
from runtime.clock import VirtualClock
from runtime.contract import protocol as p
from runtime.contract.artifact import Artifact, ResourceConfig
from runtime.cycle_driver import SWITCH_INTERVAL_S
from runtime.recorder import Recordings
from runtime.resource import Resource
from tests.bench.bench_runtime import TARGET_MS, TARGET_NS, Spread
from tests.bench.bench_watch import select

DEFAULT_SECONDS = 5.0
VARIABLES = 10_000  # elementary variables of the program, the largest set recorded
INPUTS = 64  # located %IW inputs the bench changes every cycle
OUTPUTS = 32  # located %QX outputs
SETS = (100, 1_000, 10_000)
ALL_INPUTS_SET = 1_000
WARMUP = 50
# a machine shared with others stops a process now and then for a few 100 ms: that is
# not what the benchmark measures, so it must not end in the watchdog's ERROR STOP
WATCHDOG_MS = 10_000
ROUND = 100  # cycles: 1 s without, then 1 s with a recording
SETTLE = 10  # cycles after a recording starts, not timed
HOUR_CYCLES = 3_600_000 // TARGET_MS


# An analog value's noise, the next step of a linear congruential generator: a function, as
# written out for each of the 2,500 analog values the program had more than the compiler's
# MAX_PROJECT_TOKENS (with it, some 119,000).
NOISE = (
    "FUNCTION Noise : REAL",
    "VAR_IN_OUT seed : UDINT; END_VAR",
    "seed := seed * 1103515245 + 12345;",
    "Noise := UDINT_TO_REAL(seed / 65536 MOD 1000) / 250.0;",
    "END_FUNCTION",
)


def plant_program(count: int = VARIABLES) -> str:
    """`count` elementary variables in four kinds, interleaved so that any even selection
    holds each: set points (constant), counters, noisy analog values and switching states;
    plus the located inputs and outputs."""
    declarations, body = [], []
    for n in range(count):
        kind = n % 4
        if kind == 0:  # a set point: stays what it was set to
            declarations.append(f"  sp{n} : REAL := {n % 97}.25;")
        elif kind == 1:  # a counter (totaliser, operating hours, cycle count)
            declarations.append(f"  cnt{n} : DINT := {n};")
            body.append(f"cnt{n} := cnt{n} + {n % 3 + 1};")
        elif kind == 2:  # an analog value: a level around its working point, with noise
            declarations.append(f"  pv{n} : REAL;")
            body.append(f"pv{n} := {n % 50 + 10}.0 + Noise(seed);")
        else:  # a state: on for a while, off for a while
            declarations.append(f"  st{n} : BOOL;")
            body.append(f"st{n} := (tick + {n}) MOD {40 + n % 60} < 20;")
    globals_ = [f"  ai{n} AT %IW{n} : INT;" for n in range(INPUTS)]
    globals_ += [f"  do{n} AT %QX{n // 8}.{n % 8} : BOOL;" for n in range(OUTPUTS)]
    outputs = [f"do{n} := ai{n % INPUTS} > 500;" for n in range(OUTPUTS)]
    externals = [g.split(" AT ")[0] + " : " + g.split(" : ")[1] for g in globals_]
    return "\n".join(
        [
            *NOISE,
            "VAR_GLOBAL",
            *globals_,
            "END_VAR",
            "PROGRAM Plant",
            "VAR_EXTERNAL",
            *externals,
            "END_VAR",
            "VAR",
            "  seed : UDINT := 1;",
            "  tick : DINT;",
            *declarations,
            "END_VAR",
            "tick := tick + 1;",
            *body,
            *outputs,
            "END_PROGRAM",
            "",
        ]
    )


def compiled(source: str) -> Artifact:
    config = ResourceConfig(
        name="R",
        target_cycle_ms=TARGET_MS,
        target_cycle_mode="fixed",
        watchdog_ms=WATCHDOG_MS,
        safety_time_ms=3 * WATCHDOG_MS,
    )
    result = compile_sources([SourceFile("bench.st", source)], resource=config)
    assert result.artifact is not None, [str(d) for d in result.diagnostics]
    return result.artifact


class TimedRecordings(Recordings):
    """The recordings, with the time of their calls on the cycle thread noted."""

    def __init__(self, folder: Path) -> None:
        super().__init__(folder)
        self.spent_ns = 0

    def before_programs(self, resource: Resource) -> None:
        started = time.perf_counter_ns()
        super().before_programs(resource)
        self.spent_ns += time.perf_counter_ns() - started

    def cycled(
        self,
        resource: Resource,
        begin_ns: int,
        before: list[tuple[str, Any]],
        after: list[tuple[str, Any]],
    ) -> None:
        started = time.perf_counter_ns()
        super().cycled(resource, begin_ns, before, after)
        self.spent_ns += time.perf_counter_ns() - started


@dataclass
class Block:
    """Paced cycles: each `Resource.cycle` in µs, the process CPU time and the wall-clock
    time they took, in s."""

    cycle_us: list[float] = field(default_factory=list)
    cpu_s: float = 0.0
    seconds: float = 0.0
    late: int = 0  # cycles that started late: the one before took its slot and more

    def add(self, other: Block) -> None:
        self.cycle_us += other.cycle_us
        self.cpu_s += other.cpu_s
        self.seconds += other.seconds
        self.late += other.late


class Bench:
    def __init__(self, artifact: Artifact, folder: Path) -> None:
        self.clock = VirtualClock(start_ns=1_000_000_000, epoch_ns=1_700_000_000 * 10**9)
        self.resource = Resource("R", self.clock)
        self.recordings = TimedRecordings(folder)
        self.resource.recordings = self.recordings
        self.resource.load(artifact)
        self.resource.start()
        self.field = 0
        self.paths = [v.path for v in self.resource.variables.infos()]

    def block(self, cycles: int) -> Block:
        """`cycles` CPU cycles paced at the target cycle in real time, the field inputs
        changing every cycle."""
        resource, clock = self.resource, self.clock
        block = Block()
        cpu = time.process_time()
        began = time.perf_counter_ns()
        next_ns = began
        for _ in range(cycles):
            self.field += 1
            resource.io.set_inputs(
                {f"ai{n}": (self.field * 7 + n * 131) % 1000 for n in range(0, INPUTS, 4)}
            )
            wait = next_ns - time.perf_counter_ns()
            if wait > 0:
                time.sleep(wait / 1e9)
            else:
                block.late += 1
            started = time.perf_counter_ns()
            resource.cycle()
            block.cycle_us.append((time.perf_counter_ns() - started) / 1e3)
            clock.advance(TARGET_NS)
            next_ns += TARGET_NS
        block.cpu_s = time.process_time() - cpu
        block.seconds = (time.perf_counter_ns() - began) / 1e9
        return block


def _us(spread: Spread) -> str:
    return (
        f"mean {spread.mean:8.1f} µs  p50 {spread.p50:8.1f}  p99 {spread.p99:8.1f}  "
        f"max {spread.max:8.1f}"
    )


def _bytes(count: float) -> str:
    for unit, size in (("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if count >= size:
            return f"{count / size:,.1f} {unit}"
    return f"{count:,.0f} B"


def bench_set(bench: Bench, count: int, all_inputs: bool, cycles: int) -> None:
    """Rounds of ROUND cycles without a recording, then ROUND with one (each round its own
    recording, started and finished outside the timed cycles), so that the load of a
    shared machine, which changes by the second, weighs on both alike."""
    chosen = select(bench.paths, count)
    label = f"{len(chosen):,} variables" + (", all inputs" if all_inputs else "")
    bench.block(WARMUP)
    without, with_recording = Block(), Block()
    written = dropped = size = grown = recorded = spent_ns = 0
    errors = []
    rounds = max(1, cycles // ROUND)
    for round_ in range(rounds):
        without.add(bench.block(ROUND))
        recording_id = f"b{count}{'i' if all_inputs else ''}-{round_}"
        started = bench.recordings.start(
            bench.resource, p.RecordStart(chosen, all_inputs=all_inputs, id=recording_id)
        )
        recorded = started.variables
        bench.block(SETTLE)  # the writer lays out its file: once per recording
        mark = bench.recordings.spent_ns
        with_recording.add(bench.block(ROUND))
        spent_ns += bench.recordings.spent_ns - mark
        bench.recordings.stop(bench.resource, recording_id)
        bench.recordings.close()  # waits for the writer to finish the file
        [info] = [r for r in bench.recordings.infos() if r.id == recording_id]
        written += info.cycles
        dropped += info.dropped
        size += sum(f.size for f in info.files)
        grown += _chunk_bytes(bench.recordings.folder, info)
        if info.error:
            errors.append(info.error)
    timed = len(with_recording.cycle_us)
    spent_us = spent_ns / 1e3 / timed
    off, on = Spread.of(without.cycle_us), Spread.of(with_recording.cycle_us)
    cost = on.mean - off.mean
    extra_cpu = with_recording.cpu_s / with_recording.seconds - without.cpu_s / without.seconds
    print(
        f"recording {label} ({recorded:,} in all), {timed:,} cycles of {TARGET_MS} ms "
        f"with and {len(without.cycle_us):,} without, in rounds of {ROUND}:"
    )
    print(f"  Resource.cycle without: {_us(off)}")
    print(f"  Resource.cycle with:    {_us(on)}")
    print(
        f"  -> cost on the cycle thread: {cost:+.1f} µs per cycle = "
        f"{cost / (TARGET_NS / 1e3):+.2%} of the {TARGET_MS} ms cycle "
        f"(p50 {on.p50 - off.p50:+.1f} µs, p99 {on.p99 - off.p99:+.1f} µs); "
        f"in the recorder's calls {spent_us:.1f} µs = {spent_us / (TARGET_NS / 1e3):.2%}"
    )
    print(
        f"  writer: {written:,} cycles written, {dropped:,} dropped; extra CPU of the "
        f"process {extra_cpu:.1%} of one core; late cycle starts {without.late} without, "
        f"{with_recording.late} with"
    )
    for error in errors:
        print(f"  WARNING: a recording failed: {error}")
    if not bench.resource.running():
        print(f"  WARNING: the resource is in {bench.resource.state.value}: {bench.resource.error}")
    if written:
        per_cycle = grown / written
        print(
            f"  files: {_bytes(size)} for {written:,} cycles in {rounds} recordings; their "
            f"chunks {per_cycle:,.0f} B per cycle -> {_bytes(per_cycle * HOUR_CYCLES)} per "
            "hour (+ header, summary and attachments once per file)"
        )


def _chunk_bytes(folder: Path | None, info: p.RecordingInfo) -> int:
    """The bytes of a recording's chunks with their message indexes: what grows with every
    cycle (the header, the summary and the attachments come once per file)."""
    assert folder is not None
    total = 0
    for file in info.files:
        with (folder / file.name).open("rb") as stream:
            summary = make_reader(stream).get_summary()
        assert summary is not None, file.name
        total += sum(c.chunk_length + c.message_index_length for c in summary.chunk_indexes)
    return total


@contextmanager
def _switch_interval() -> Iterator[None]:
    before = sys.getswitchinterval()
    sys.setswitchinterval(SWITCH_INTERVAL_S)  # as the cycle driver sets it
    try:
        yield
    finally:
        sys.setswitchinterval(before)


def main(seconds: float | None = None) -> None:
    length = seconds if seconds is not None else DEFAULT_SECONDS
    cycles = max(10, round(length * 1000 / TARGET_MS))
    started = time.perf_counter()
    artifact = compiled(plant_program())
    print(
        f"recording benchmark: a program with {VARIABLES:,} variables (set points, counters, "
        f"noisy REALs, switching BOOLs) and {INPUTS} changing inputs, compiled in "
        f"{time.perf_counter() - started:.1f} s; {length:g} s per block"
    )
    with tempfile.TemporaryDirectory() as folder, _switch_interval():
        bench = Bench(artifact, Path(folder))
        for count in SETS:
            bench_set(bench, count, False, cycles)
        bench_set(bench, ALL_INPUTS_SET, True, cycles)


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0] if __doc__ else None)
    parser.add_argument(
        "--seconds", type=float, help="seconds with (and without) a recording per set (5)"
    )
    main(parser.parse_args().seconds)
