"""OPC UA server benchmark (runtime/field_io/opcua/resource_server.py): 10,000 exposed
variables served while the resource runs a 10 ms 'fixed' cycle under the real cycle driver
with its Zenoh link, one client subscribing all of them at 100 ms.

The configuration: `Main.rows`, an array of 100 structures of 100 INT/REAL/BOOL members
(10,000 variable nodes below 102 objects, each object with at most 100 children); each
cycle the program changes the 100 members of one row, the next row the next cycle: 1 % of
the exposed values per 10 ms cycle, 10,000 changes a second, each value once a second.

1. The address space: from the server's start (the driver made) to listening, and to all
   nodes there; the cycle jitter meanwhile.
2. One asyncua client in a separate process (Basic256Sha256 sign & encrypt, a user of the
   resource): the time to create the 10,000 monitored items (calls of 1,000), then, with
   100 ms sampling and publishing, the notifications a second it receives and their
   latency (receipt minus the value's SourceTimestamp, which the server sets at the end
   of the cycle that produced it; the same host clock).
3. The cycle jitter and the CPU time of the resource's process (all its threads; the
   client's process not counted) a second: without OPC UA at all, served with no client,
   and served with the client subscribed, each over its own window of the same run. And
   what the snapshot of the exposed values costs the cycle thread (`after_cycle`).

Run with `python -m tests.bench.bench_opcua [--seconds S]` (10 s per window unless
`--seconds` or `PADT_BENCH_SECONDS` says otherwise). It prints figures and asserts nothing
about time (machines are shared and noisy).
"""

from __future__ import annotations

import argparse
import asyncio
import dataclasses
import gc
import json
import logging
import os
import socket
import sys
import tempfile
import time
from contextlib import suppress
from dataclasses import dataclass
from datetime import UTC
from itertools import pairwise
from pathlib import Path
from typing import Any

from backend.compiler.pipeline import compile_sources
from backend.compiler.source import SourceFile
from runtime.clock import RealClock
from runtime.collector import COLLECTOR
from runtime.contract.accounts import hash_password
from runtime.contract.artifact import Artifact, UserAccount
from runtime.contract.opcua import OpcuaConfig, OpcuaServer
from runtime.field_io import FieldIo
from runtime.field_io.opcua.driver import OpcuaDriver
from runtime.field_io.opcua.kind import OpcuaOptions
from runtime.field_io.opcua.resource_server import ResourceServer
from tests.bench.bench_runtime import TARGET_MS, TARGET_NS, LoggedResource, Spread, _config, driven
from tests.bench.client_process import ClientProcess
from tests.support.ports import free_port

ROWS = 100
MEMBERS = 100
ITEMS = ROWS * MEMBERS
KINDS = ("INT", "REAL", "BOOL")
PER_CALL = 1_000  # monitored items per CreateMonitoredItems call
INTERVAL_MS = 100.0  # sampling and publishing
RESOURCE = "R"
USER, PASSWORD = "scada", "bench-opcua"
SETTLE_S = 1.0  # before a window: the cycle settled, the initial values delivered
DEFAULT_SECONDS = 10.0
SECONDS_ENV = "PADT_BENCH_SECONDS"
REPO = Path(__file__).resolve().parents[2]


def _source() -> str:
    """100 rows of 100 members; each cycle all members of the next row change."""
    members = "\n".join(f"  m{n} : {KINDS[n % len(KINDS)]};" for n in range(MEMBERS))
    steps = []
    for n in range(MEMBERS):
        kind, member = KINDS[n % len(KINDS)], f"rows[turn].m{n}"
        change = {"INT": f"{member} + 1", "REAL": f"{member} + 0.5", "BOOL": f"NOT {member}"}
        steps.append(f"{member} := {change[kind]};")
    return "\n".join(
        [
            f"TYPE Row : STRUCT\n{members}\nEND_STRUCT END_TYPE",
            "PROGRAM Main",
            f"VAR rows : ARRAY[0..{ROWS - 1}] OF Row; turn : INT; END_VAR",
            *steps,
            f"turn := (turn + 1) MOD {ROWS};",
            "END_PROGRAM",
            "",
        ]
    )


