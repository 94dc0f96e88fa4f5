"""Modbus TCP benchmark (docs/modbus.md): what field I/O costs the CPU cycle, and what the
served image delivers while the resource runs.

1. The exchange per cycle for 1,000 mapped registers (`FieldIo.before_cycle` and
   `after_cycle`, on the cycle thread): 1,000 served holding registers (%MW), and 1,000
   input registers a device delivered (with storing them into their variables); beside
   the CPU cycle of the same configuration, as the baseline measured in the same run.
2. Server requests per second (reads of 100 holding registers, one client process on
   loopback, back to back) while the resource runs a 10 ms 'fixed' cycle under the real
   cycle driver with its Zenoh link.
3. The cycle jitter of that resource without Modbus traffic and with it (the same
   configuration, served in both runs).

Run with `python -m tests.bench.bench_modbus [--seconds S]` (10 s per timed run unless
`--seconds` or `PADT_BENCH_SECONDS` says otherwise). It prints figures and asserts nothing
about time (machines are shared and noisy).
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time
from collections.abc import Callable
from itertools import pairwise

from backend.compiler.pipeline import compile_sources
from backend.compiler.source import SourceFile
from runtime.clock import RealClock
from runtime.contract.artifact import Artifact
from runtime.field_io import FieldIo
from runtime.field_io.delivery import Delivery
from runtime.field_io.modbus.poller import DevicePoller
from runtime.resource import Resource
from tests.bench.bench_runtime import (
    TARGET_MS,
    TARGET_NS,
    LoggedResource,
    Spread,
    _config,
    _drive,
    _ms,
)
from tests.support.ports import free_port

REGISTERS = 1_000
READ_COUNT = 100  # registers per request of the client
DEFAULT_SECONDS = 10.0
SECONDS_ENV = "PADT_BENCH_SECONDS"


def _source(kind: str) -> str:
    """1,000 located INTs and a program that changes one of them every cycle."""
    names = "\n".join(f"  r{n} AT %{kind}W{n} : INT;" for n in range(REGISTERS))
    target = "r0 := r0 + 1;" if kind == "M" else "n := n + r0;"
    return (
        f"VAR_GLOBAL\n{names}\nEND_VAR\nPROGRAM Main\nVAR n : INT; END_VAR\n{target}\nEND_PROGRAM\n"
    )


def _artifact(kind: str, device_port: int = 0) -> Artifact:
    settings: dict[str, object] = {"serve": kind == "M"}
    if kind == "I":  # a device delivers every register
        points = [
            {"variable": f"r{n}", "area": "input_register", "address": n} for n in range(REGISTERS)
        ]
        settings["device"] = [
            {"name": "rack", "host": "127.0.0.1", "port": device_port, "timeout_ms": 100,
             "period_ms": 60_000, "point": points}
        ]  # fmt: skip
    text = _source(kind)
    result = compile_sources([SourceFile("bench.st", text)], resource=_config(), modbus=settings)
    assert result.artifact is not None, [str(d) for d in result.diagnostics[:3]]
    return result.artifact


def _field_io(resource: Resource, port: int | None = 0) -> FieldIo:
    field_io = FieldIo(
        lambda: resource.artifact, resource.variables, resource.io, resource.recorder,
        resource.running, port,
    )  # fmt: skip
    resource.field_io = field_io
    return field_io


def _timed_us(work: list[Callable[[], None]], cycles: int) -> Spread:
    samples = []
    for _ in range(cycles):
        started = time.perf_counter_ns()
        for step in work:
            step()
        samples.append((time.perf_counter_ns() - started) / 1e3)
    return Spread.of(samples)


def _print(label: str, spread: Spread) -> None:
    print(
        f"  {label:<52} mean {spread.mean:7.1f} us   p50 {spread.p50:7.1f} us   "
        f"p99 {spread.p99:7.1f} us"
    )


def _delivery(poller: DevicePoller) -> Callable[[], None]:
    """What a poll of the device hands over, once per cycle: every register changed."""
    values = {f"r{n}": n for n in range(REGISTERS)}

    def deliver() -> None:
        poller.delivery = Delivery(poller.delivery.seq + 1, values, True)

    return deliver


def bench_exchange(cycles: int = 5_000) -> None:
    print(f"exchange per CPU cycle, {REGISTERS:,} mapped registers ({cycles:,} cycles each):")
    clock = RealClock()
    for kind, label in (("M", "served (%MW, holding registers)"), ("I", "delivered (%IW)")):
        resource = Resource("R", clock)
        resource.load(_artifact(kind, free_port()))
        resource.start()
        field_io = _field_io(resource)
        field_io.before_cycle()  # starts the server or the poller (off the cycle thread)
        cycle = _timed_us([resource.cycle], cycles)
        if kind == "M":
            exchange = _timed_us([field_io.before_cycle, field_io.after_cycle], cycles)
        else:
            # the delivered values stored into their variables is the cycle's step 1, counted
            # here with the exchange
            steps = [_delivery(field_io.pollers[0]), field_io.before_cycle]
            steps += [resource.io.read_inputs, field_io.after_cycle]
            exchange = _timed_us(steps, cycles)
        _print(f"CPU cycle, {label} configuration (baseline)", cycle)
        _print(f"exchange, {label}", exchange)
        print(f"  -> exchange / CPU cycle (mean): {exchange.mean / cycle.mean:.2f}")
        field_io.close()


def _client(port: int, seconds: float) -> None:
    """The load: back-to-back reads of 100 holding registers; prints how many answered."""
    from pymodbus.client import ModbusTcpClient

    client = ModbusTcpClient("127.0.0.1", port=port, timeout=3)
    client.connect()  # type: ignore[no-untyped-call]
    done = failed = 0
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        reply = client.read_holding_registers(1024, count=READ_COUNT)
        if reply.isError():
            failed += 1
        else:
            done += 1
    client.close()  # type: ignore[no-untyped-call]
    print(done, failed)


def _run(seconds: float, traffic: bool) -> tuple[list[int], int, int]:
    """The periods of a resource serving 1,000 registers at a 10 ms cycle, and the
    requests a client process got answered (and refused) meanwhile."""
    clock = RealClock()
    resource = LoggedResource("R", clock)
    resource.load(_artifact("M"))
    resource.start()
    port = free_port()
    field_io = _field_io(resource, port)
    client = None
    if traffic:
        command = [sys.executable, "-m", "tests.bench.bench_modbus", "--client", str(port)]
        command += ["--seconds", str(seconds - 1.0)]
        client = subprocess.Popen(command, stdout=subprocess.PIPE, text=True)

    try:
        _drive(resource, clock, seconds)
    finally:
        field_io.close()
    done = failed = 0
    if client is not None:
        out, _ = client.communicate(timeout=30)
        done, failed = (int(x) for x in out.split()[-2:])
    periods = [b - a for a, b in pairwise(resource.log.starts_ns)]
    return periods, done, failed


def bench_served(seconds: float) -> None:
    print(
        f"served image, {REGISTERS:,} holding registers, target cycle {TARGET_MS} ms 'fixed', "
        f"real CycleDriver with a Zenoh link, {seconds:g} s per run:"
    )
    quiet, _, _ = _run(seconds, traffic=False)
    busy, done, failed = _run(seconds, traffic=True)
    rate = done / max(0.001, seconds - 1.0)
    print(
        f"  server: {rate:,.0f} requests/s of {READ_COUNT} registers answered "
        f"({failed} refused), one client process on loopback"
    )
    for label, periods in (("without Modbus traffic", quiet), ("with Modbus traffic", busy)):
        if not periods:
            print(f"  {label}: no periods")
            continue
        jitter = [abs(p - TARGET_NS) for p in periods]
        over = sum(1 for p in periods if p > TARGET_NS + 1_000_000)
        print(f"  {label}: {len(periods):,} periods   jitter {_ms(Spread.of(jitter))}")
        print(f"    periods more than 1 ms too long: {over} ({100 * over / len(periods):.2f} %)")
    if quiet and busy:
        ratio = Spread.of([abs(p - TARGET_NS) for p in busy]).p99 / max(
            1.0, Spread.of([abs(p - TARGET_NS) for p in quiet]).p99
        )
        print(f"  -> jitter p99 with / without traffic: {ratio:.2f}")


def main(seconds: float | None = None) -> None:
    if seconds is None:
        seconds = float(os.environ.get(SECONDS_ENV, DEFAULT_SECONDS))
    bench_exchange()
    bench_served(seconds)


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0] if __doc__ else None)
    parser.add_argument("--seconds", type=float, default=None)
    parser.add_argument("--client", type=int, default=None, metavar="PORT", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.client is not None:
        _client(args.client, args.seconds or DEFAULT_SECONDS)
    else:
        main(args.seconds)
