"""Cycle jitter with everything on (issue 16): the 1,000-statement program at a 10 ms
'fixed' target under the real cycle driver with its Zenoh link, while

- a client process watches 200 of its variables at 10 Hz (an engineer's online screen),
- a Modbus TCP client process reads the 100 served holding registers every 100 ms (an HMI),
- a recording of 100 variables writes every CPU cycle to a zstd MCAP file;

and on its own, with other programs keeping every CPU busy (a busy loop per CPU, at the
normal priority).

Beside it, the same resource with none of the three, measured in the same run: the
baseline. Last, everything on again with the bodies as C (runtime/code/native/), the runtime's
default. Run with `python -m tests.bench.bench_jitter_loaded [--seconds S]` (30 s per run
unless `--seconds` or `PADT_BENCH_SECONDS` says otherwise); it prints figures and asserts
nothing (machines are shared and noisy).
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from itertools import pairwise
from pathlib import Path

from backend.compiler.pipeline import compile_sources
from backend.compiler.source import SourceFile
from runtime.clock import RealClock
from runtime.code.native.tier import NativeTier
from runtime.contract.artifact import Artifact
from runtime.contract.protocol import RecordStart
from runtime.recorder import Recordings
from tests.bench.bench_language import thousand_statements
from tests.bench.bench_modbus import _field_io
from tests.bench.bench_runtime import (
    TARGET_NS,
    LoggedResource,
    Spread,
    _config,
    _ms,
    driven,
)
from tests.bench.bench_watch import START_TIMEOUT_S, select
from tests.bench.client_process import ClientProcess
from tests.support.ports import free_port

REGISTERS = 100  # served holding registers, %MW0..%MW99
WATCHED = 200
RECORDED = 100
PERIOD_MS = 100  # the watch set's and the HMI's period
DEFAULT_SECONDS = 30.0
SECONDS_ENV = "PADT_BENCH_SECONDS"


def _artifact() -> Artifact:
    registers = "\n".join(f"  r{n} AT %MW{n} : INT;" for n in range(REGISTERS))
    # the served image follows the program: one register counts the cycles
    served = f"VAR_GLOBAL\n{registers}\nEND_VAR\nPROGRAM Io\nr0 := r0 + 1;\nEND_PROGRAM\n"
    sources = [SourceFile("bench.st", thousand_statements()), SourceFile("io.st", served)]
    result = compile_sources(sources, resource=_config(), modbus={"serve": True})
    assert result.artifact is not None, [str(d) for d in result.diagnostics[:3]]
    return result.artifact


def hmi_client(port: int) -> None:
    """Reads the 100 served registers every 100 ms until the server goes; prints "ready"
    once connected, then the answered and failed reads."""
    from pymodbus.client import ModbusTcpClient
    from pymodbus.exceptions import ConnectionException

    client = ModbusTcpClient("127.0.0.1", port=port, timeout=3, retries=0)
    client.connect()  # type: ignore[no-untyped-call]
    print("ready", flush=True)
    done = failed = 0
    next_s = time.monotonic()
    try:
        while True:
            reply = client.read_holding_registers(1024, count=REGISTERS)
            done, failed = (done + 1, failed) if not reply.isError() else (done, failed + 1)
            next_s += PERIOD_MS / 1000
            time.sleep(max(0.0, next_s - time.monotonic()))
    except ConnectionException:
        pass  # the resource's run ended
    client.close()  # type: ignore[no-untyped-call]
    print(done, failed, flush=True)


LOADS = ("watch", "hmi", "recording")
# on its own, not in "everything on": other programs keeping every CPU of the machine busy
BUSY = "cpu"
BUSY_LOOP = "while True: pass"


def _periods(
    seconds: float, loads: frozenset[str], native: NativeTier | None = None
) -> tuple[list[int], list[str]]:
    """The periods of the resource running `seconds` with `loads` on (with `native`, its
    bodies as C); and what the loads did."""
    clock = RealClock()
    resource = LoggedResource("R", clock)
    resource.native = native
    resource.load(_artifact())
    resource.tier_up(wait=True)
    resource.start()
    port = free_port()
    field_io = _field_io(resource, port)
    said: list[str] = []
    with tempfile.TemporaryDirectory(prefix="padt-bench-jitter-") as folder:
        resource.recordings = Recordings(Path(folder))
        if "recording" in loads:
            paths = [v.path for v in resource.variables.infos()]
            recorded = select(paths, RECORDED)
            resource.recordings.start(resource, RecordStart(variables=recorded))
        watcher = hmi = None
        busy = []
        try:
            if BUSY in loads:  # at the normal priority, the runtime's cycle thread real-time
                loop = [sys.executable, "-c", BUSY_LOOP]
                busy = [subprocess.Popen(loop) for _ in range(os.cpu_count() or 1)]
            with driven(resource, clock) as endpoint:
                if "watch" in loads:
                    watcher = ClientProcess(
                        "tests.bench.bench_watch", endpoint, str(WATCHED), str(PERIOD_MS)
                    )
                    watcher.receive(START_TIMEOUT_S)  # watching
                if "hmi" in loads:
                    command = [sys.executable, "-m", "tests.bench.bench_jitter_loaded"]
                    command += ["--hmi", str(port)]
                    hmi = subprocess.Popen(command, stdout=subprocess.PIPE, text=True)
                    assert hmi.stdout is not None
                    hmi.stdout.readline()  # connected
                resource.log.starts_ns.clear()  # the window starts with every load on
                time.sleep(seconds)
                if watcher is not None:
                    arrivals = watcher.ask("stop")["arrivals"]
                    complete = sum(1 for _, _, count, _ in arrivals if count == WATCHED)
                    said.append(
                        f"watch: {len(arrivals)} messages of {WATCHED} values ({complete} complete)"
                    )
        finally:
            for process in busy:
                process.kill()
                process.wait()
            if watcher is not None:
                watcher.close()
            field_io.close()
            resource.recordings.close()
        if hmi is not None:
            out, _ = hmi.communicate(timeout=60)
            done, failed = (int(x) for x in out.split()[-2:])
            said.append(f"HMI: {done} reads of {REGISTERS} registers answered, {failed} failed")
        if "recording" in loads:
            info = resource.recordings.infos()[0]
            said.append(f"recording: {info.cycles:,} cycles, {info.dropped} dropped")
    return [b - a for a, b in pairwise(resource.log.starts_ns)], said


def _report(label: str, periods: list[int]) -> Spread | None:
    if not periods:
        print(f"  {label}: no periods")
        return None
    jitter = Spread.of([abs(p - TARGET_NS) for p in periods])
    over = sum(1 for p in periods if p > TARGET_NS + 1_000_000)
    print(f"  {label}: {len(periods):,} periods   jitter {_ms(jitter)}")
    print(f"    periods more than 1 ms too long: {over} ({100 * over / len(periods):.2f} %)")
    return jitter


def main(seconds: float | None = None) -> None:
    seconds = seconds or float(os.environ.get(SECONDS_ENV, DEFAULT_SECONDS))
    print(
        "jitter with everything on: 1,000-statement program, target cycle 10 ms 'fixed', "
        f"real CycleDriver with a Zenoh link, {seconds:g} s per run; loads: watch = {WATCHED} "
        f"values watched at 10 Hz by a client process, hmi = {REGISTERS} holding registers "
        f"read at 10 Hz by a Modbus client process, recording = {RECORDED} variables "
        f"recorded every cycle; on its own: {BUSY} = a busy loop per CPU in processes at the "
        "normal priority:"
    )
    runs = [frozenset[str]()] + [frozenset({load}) for load in LOADS] + [frozenset(LOADS)]
    runs.append(frozenset({BUSY}))
    p99: dict[frozenset[str], float] = {}
    for loads in runs:
        periods, said = _periods(seconds, loads)
        label = " + ".join(sorted(loads)) or "nothing on (baseline)"
        jitter = _report(label, periods)
        for line in said:
            print(f"    {line}")
        if jitter is not None:
            p99[loads] = jitter.p99
    if frozenset() in p99 and frozenset(LOADS) in p99:
        ratio = p99[frozenset(LOADS)] / max(1.0, p99[frozenset()])
        print(f"  -> jitter p99 everything on / nothing on: {ratio:.2f}")
    with tempfile.TemporaryDirectory(prefix="padt-bench-native-") as cache:
        native = NativeTier(Path(cache))
        if not native.available:
            print("  everything on, native code: no C compiler or no Python.h here, skipped")
            return
        periods, said = _periods(seconds, frozenset(LOADS), native)
        _report(" + ".join(sorted(LOADS)) + ", bodies as C (the runtime's default)", periods)
        for line in said:
            print(f"    {line}")


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, help="length of each run")
    parser.add_argument("--hmi", type=int, metavar="PORT", help="(internal) run the HMI client")
    options = parser.parse_args()
    if options.hmi:
        hmi_client(options.hmi)
    else:
        main(options.seconds)