def _artifact(port: int | None) -> Artifact:
    """The configuration, served on `port` (None: no OPC UA at all)."""
    result = compile_sources([SourceFile("bench.st", _source())], resource=_config())
    assert result.artifact is not None, [str(d) for d in result.diagnostics[:3]]
    if port is None:
        return result.artifact
    server = OpcuaServer(port=port, exposed=("Main.rows",), trust_unknown_clients=True)
    users = (UserAccount(USER, "read", hash_password(PASSWORD)),)
    return dataclasses.replace(result.artifact, opcua=OpcuaConfig(server), users=users).with_crc()


class TimedFieldIo(FieldIo):
    """Notes when the OPC UA server's snapshot of the exposed values was taken on the cycle
    thread, and how long `after_cycle` took then (monotonic ns)."""

    snapshots: list[tuple[int, int]]

    def opcua_server(self) -> ResourceServer | None:
        drivers = (d for d in self._active if isinstance(d, OpcuaDriver))
        return next((d.server for d in drivers), None)

    def after_cycle(self) -> None:
        server = self.opcua_server()
        wanted = server is not None and server.wanted
        started = time.monotonic_ns()
        super().after_cycle()
        if wanted:
            self.snapshots.append((started, time.monotonic_ns() - started))


def _field_io(resource: LoggedResource) -> TimedFieldIo:
    field_io = TimedFieldIo(
        lambda: resource.artifact, resource.variables, resource.io, resource.recorder,
        resource.running, resource=RESOURCE, accounts=lambda: resource.access.users,
        opcua=OpcuaOptions(),
    )  # fmt: skip
    field_io.snapshots = []
    resource.field_io = field_io
    return field_io


def _resource(artifact: Artifact) -> tuple[LoggedResource, TimedFieldIo]:
    resource = LoggedResource(RESOURCE, RealClock())
    resource.load(artifact)
    resource.start()
    return resource, _field_io(resource)


@dataclass(frozen=True)
class Window:
    """What a resource did between two instants (monotonic ns)."""

    periods: list[int]
    cpu_percent: float  # the process's CPU time a second, % of one core
    snapshots_ns: list[int]  # `after_cycle` with a snapshot of the exposed values
    collections: list[tuple[int, int]]  # the cycle collector's runs: generation, ns
    in_sight: int  # the objects the collector walks in a full collection, after the window

    @property
    def jitter(self) -> Spread | None:
        return Spread.of([abs(p - TARGET_NS) for p in self.periods]) if self.periods else None


def _periods(resource: LoggedResource, start_ns: int, end_ns: int) -> list[int]:
    starts = [s for s in list(resource.log.starts_ns) if start_ns <= s <= end_ns]
    return [b - a for a, b in pairwise(starts)]


class Collections:
    """The cycle collector's runs (on any thread), while installed."""

    def __init__(self) -> None:
        self.runs: list[tuple[int, int]] = []
        self._started = 0

    def __call__(self, phase: str, info: dict[str, Any]) -> None:
        if phase == "start":
            self._started = time.perf_counter_ns()
        else:
            self.runs.append((info["generation"], time.perf_counter_ns() - self._started))


def _window(resource: LoggedResource, field_io: TimedFieldIo, seconds: float) -> Window:
    collections = Collections()
    gc.callbacks.append(collections)
    try:
        start_ns, cpu = time.monotonic_ns(), time.process_time()
        time.sleep(seconds)
        cpu, end_ns = time.process_time() - cpu, time.monotonic_ns()
    finally:
        gc.callbacks.remove(collections)
    snapshots = [d for at, d in list(field_io.snapshots) if start_ns <= at <= end_ns]
    wall = (end_ns - start_ns) / 1e9
    periods = _periods(resource, start_ns, end_ns)
    in_sight = len(gc.get_objects())  # after the window: its walk does not count there
    return Window(periods, 100 * cpu / wall, snapshots, collections.runs, in_sight)


# ---- the client, in its own process ----------------------------------------------------------


