"""Watch-set benchmark: live values of 10,000 variables (and of 100, for comparison) at
10 Hz from the runtime to a backend client, under the real cycle driver at a 10 ms 'fixed'
target cycle. It prints the delivered rate against the expected 10 messages per second,
the message size, the latency from the end of the CPU cycle that produced the values to
their arrival in the client's callback (p50 / p99 / max), and the runtime's extra time for
the watch set (building the message and publishing it), per publication and per CPU cycle
as a share of the 10 ms cycle.

The runtime (router, cycle driver, link) runs in this process; the client is a separate
process (`ResourceClient.watch` in `python -m tests.bench.bench_watch --client ...`), so
that decoding 10,000 values does not compete with the cycle for this interpreter. Both
stamp events with `time.monotonic_ns()`, CLOCK_MONOTONIC on Linux: one clock for every
process of the machine. All timing is wrapped around the runtime here (a Resource and a
ResourceLink subclass), never put into runtime code.

Run with `python -m tests.bench.bench_watch [--seconds S]`; each set is watched for 20 s
unless `--seconds` or `PADT_BENCH_SECONDS` says otherwise. It prints figures and asserts
nothing about time (machines are shared and noisy).
"""

from __future__ import annotations

import argparse
import json
import os
import queue
import secrets
import sys
import threading
import time
import traceback
from collections import Counter
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from itertools import pairwise
from pathlib import Path
from typing import Any

import zenoh

from backend.engineering.resource_client import ResourceClient
from backend.engineering.start_up_freeze import freeze_start_up
from runtime.clock import Clock, RealClock
from runtime.collector import COLLECTOR
from runtime.contract.artifact import Artifact
from runtime.contract.keyspace import watch_key, watcher_key
from runtime.contract.protocol import (
    MAX_REQUEST_BYTES,
    GetVariables,
    ProgramState,
    Quality,
    ResourceState,
    WatchValues,
)
from runtime.contract.refusal import Refusal
from runtime.contract.session import open_client, open_router
from runtime.cycle_driver import CycleDriver
from runtime.force_table import ForceTable
from runtime.link import ResourceLink
from runtime.online_values import OnlineValues
from runtime.resource import Resource
from runtime.runtime_priority import DEFAULT_CYCLE_PRIORITY, DEFAULT_NICE, raise_priority
from runtime.variables import Variables
from runtime.watch_sets import WatchSet, WatchSnapshot
from tests.bench.bench_runtime import (
    SECONDS_ENV,
    TARGET_MS,
    TARGET_NS,
    TOLERANCE_NS,
    Spread,
    _compile,
    ten_thousand_paths,
)
from tests.bench.client_process import ClientProcess
from tests.support.ports import free_port

REPO = Path(__file__).resolve().parents[2]
RESOURCE = "R"  # the name bench_runtime's configuration gives the resource
DEFAULT_SECONDS = 20.0
PERIOD_MS = 100  # 10 Hz
# the watch set, with the cycle thread as `padt runtime` runs it (real-time) and,
# as the baseline, at the runtime's nice value alone; then a small set for comparison
SETS = ((10_000, DEFAULT_CYCLE_PRIORITY), (10_000, 0), (100, DEFAULT_CYCLE_PRIORITY))
SETTLE_S = 2.0  # after the window, for the last messages to arrive
START_TIMEOUT_S = 60.0  # client start-up (imports, connecting) and first publications
DUMPS_ROUNDS = 10


# ---- the runtime side, timed from outside ------------------------------------------------------


@dataclass(frozen=True)
class Publication:
    """One watch-set message the cycle driver sent, with the time it spent on it."""

    watch_id: str
    cycle: int  # the message's "cycle": the CPU cycle whose values it carries
    watched_ns: int  # Resource.watched: reading the values, with their quality
    publish_ns: int  # ResourceLink.publish_watch on the cycle thread: the hand-over
    values: int = 0  # in the message: fewer while a large set is still being registered

    @property
    def total_ns(self) -> int:
        return self.watched_ns + self.publish_ns


@dataclass
class PublicationLog:
    publications: list[Publication] = field(default_factory=list)
    last_watched_ns: int = 0  # the driver calls watched() right before publish_watch()


