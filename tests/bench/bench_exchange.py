"""The exchange between resources (docs/exchange.md) across two Zenoh routers: real
`padt router` and `padt runtime` processes on this host, the routers linked through a
link with a network's delay and losses (tests/support/impaired_link.py: this kernel has no
netem, so the link is a proxy in user space).

    Producer -- router A -- [link: delay, loss, down/up] -- router B -- Consumer

1. **Latency** from a write in one resource to the value in another: the bench writes
   `gSet` in Producer (an online write), Producer publishes it every 10 ms, Consumer takes
   it into `gGot` and its program copies it to `gEcho`, which Consumer publishes every
   10 ms; the bench, on router B, notes when the echo carries the value written. So each
   figure holds two publication periods (0..10 ms each), a Consumer cycle (5 ms), the
   write's command and three hops; p50 and p99 of 200 writes, over a plain link, with 5 ms
   of delay each way, and with 5 ms and 1 % loss.
2. **Jitter while the link flaps**: Consumer's cycle statistics over a window with the
   link steady, and over one with the link down and up every 0.5 s (its subscription
   going stale and coming back each time).
3. **Values a second**: Producer publishes 1, 2 and 4 publications of 1,000 DINT values
   every 10 ms; how many values a second Consumer takes (messages taken times 1,000), and
   the CPU both runtimes use meanwhile.

Run with `python -m tests.bench.bench_exchange [--seconds S]` (5 s per window unless
`--seconds` or `PADT_BENCH_SECONDS` says otherwise). It prints figures and asserts nothing
about time (machines are shared and noisy).
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import zenoh

from backend.engineering.resource_client import ResourceClient
from runtime.contract.keyspace import exchange_key
from runtime.contract.protocol import GetEvents, GetStatus, ResetStats, Write
from runtime.contract.session import open_client
from tests.support.impaired_link import ImpairedLink, impaired_link
from tests.support.ports import free_port
from tests.support.runtime_process import runtime_process, stored_project, wait_until_answering

REPO = Path(__file__).resolve().parents[2]
SECONDS_ENV, DEFAULT_SECONDS = "PADT_BENCH_SECONDS", 5.0
WRITES = 200
BULK = 1000  # values in one publication of the throughput case


def _producer(publications: int) -> tuple[str, str]:
    bulk = [f"b{p}_{i}" for p in range(publications) for i in range(BULK)]
    source = "VAR_GLOBAL gSet : DINT; gTick : DINT;\n"
    source += "".join(f"{name} : DINT;\n" for name in bulk) + "END_VAR\n"
    source += "PROGRAM Main\nVAR_EXTERNAL gTick : DINT; END_VAR\ngTick := gTick + 1;\nEND_PROGRAM\n"
    settings = _head("Producer") + (
        '[[exchange.publish]]\nname = "set"\nvariables = ["gSet", "gTick"]\nperiod_ms = 10\n'
    )
    for p in range(publications):
        names = ", ".join(f'"b{p}_{i}"' for i in range(BULK))
        settings += (
            f'[[exchange.publish]]\nname = "bulk{p}"\nvariables = [{names}]\nperiod_ms = 10\n'
        )
    return source, settings


def _consumer(publications: int) -> tuple[str, str]:
    bulk = [f"b{p}_{i}" for p in range(publications) for i in range(BULK)]
    source = "VAR_GLOBAL gGot : DINT; gEcho : DINT;\n"
    source += "".join(f"{name} : DINT;\n" for name in bulk) + "END_VAR\n"
    source += (
        "PROGRAM Main\nVAR_EXTERNAL gGot : DINT; gEcho : DINT; END_VAR\n"
        "gEcho := gGot;\nEND_PROGRAM\n"
    )
    settings = _head("Consumer") + (
        '[[exchange.publish]]\nname = "echo"\nvariables = ["gEcho"]\nperiod_ms = 10\n'
        '[[exchange.subscribe]]\nresource = "Producer"\npublication = "set"\ntimeout_ms = 300\n'
        '[[exchange.subscribe.variable]]\nvariable = "gGot"\nfrom = "gSet"\n'
    )
    for p in range(publications):
        settings += (
            f'[[exchange.subscribe]]\nresource = "Producer"\npublication = "bulk{p}"\n'
            "timeout_ms = 300\n"
        )
        settings += "".join(
            f'[[exchange.subscribe.variable]]\nvariable = "b{p}_{i}"\n' for i in range(BULK)
        )
    return source, settings


def _head(resource: str) -> str:
    return (
        f'[project]\nname = "{resource.lower()}"\n[resource]\nname = "{resource}"\n'
        'autostart = "cold"\ntarget_cycle_ms = 5\nsafety_operation = false\n'
    )


@contextlib.contextmanager
def _router(port: int, connect: int | None = None) -> Iterator[None]:
    command = [sys.executable, "-m", "padt.cli", "router", "--listen", f"tcp/127.0.0.1:{port}"]
    if connect is not None:
        command += ["--connect", f"tcp/127.0.0.1:{connect}"]
    process = subprocess.Popen(command, cwd=REPO, stdout=subprocess.PIPE, text=True)
    try:
        assert process.stdout is not None and "listening" in process.stdout.readline()
        yield
    finally:
        process.terminate()
        process.wait(10)


def _cpu_s(pid: int) -> float:
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


class _Echoes:
    """When each value of Consumer's echo publication was first seen (router B's side)."""

    def __init__(self, session: zenoh.Session) -> None:
        self.seen: dict[int, float] = {}
        self._lock = threading.Lock()
        self._subscriber = session.declare_subscriber(exchange_key("Consumer", "echo"), self._on)

    def _on(self, sample: zenoh.Sample) -> None:
        now = time.monotonic()
        value = json.loads(sample.payload.to_bytes())["values"]["gEcho"][1]
        with self._lock:
            self.seen.setdefault(value, now)

    def wait(self, value: int, timeout_s: float = 5.0) -> float | None:
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            with self._lock:
                if value in self.seen:
                    return self.seen[value]
            time.sleep(0.0005)
        return None


def _latencies(producer: ResourceClient, echoes: _Echoes, first: int) -> list[float]:
    found = []
    for value in range(first, first + WRITES):
        started = time.monotonic()
        producer.ask(Write("gSet", value))
        seen = echoes.wait(value)
        if seen is not None:
            found.append((seen - started) * 1000)
        time.sleep(0.02)
    return found


def _percentiles(values: list[float]) -> str:
    if not values:
        return "no value arrived"
    ordered = sorted(values)
    p99 = ordered[min(len(ordered) - 1, round(0.99 * (len(ordered) - 1)))]
    return (
        f"p50 {statistics.median(ordered):6.1f} ms  p99 {p99:6.1f} ms  "
        f"max {ordered[-1]:6.1f} ms  ({len(values)}/{WRITES} arrived)"
    )


@dataclass
class _Plant:
    link: ImpairedLink
    producer: ResourceClient
    consumer: ResourceClient
    echoes: _Echoes
    pids: tuple[int, int]  # Producer's, Consumer's

    def settled(self) -> None:
        """Both cycle and Consumer holds Producer's values (the first C builds are done)."""
        deadline = time.monotonic() + 120
        value = -7
        while time.monotonic() < deadline:
            self.producer.ask(Write("gSet", value))
            if self.echoes.wait(value, 1.0) is not None:
                return
            value -= 1
        raise RuntimeError("the exchange never settled")