def _client(port: int) -> None:
    logging.getLogger("asyncua").setLevel(logging.ERROR)  # its notes on revised values
    asyncio.run(_client_session(port))


async def _client_session(port: int) -> None:
    """Connects, subscribes every exposed variable, says `ready`; counts the notifications
    between `go` and `stop` on its input, then says what it saw."""
    from asyncua.client.client import Client
    from asyncua.common.subscription import Subscription
    from asyncua.crypto.cert_gen import setup_self_signed_certificate
    from asyncua.ua import PublishResult
    from cryptography.x509.oid import ExtendedKeyUsageOID

    class Counting(Subscription):
        """Each publish response's items counted, with their latency; nothing dispatched."""

        counting = False
        latencies_ms: list[float] = []  # one subscription in this process
        publishes = 0

        async def publish_callback(self, publish_result: PublishResult) -> None:
            received = time.time()
            if not self.counting:
                return
            Counting.publishes += 1
            for data in publish_result.NotificationMessage.NotificationData or ():
                for item in getattr(data, "MonitoredItems", None) or ():
                    stamp = item.Value.SourceTimestamp if item.Value is not None else None
                    if stamp is None:
                        continue
                    if stamp.tzinfo is None:
                        stamp = stamp.replace(tzinfo=UTC)
                    self.latencies_ms.append((received - stamp.timestamp()) * 1e3)

    with tempfile.TemporaryDirectory(prefix="padt-bench-opcua-") as folder:
        cert, key = Path(folder) / "client.der", Path(folder) / "client.pem"
        uri = "urn:padt-bench:client"
        await setup_self_signed_certificate(
            key, cert, uri, socket.gethostname(), [ExtendedKeyUsageOID.CLIENT_AUTH],
            {"commonName": "padt bench client"},
        )  # fmt: skip
        # patient: with its default 1 s health probe asyncua takes a server this busy for
        # lost and disconnects (seen here while creating the monitored items)
        client = Client(f"opc.tcp://127.0.0.1:{port}/", timeout=60, watchdog_intervall=60)
        client.application_uri = uri
        await client.set_security_string(f"Basic256Sha256,SignAndEncrypt,{cert},{key}")
        client.set_user(USER)
        client.set_password(PASSWORD)
        started = time.perf_counter()
        await client.connect()
        connect_s = time.perf_counter() - started
        try:
            await _subscribed(client, Counting, connect_s)
        finally:
            with suppress(Exception):  # the results are out; the server goes anyway
                await asyncio.wait_for(client.disconnect(), 10)


async def _subscribed(client: Any, counting: Any, connect_s: float) -> None:
    from asyncua.ua import CreateSubscriptionParameters

    namespace = await client.get_namespace_index(f"urn:padt:{RESOURCE}:variables")
    params = CreateSubscriptionParameters(
        RequestedPublishingInterval=INTERVAL_MS, RequestedLifetimeCount=10_000,
        RequestedMaxKeepAliveCount=client.get_keepalive_count(INTERVAL_MS),
        MaxNotificationsPerPublish=0, PublishingEnabled=True, Priority=0,
    )  # fmt: skip
    subscription = counting(client.uaclient.session, params, None)
    await subscription.init()
    nodes = [
        client.get_node(f"ns={namespace};s={RESOURCE}.Main.rows[{row}].m{member}")
        for row in range(ROWS)
        for member in range(MEMBERS)
    ]
    calls, refused = [], 0
    for n in range(0, len(nodes), PER_CALL):
        started = time.perf_counter()
        handles = await subscription.subscribe_data_change(
            nodes[n : n + PER_CALL], sampling_interval=INTERVAL_MS, queuesize=1
        )
        calls.append(time.perf_counter() - started)
        refused += sum(1 for h in handles if not isinstance(h, int))
    _say({"connect_s": connect_s, "calls_s": calls, "refused": refused})
    await asyncio.to_thread(sys.stdin.readline)  # go
    cpu, started = time.process_time(), time.monotonic()
    counting.counting = True
    await asyncio.to_thread(sys.stdin.readline)  # stop
    counting.counting = False
    seconds, cpu = time.monotonic() - started, time.process_time() - cpu
    latencies = counting.latencies_ms
    _say(
        {
            "seconds": seconds, "notifications": len(latencies),
            "publishes": counting.publishes,
            "latency_ms": dataclasses.asdict(Spread.of(latencies)) if latencies else None,
            "cpu_percent": 100 * cpu / seconds,
        }
    )  # fmt: skip
    await asyncio.to_thread(sys.stdin.readline)  # the end of input