class TimedResource(Resource):
    """Notes when each CPU cycle starts and ends (monotonic ns, by the cycle count it
    leaves behind, which is the "cycle" of a watch message) and how long `watched()`
    takes. It also registers watch sets handed to it by another thread, in the cycle
    thread between two cycles, as a command would be."""

    def __init__(self, name: str, clock: Clock, log: PublicationLog) -> None:
        super().__init__(name, clock)
        self.online = TimedOnlineValues(self.variables, log)
        self.starts_ns: dict[int, int] = {}
        self.ends_ns: dict[int, int] = {}
        self.pending: queue.Queue[Callable[[], object]] = queue.Queue()
        self.pending_errors: list[str] = []

    def cycle(self) -> None:
        self._register_pending()
        before = self.cycle_count
        started = time.monotonic_ns()
        super().cycle()
        ended = time.monotonic_ns()
        if self.cycle_count != before:
            self.starts_ns[self.cycle_count] = started
            self.ends_ns[self.cycle_count] = ended

    def _register_pending(self) -> None:
        while True:
            try:
                action = self.pending.get_nowait()
            except queue.Empty:
                return
            try:
                action()
            except Exception as exc:  # never let the benchmark's own work stop the resource
                self.pending_errors.append(f"{type(exc).__name__}: {exc}")


class TimedOnlineValues(OnlineValues):
    """Online values that note how long reading a watch set's snapshot takes."""

    def __init__(self, variables: Variables, log: PublicationLog) -> None:
        super().__init__(variables)
        self.publication_log = log

    def snapshot(
        self,
        watch_set: WatchSet,
        cycle: int,
        running: bool,
        forces: ForceTable,
        bad: frozenset[str] = frozenset(),
    ) -> WatchSnapshot:
        started = time.monotonic_ns()
        snapshot = super().snapshot(watch_set, cycle, running, forces, bad)
        self.publication_log.last_watched_ns = time.monotonic_ns() - started
        return snapshot


class TimedLink(ResourceLink):
    """Times each watch-set publication on the cycle thread (handing the snapshot to the
    publisher thread, which encodes and puts it)."""

    def __init__(self, session: zenoh.Session, resource: Resource, log: PublicationLog) -> None:
        super().__init__(session, resource.name, resource.identity)
        self.publication_log = log

    def publish_watch(self, watch_id: str, snapshot: WatchSnapshot) -> None:
        started = time.monotonic_ns()
        super().publish_watch(watch_id, snapshot)
        spent = time.monotonic_ns() - started
        log = self.publication_log
        log.publications.append(
            Publication(watch_id, snapshot.cycle, log.last_watched_ns, spent, len(snapshot.values))
        )