@contextlib.contextmanager
def _plant(folder: Path, publications: int) -> Iterator[_Plant]:
    producer_state = stored_project(
        folder / f"p{publications}", "producer", *_producer(publications)
    )
    consumer_state = stored_project(
        folder / f"p{publications}", "consumer", *_consumer(publications)
    )
    port_a, port_b, port_link = free_port(), free_port(), free_port()
    a, b = f"tcp/127.0.0.1:{port_a}", f"tcp/127.0.0.1:{port_b}"
    with (
        _router(port_a),
        impaired_link(port_link, port_a) as link,
        _router(port_b, connect=port_link),
        runtime_process("Producer", producer_state, a) as producer_process,
        runtime_process("Consumer", consumer_state, b) as consumer_process,
        contextlib.closing(open_client(a)) as session_a,
        contextlib.closing(open_client(b)) as session_b,
    ):
        producer = ResourceClient(session_a, "Producer")
        consumer = ResourceClient(session_b, "Consumer")
        wait_until_answering(producer, 60)
        wait_until_answering(consumer, 60)
        plant = _Plant(
            link, producer, consumer, _Echoes(session_b),
            (producer_process.pid, consumer_process.pid),
        )  # fmt: skip
        plant.settled()
        yield plant


def bench_latency(folder: Path) -> None:
    print("exchange between resources, across two routers (write in Producer -> value in")
    print("Consumer -> its echo seen; two 10 ms publication periods and a 5 ms cycle inside):")
    with _plant(folder, 0) as plant:
        first = 1
        for label, delay_ms, loss in (
            ("plain link", 0.0, 0.0),
            ("5 ms each way", 5.0, 0.0),
            ("5 ms each way, 1 % loss", 5.0, 0.01),
        ):
            plant.link.delay_ms, plant.link.loss = delay_ms, loss
            plant.settled()
            found = _latencies(plant.producer, plant.echoes, first)
            first += WRITES
            print(f"  {label:26} {_percentiles(found)}")
        plant.link.delay_ms, plant.link.loss = 0.0, 0.0