def _say(message: dict[str, Any]) -> None:
    print(json.dumps(message), flush=True)


# ---- the runs ----------------------------------------------------------------------------------


def _ms(ns: float) -> str:
    return f"{ns / 1e6:7.3f} ms"


def _jitter(label: str, window: Window) -> None:
    jitter = window.jitter
    if jitter is None:
        print(f"    {label:<28} no periods")
        return
    over = sum(1 for p in window.periods if p > TARGET_NS + 1_000_000)
    print(
        f"    {label:<28} {len(window.periods):6,} periods   p50 {_ms(jitter.p50)}   "
        f"p99 {_ms(jitter.p99)}   max {_ms(jitter.max)}   > 1 ms late: {over}"
    )


def _without_opcua(seconds: float) -> Window:
    resource, field_io = _resource(_artifact(None))
    try:
        with driven(resource, resource.clock):
            time.sleep(SETTLE_S)
            return _window(resource, field_io, seconds)
    finally:
        field_io.close()


@dataclass(frozen=True)
class Served:
    listening_s: float
    built_s: float
    nodes: int
    building: list[int]  # the periods while the address space was built
    quiet: Window  # no client
    busy: Window  # the client subscribed
    ready: dict[str, Any]  # what the client said once subscribed
    seen: dict[str, Any]  # and what it received in the window


def _served(seconds: float) -> Served:
    port = free_port()
    resource, field_io = _resource(_artifact(port))
    started_ns = time.monotonic_ns()
    field_io.follow_configuration()  # the driver made: the server starts on the I/O thread
    server = field_io.opcua_server()
    assert server is not None
    try:
        with driven(resource, resource.clock):
            listening = built = 0
            deadline = started_ns + 180 * 1_000_000_000
            while not built:
                now = time.monotonic_ns()
                if server.error or now > deadline:
                    raise RuntimeError(f"the OPC UA server: {server.error or 'not built'}")
                if not listening and server.port:
                    listening = now
                if server._by_node and len(server._by_node) == len(server._plan.variables):
                    built = now
                time.sleep(0.002)
            building = _periods(resource, started_ns, built)
            nodes = len(server._built)
            time.sleep(SETTLE_S)
            quiet = _window(resource, field_io, seconds)
            client = ClientProcess("tests.bench.bench_opcua", str(port))
            try:
                ready = client.receive(180)
                time.sleep(SETTLE_S)  # the initial values of all items delivered
                client.tell("go")
                busy = _window(resource, field_io, seconds)
                client.tell("stop")
                seen = client.receive(60)
            finally:
                client.close()
    finally:
        field_io.close()
    return Served(
        (listening - started_ns) / 1e9, (built - started_ns) / 1e9, nodes, building, quiet,
        busy, ready, seen,
    )  # fmt: skip