def select(paths: Sequence[str], count: int) -> list[str]:
    """`count` variables spread evenly over `paths` (all of them when there are no more);
    the client and this process pick the same ones from the same list."""
    if count >= len(paths):
        return list(paths)
    return [paths[n * len(paths) // count] for n in range(count)]


@contextmanager
def serving(
    resource: TimedResource, clock: Clock, log: PublicationLog, cycle_priority: int
) -> Iterator[str]:
    """A Zenoh router on loopback, the runtime's session and link, and the real cycle
    driver on its own thread; yields the endpoint for the client."""
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    router = open_router(endpoint)
    try:
        session = open_client(endpoint)
        try:
            link = TimedLink(session, resource, log)
            try:
                stop = threading.Event()
                driver = CycleDriver(resource, clock, link, cycle_priority=cycle_priority)
                thread = threading.Thread(target=driver.run, args=(stop,), name="padt-cycle")
                thread.start()
                try:
                    yield endpoint
                finally:
                    stop.set()
                    thread.join()
            finally:
                link.close()
        finally:
            session.close()
    finally:
        router.close()


# ---- the client process ------------------------------------------------------------------------


def _say(message: dict[str, Any]) -> None:
    print(json.dumps(message), flush=True)


def client_main(endpoint: str, count: int, period_ms: int) -> None:
    """The backend side: watch `count` variables until a line (or EOF) on stdin, then
    print what arrived, as (cycle, monotonic ns on arrival, values, of which live)."""
    session = open_client(endpoint)
    try:
        client = ResourceClient(session, RESOURCE)
        client.wait_until_answering()
        paths = [v.path for v in client.ask(GetVariables()).variables]
        selection = select(paths, count)
        arrivals: list[tuple[int, int, int, int]] = []

        def on_values(message: WatchValues) -> None:
            arrived = time.monotonic_ns()
            values = message.values
            live = sum(1 for value in values.values() if value.quality == Quality.LIVE)
            arrivals.append((message.cycle, arrived, len(values), live))

        close: Callable[[], None]
        try:
            watch = client.watch(selection, on_values, period_ms)
            hello = {"ready": watch.watch_id, "mode": "client", "variables": len(watch.variables)}
            close = watch.close
        except Refusal as refused:
            # the same subscription and liveliness token as ResourceClient.watch; the
            # benchmark process registers the set in the runtime instead of the command
            watch_id = secrets.token_hex(8)

            def on_sample(sample: zenoh.Sample) -> None:
                on_values(json.loads(sample.payload.to_bytes()))

            subscriber = session.declare_subscriber(watch_key(RESOURCE, watch_id), on_sample)
            token = session.liveliness().declare_token(watcher_key(RESOURCE, watch_id))

            def close_direct() -> None:
                token.undeclare()
                subscriber.undeclare()

            hello = {"ready": watch_id, "mode": "direct", "refused": str(refused)}
            close = close_direct
        freeze_start_up()  # as the PADT's API and UI processes do once they serve
        _say(hello)
        sys.stdin.readline()
        close()
        _say({"arrivals": list(arrivals)})
    finally:
        session.close()


# ---- one watch set ------------------------------------------------------------------------------


def _ms(ns: float) -> str:
    return f"{ns / 1e6:.3f} ms"


def _spread_ms(spread: Spread) -> str:
    return (
        f"mean {_ms(spread.mean)}   p50 {_ms(spread.p50)}   p99 {_ms(spread.p99)}   "
        f"max {_ms(spread.max)}"
    )


def _wait_for_publications(
    log: PublicationLog, watch_id: str, count: int, timeout_s: float
) -> list[Publication]:
    deadline = time.monotonic() + timeout_s
    while True:
        mine = [p for p in log.publications if p.watch_id == watch_id]
        if len(mine) >= count or time.monotonic() > deadline:
            return mine
        time.sleep(0.01)


def bench_watch_set(artifact: Artifact, count: int, seconds: float, cycle_priority: int) -> None:
    clock = RealClock()
    log = PublicationLog()
    resource = TimedResource(RESOURCE, clock, log)
    resource.load(artifact)
    COLLECTOR.manage()  # as the runtime process does before its first cycle
    resource.start()
    selection = select([v.path for v in resource.variables.infos()], count)
    print(
        f"watch set of {len(selection):,} variables every {PERIOD_MS} ms, {seconds:g} s; "
        f"target cycle {TARGET_MS} ms 'fixed', real CycleDriver, client in a separate process; "
        f"cycle thread: {_scheduling(cycle_priority)}:"
    )
    with serving(resource, clock, log, cycle_priority) as endpoint:
        client = ClientProcess("tests.bench.bench_watch", endpoint, str(count), str(PERIOD_MS))
        try:
            hello = client.receive(START_TIMEOUT_S)
            watch_id = str(hello["ready"])
            if hello["mode"] == "direct":
                request = {"cmd": "watch", "id": watch_id, "variables": selection}
                print(
                    "  registration: ResourceClient.watch refused it "
                    f"({hello['refused']}; the request is {len(json.dumps(request)):,} "
                    f"bytes, the limit {MAX_REQUEST_BYTES:,}); registered in the runtime "
                    "process instead (Resource.watch between two cycles), same publication path"
                )
                resource.pending.put(
                    lambda: resource.online.watch(
                        watch_id, selection, PERIOD_MS, False, None, clock.now_ns()
                    )
                )
            else:
                print(f"  registration: ResourceClient.watch ({hello['variables']:,} variables)")
            # the first message goes out at once on registration, after a command and not
            # after a cycle: the window starts with the second
            published = _wait_for_publications(log, watch_id, 2, START_TIMEOUT_S)
            if len(published) < 2:
                print(f"  WARNING: {len(published)} publication(s) in {START_TIMEOUT_S:g} s")
                for error in resource.pending_errors:
                    print(f"  registration error: {error}")
                return
            window_start = resource.ends_ns[published[1].cycle]
            window_end = window_start + int(seconds * 1e9)
            time.sleep(max(0.0, (window_end - time.monotonic_ns()) / 1e9) + SETTLE_S)
            arrivals = client.ask("stop")["arrivals"]
        finally:
            client.close()
    _report(resource, log, watch_id, selection, arrivals, window_start, window_end)


def _report(
    resource: TimedResource,
    log: PublicationLog,
    watch_id: str,
    selection: list[str],
    arrivals: list[list[int]],
    window_start: int,
    window_end: int,
) -> None:
    seconds = (window_end - window_start) / 1e9
    ends = resource.ends_ns
    expected = seconds * 1000 / PERIOD_MS

    def in_window(cycle: int) -> bool:
        return cycle in ends and window_start <= ends[cycle] < window_end

    # a set registered in several requests is published part by part meanwhile; a client
    # takes only the whole set's messages (their revision), so only those count
    mine = [p for p in log.publications if p.watch_id == watch_id and p.values == len(selection)]
    sent = [p for p in mine if in_window(p.cycle)]
    sent_cycles = {p.cycle for p in sent}
    cycles = sorted(c for c in ends if in_window(c))

    # the message: its size as publish_watch encodes it, and the encoding alone
    snapshot = resource.online.snapshot(
        WatchSet(watch_id, tuple(selection), PERIOD_MS * 1_000_000),
        resource.cycle_count,
        resource.running(),
        resource.forcing.table,
    )
    encoded = snapshot.message()
    dumps_ns = []
    for _ in range(DUMPS_ROUNDS):  # what the publisher thread does, off the cycle thread
        started = time.monotonic_ns()
        snapshot.message()
        dumps_ns.append(time.monotonic_ns() - started)
    print(
        f"  message: {len(snapshot.values):,} values, {len(encoded):,} bytes "
        f"({len(encoded) / 1024:,.1f} KiB) of JSON"
    )

    gaps = Counter(b - a for a, b in pairwise(sorted(sent_cycles)))
    gap_text = ", ".join(f"{gap} cycles x{n}" for gap, n in sorted(gaps.items()))
    print(
        f"  published: {len(sent)} in {seconds:g} s = {len(sent) / seconds:.2f}/s "
        f"(expected {expected / seconds:.0f}/s); CPU cycles between two: {gap_text or '-'}"
    )

    arrived: dict[int, list[int]] = {}
    for cycle, at_ns, values, live in arrivals:
        arrived.setdefault(cycle, [at_ns, values, live])
    delivered = [c for c in sorted(sent_cycles) if c in arrived]
    duplicates = len(arrivals) - len(arrived)
    print(
        f"  delivered: {len(delivered)} of {len(sent)} published = "
        f"{len(delivered) / seconds:.2f} messages/s (expected {expected / seconds:.0f}/s, "
        f"{len(delivered) / expected:.1%} of expected); lost {len(sent) - len(delivered)}"
        + (f"; {duplicates} duplicate(s)" if duplicates else "")
    )
    short = [c for c in delivered if arrived[c][1] != len(selection)]
    not_live = [c for c in delivered if arrived[c][2] != arrived[c][1]]
    if short or not_live:
        print(
            f"  WARNING: {len(short)} message(s) with fewer values than watched, "
            f"{len(not_live)} with values not 'live'"
        )
    if delivered:
        latency = Spread.of([arrived[c][0] - ends[c] for c in delivered])
        print(
            "  latency, end of the producing CPU cycle -> client callback (decoded): "
            f"p50 {_ms(latency.p50)}   p99 {_ms(latency.p99)}   max {_ms(latency.max)}"
            f"   (mean {_ms(latency.mean)})"
        )

    if sent:
        print("  runtime time per publication (in the cycle thread, after the cycle):")
        print(
            f"    Resource.watched()          {_spread_ms(Spread.of([p.watched_ns for p in sent]))}"
        )
        print(
            f"    ResourceLink.publish_watch  {_spread_ms(Spread.of([p.publish_ns for p in sent]))}"
        )
        print(
            f"    (on the publisher thread, not in the cycle: building and encoding the "
            f"message, timed apart over {DUMPS_ROUNDS} calls: "
            f"mean {_ms(sum(dumps_ns) / len(dumps_ns))}   best {_ms(min(dumps_ns))})"
        )
        per_publication = Spread.of([p.total_ns for p in sent])
        print(f"    both                        {_spread_ms(per_publication)}")
        print(
            f"    -> per publication: {per_publication.mean / TARGET_NS:.1%} of the "
            f"{TARGET_MS} ms cycle (mean), {per_publication.max / TARGET_NS:.1%} (max)"
        )
    if cycles:
        spent = sum(p.total_ns for p in sent)
        extra = spent / len(cycles)
        print(
            f"  runtime extra time per CPU cycle for the watch set (averaged over "
            f"{len(cycles):,} cycles; {seconds * 1e3 / TARGET_MS:,.0f} at {TARGET_MS} ms): "
            f"{_ms(extra)} = {extra / TARGET_NS:.2%} of the {TARGET_MS} ms cycle"
        )
        print(
            f"    (publication time / window: {spent / (window_end - window_start):.2%} "
            "of the wall-clock time)"
        )

    periods = {c: resource.starts_ns[c] - resource.starts_ns[c - 1] for c in cycles[1:]}
    if periods:
        late = [c for c, p in periods.items() if p > TARGET_NS + TOLERANCE_NS]
        after_publication = [c for c in late if c - 1 in sent_cycles]
        print(
            f"  CPU cycle period: {_spread_ms(Spread.of(list(periods.values())))}; "
            f"{len(late)} of {len(periods):,} > {TARGET_MS} ms + "
            f"{TOLERANCE_NS // 1_000_000} ms, {len(after_publication)} of them right after "
            "a publication"
        )
    if resource.state not in (ResourceState.RUN, ResourceState.RUN_UP_STOP):
        print(f"  WARNING: resource in {resource.state} ({resource.error})")
    for program in resource.programs:
        if program.state != ProgramState.RUN:
            print(f"  WARNING: program {program.name} is {program.state}: {program.error}")
    for error in resource.pending_errors:
        print(f"  WARNING: registration error: {error}")


# ---- entry points ------------------------------------------------------------------------------


def watch_seconds(seconds: float | None = None) -> float:
    """How long each set is watched: the argument, else $PADT_BENCH_SECONDS, else 20 s."""
    if seconds is not None:
        return seconds
    return float(os.environ.get(SECONDS_ENV, DEFAULT_SECONDS))


def _scheduling(cycle_priority: int) -> str:
    if not cycle_priority:
        return "the runtime's nice value (baseline)"
    return f"SCHED_FIFO {cycle_priority} (as `padt runtime` runs it, where allowed)"


def main(seconds: float | None = None) -> None:
    length = watch_seconds(seconds)
    # the runtime's priority, as `padt runtime` takes it before its threads start
    priority = raise_priority(DEFAULT_NICE)
    started = time.perf_counter()
    artifact = _compile(ten_thousand_paths())
    print(
        "watch-set benchmark: a program with 10,000 variables (bench_runtime's), "
        f"compiled in {time.perf_counter() - started:.1f} s; the runtime at {priority}, "
        "the client at normal priority"
    )
    for count, cycle_priority in SETS:
        try:
            bench_watch_set(artifact, count, length, cycle_priority)
        except Exception:  # report and go on: the other set still says something
            print(f"  FAILED for {count:,} variables:")
            traceback.print_exc(file=sys.stdout)


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0] if __doc__ else None)
    parser.add_argument("--seconds", type=float, help="how long each set is watched")
    parser.add_argument(
        "--client", nargs=3, metavar=("ENDPOINT", "COUNT", "PERIOD_MS"), help=argparse.SUPPRESS
    )
    args = parser.parse_args()
    if args.client:
        client_main(args.client[0], int(args.client[1]), int(args.client[2]))
    else:
        main(args.seconds)