def bench_flapping(folder: Path, seconds: float) -> None:
    print("Consumer's cycle (target 5 ms) while its link to Producer flaps (down 1 s, up 2 s):")
    with _plant(folder, 0) as plant:
        for label, flapping in (("link steady", False), ("link flapping", True)):
            plant.settled()
            plant.consumer.ask(ResetStats())
            after = _last_event(plant.consumer)
            downs: list[int] = []
            ups: list[int] = []
            ends = time.monotonic() + 2 * seconds
            while time.monotonic() < ends:
                if flapping:
                    downs.append(time.time_ns())
                    plant.link.down()
                    time.sleep(1.0)
                    ups.append(time.time_ns())
                    plant.link.up()
                time.sleep(2.0)
            time.sleep(2.0)  # the last recovery, if it is slow
            stats = plant.consumer.ask(GetStatus()).status.stats
            events = plant.consumer.ask(GetEvents(limit=1000, after=after)).events
            lost = [e.time_ns for e in events if e.message.startswith("Exchange Producer/set lost")]
            back = [e.time_ns for e in events if "Producer/set connected again" in e.message]
            print(
                f"  {label:14} {stats.count} cycles, mean {stats.mean_ms:.2f} ms, max "
                f"{stats.max_ms:.2f} ms, jitter max {stats.jitter_max_ms:.2f} ms, "
                f"{stats.overruns} overruns; {len(downs)} cuts, {len(lost)} times stale, "
                f"{len(back)} times back"
            )
            if downs:
                print(
                    f"  {'':14} safe values after a cut: {_after(downs, lost)} (timeout 300 ms); "
                    f"values back after the link: {_after(ups, back)}"
                )


def _last_event(client: ResourceClient) -> int:
    """The sequence number of the newest event (the log answers oldest first)."""
    seq = 0
    while events := client.ask(GetEvents(limit=1000, after=seq)).events:
        seq = events[-1].seq
    return seq


def _after(causes: list[int], effects: list[int]) -> str:
    """The time from each cause to the first effect after it, in ms: median and max."""
    found = []
    for cause in causes:
        later = [effect for effect in effects if effect >= cause]
        if later:
            found.append((min(later) - cause) / 1e6)
    if not found:
        return "never"
    return f"median {statistics.median(found):.0f} ms, max {max(found):.0f} ms"


def bench_throughput(folder: Path, seconds: float) -> None:
    print(f"values a second taken (publications of {BULK:,} DINT every 10 ms):")
    for publications in (1, 2, 4):
        with _plant(folder, publications) as plant:

            def taken() -> int:
                io = plant.consumer.ask(GetStatus()).status.io
                assert io is not None
                return sum(d.requests for d in io.devices if d.name.startswith("Producer/bulk"))

            before, cpu_before = taken(), [_cpu_s(pid) for pid in plant.pids]
            started = time.monotonic()
            time.sleep(seconds)
            elapsed = time.monotonic() - started
            messages = taken() - before
            stats = plant.consumer.ask(GetStatus()).status.stats
            cpu = [
                (_cpu_s(pid) - was) / elapsed * 100
                for pid, was in zip(plant.pids, cpu_before, strict=True)
            ]
            offered = publications * BULK * 100
            print(
                f"  {publications} x {BULK:,}: offered {offered:9,}/s, taken "
                f"{messages * BULK / elapsed:11,.0f}/s; CPU Producer {cpu[0]:3.0f} %, "
                f"Consumer {cpu[1]:3.0f} %; Consumer's cycle mean {stats.mean_ms:.2f} ms, "
                f"max {stats.max_ms:.2f} ms"
            )


def main(seconds: float | None = None) -> None:
    if seconds is None:
        seconds = float(os.environ.get(SECONDS_ENV, DEFAULT_SECONDS))
    with tempfile.TemporaryDirectory(prefix="padt-bench-exchange-") as folder:
        bench_latency(Path(folder) / "latency")
        bench_flapping(Path(folder) / "flapping", seconds)
        bench_throughput(Path(folder) / "throughput", seconds)


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0] if __doc__ else None)
    parser.add_argument("--seconds", type=float, default=None)
    main(parser.parse_args().seconds)