def bench_served(seconds: float) -> None:
    print(
        f"OPC UA server, {ITEMS:,} exposed variables ({ROWS} structures of {MEMBERS} "
        f"INT/REAL/BOOL members), the program changing {MEMBERS} of them (1 %) every cycle; "
        f"target cycle {TARGET_MS} ms 'fixed', real CycleDriver with a Zenoh link, "
        f"{seconds:g} s per window:"
    )
    COLLECTOR.manage()  # as the runtime process does before its first cycle
    none = _without_opcua(seconds)
    try:
        served = _served(seconds)
    except (RuntimeError, OSError) as exc:  # the other sections still run
        print(f"  FAILED: {exc}")
        return
    building = Spread.of([abs(p - TARGET_NS) for p in served.building or [TARGET_NS]])
    print(
        f"  address space: listening {served.listening_s:6.2f} s, all {served.nodes:,} nodes "
        f"{served.built_s:6.2f} s after the server's start"
    )
    print(
        f"    cycle jitter meanwhile: {len(served.building):,} periods   "
        f"p99 {_ms(building.p99)}   max {_ms(building.max)}"
    )
    calls = served.ready["calls_s"]
    print(
        f"  client (own process, Basic256Sha256 sign & encrypt): connected in "
        f"{served.ready['connect_s']:.2f} s; {ITEMS:,} monitored items created in "
        f"{sum(calls):.2f} s ({len(calls)} calls of {PER_CALL:,}: slowest {max(calls):.2f} s; "
        f"{served.ready['refused']} refused)"
    )
    seen = served.seen
    changed = len(served.busy.periods) * MEMBERS / max(0.001, seconds)
    print(
        f"  subscription, {INTERVAL_MS:g} ms sampling and publishing: "
        f"{seen['notifications'] / seen['seconds']:8,.0f} notifications/s received "
        f"({changed:,.0f} values/s changed by the program; {seen['publishes']} publishes)"
    )
    latency = seen["latency_ms"]
    if latency is not None:
        print(
            f"    latency (receipt - SourceTimestamp): p50 {latency['p50']:7.1f} ms   "
            f"p99 {latency['p99']:7.1f} ms   max {latency['max']:7.1f} ms"
        )
    print(f"  cycle jitter |period - {TARGET_MS} ms|:")
    _jitter("without OPC UA", none)
    _jitter("served, no client", served.quiet)
    _jitter("served, client subscribed", served.busy)
    if none.jitter is not None and served.busy.jitter is not None:
        ratio = served.busy.jitter.p99 / max(1.0, none.jitter.p99)
        print(f"    -> jitter p99 subscribed / without OPC UA: {ratio:.2f}")
    print(
        "  cycle collector (the runtime freezes what its start-up made; the server starts after):"
    )
    for label, window in (
        ("without OPC UA", none), ("served, no client", served.quiet),
        ("served, client subscribed", served.busy),
    ):  # fmt: skip
        full = [ns for generation, ns in window.collections if generation == 2]
        longest = max((ns for _, ns in window.collections), default=0)
        print(
            f"    {label:<28} {len(window.collections):5,} runs, {len(full):3} full "
            f"(together {_ms(sum(full))})   longest {_ms(longest)}   "
            f"{window.in_sight:9,} objects in its sight"
        )
    print("  CPU time of the resource's process a second (% of one core):")
    print(f"    {'without OPC UA':<28} {none.cpu_percent:6.1f} %")
    print(f"    {'served, no client':<28} {served.quiet.cpu_percent:6.1f} %")
    print(
        f"    {'served, client subscribed':<28} {served.busy.cpu_percent:6.1f} %   -> the "
        f"server: {served.busy.cpu_percent - none.cpu_percent:+.1f} % over without OPC UA"
    )
    print(f"    (the client's process: {seen['cpu_percent']:.1f} %, not counted above)")
    for label, window in (("no client", served.quiet), ("subscribed", served.busy)):
        if window.snapshots_ns:
            spread = Spread.of(window.snapshots_ns)
            rate = len(window.snapshots_ns) / max(0.001, seconds)
            print(
                f"  snapshot of the {ITEMS:,} values on the cycle thread ({label}): "
                f"{rate:5.1f}/s   mean {_ms(spread.mean)}   p99 {_ms(spread.p99)}   "
                f"max {_ms(spread.max)}"
            )


def main(seconds: float | None = None) -> None:
    if seconds is None:
        seconds = float(os.environ.get(SECONDS_ENV, DEFAULT_SECONDS))
    bench_served(seconds)


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0] if __doc__ else None)
    parser.add_argument("--seconds", type=float, default=None)
    parser.add_argument("--client", type=int, default=None, metavar="PORT", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.client is not None:
        _client(args.client)
    else:
        main(args.seconds)
