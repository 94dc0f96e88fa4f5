"""`padt runtime`: run one resource as its own process."""

from __future__ import annotations

import argparse
import logging
import socket
import sys
from pathlib import Path

from runtime.clock import RealClock
from runtime.code.native.tier import NativeTier
from runtime.collector import COLLECTOR
from runtime.commissioning import setup_secret
from runtime.configuration_store import ConfigurationStore
from runtime.context import ContextInvalid, load_context
from runtime.contract.artifact import ArtifactError, load_artifact
from runtime.contract.keyspace import resource_argument
from runtime.contract.protocol import safe_host
from runtime.contract.refusal import Refusal
from runtime.contract.session_options import add_zenoh_options
from runtime.contract.setup_secret import SetupSecretError
from runtime.contract.state_folder import (
    artifact_path,
    context_path,
    events_path,
    identity_path,
    native_path,
    recordings_path,
)
from runtime.contract.stop_request import StopRequest
from runtime.event_log import EventLog
from runtime.event_recorder import LONG_TERM_SHARES
from runtime.field_io.modbus.request_meter import REQUESTS_PER_SECOND
from runtime.identity import Identity
from runtime.resource import Resource
from runtime.restart import take_context, warm_start
from runtime.runtime_priority import (
    CYCLE_PRIORITY_RANGE,
    DEFAULT_CYCLE_PRIORITY,
    DEFAULT_NICE,
    NICE_RANGE,
    raise_priority,
)

log = logging.getLogger("padt.runtime")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--setup-secret-file",
        type=Path,
        metavar="FILE",
        help="while there is no configuration, the first download must log in as 'setup' "
        "with the secret in FILE (16 to 32 of A-Z a-z 0-9 _ -); without it the runtime "
        "makes one at its first start, shows it once and keeps it in the state folder "
        "(setup-secret, owner-only) until a configuration is loaded",
    )
    parser.add_argument(
        "--resource",
        required=True,
        type=resource_argument,
        help="name of the resource to run (a plain identifier: it is part of its Zenoh keys)",
    )
    parser.add_argument(
        "--state-dir",
        required=True,
        type=Path,
        help="folder of the resource's loaded configuration and saved state",
    )
    add_zenoh_options(parser, "Zenoh router to connect to")
    parser.add_argument(
        "--context-period-ms",
        type=int,
        default=1000,
        metavar="MS",
        help="how often the context is saved while the resource runs (default 1000)",
    )
    parser.add_argument(
        "--nice",
        type=int,
        default=DEFAULT_NICE,
        choices=NICE_RANGE,
        metavar="N",
        help=f"priority of the runtime as a nice value, -20 (highest) to 19 (default "
        f"{DEFAULT_NICE}; below 0 needs CAP_SYS_NICE, else it runs at normal priority)",
    )
    parser.add_argument(
        "--rt-priority",
        type=int,
        default=DEFAULT_CYCLE_PRIORITY,
        choices=CYCLE_PRIORITY_RANGE,
        metavar="N",
        help=f"real-time priority (SCHED_FIFO) of the cycle thread, 1 to 99 (default "
        f"{DEFAULT_CYCLE_PRIORITY}; needs CAP_SYS_NICE, else it keeps its nice value; 0: off)",
    )
    parser.add_argument(
        "--modbus-port",
        type=int,
        default=None,
        metavar="PORT",
        help="port of the served Modbus TCP image instead of the configured one (0: any free)",
    )
    parser.add_argument(
        "--modbus-rate",
        type=int,
        default=REQUESTS_PER_SECOND,
        choices=range(1, 1_000_001),
        metavar="N",
        help=f"Modbus requests the served image answers per second, all clients together "
        f"(default {REQUESTS_PER_SECOND}); a flood is answered no faster",
    )
    parser.add_argument(
        "--opcua-port",
        type=int,
        default=None,
        metavar="PORT",
        help="port of the OPC UA server instead of the configured one (0: any free)",
    )
    parser.add_argument(
        "--native-code",
        action=argparse.BooleanOptionalAction,
        default=True,
        help="run the bodies of programs, function blocks, FUNCTIONs and methods as C "
        "compiled on this machine where they translate, the variables in native memory and "
        "the usual CPU cycle in C "
        "(the default; needs a C compiler and Python's headers, else and until they are "
        "built they run as Python; --no-native-code: all as Python; docs/native-code.md)",
    )


def commission(resource: Resource, state_dir: Path, given: Path | None) -> None:
    """No configuration after power-up: the first download needs the setup secret, shown
    here once when it is new (runtime/commissioning.py). Raises SetupSecretError."""
    setup = setup_secret(state_dir, given)
    resource.commission(setup)
    if setup.made:
        log.warning(
            "no configuration yet: the first download needs the setup secret %s (shown only "
            "now; kept in %s, owner-only, until a configuration is loaded)",
            setup.text,
            setup.path,
        )
    else:
        log.info(
            "no configuration yet: the first download needs the setup secret of %s", setup.path
        )


def power_up(resource: Resource, state_dir: Path) -> None:
    """What a controller does when it comes up: load the stored configuration, take the
    saved context when it is valid (warm) or not (cold), then Autostart decides."""
    path = artifact_path(state_dir)
    if not path.exists():
        return
    try:
        resource.load(load_artifact(path.read_bytes()))
    except (ArtifactError, Refusal) as exc:  # it stays STOP/INVALID; a download mends it
        log.error("stored configuration refused: %s", exc)
        resource.events.record("state", f"stored configuration refused: {exc}", long_term=True)
        return
    assert resource.artifact is not None
    autostart = resource.artifact.resource.autostart
    saved = load_context(context_path(state_dir), resource.artifact.crc)
    if isinstance(saved, ContextInvalid):
        resource.events.record("state", f"cold start: {saved.reason}", long_term=True)
    elif autostart == "cold":
        resource.events.record("state", "cold start: Autostart is cold", long_term=True)
    else:
        warm_start(resource, saved)
    if autostart != "off":
        resource.start()


def run(args: argparse.Namespace) -> int:
    stop = StopRequest()
    logging.basicConfig(level=logging.INFO, format="%(asctime)s runtime %(message)s")
    # first: the threads started from here on (Zenoh's, the I/O's, the savers) inherit it,
    # so that none of them holds the GIL the cycle waits for while it waits for a CPU
    priority = raise_priority(args.nice)
    clock = RealClock()
    # written behind: the cycle thread records events and must not wait for an fsync
    events = EventLog(
        clock.wall_ns,
        long_path=events_path(args.state_dir),
        write_behind=True,
        shares=LONG_TERM_SHARES,
    )
    identity = Identity.kept_in(identity_path(args.state_dir))
    resource = Resource(args.resource, clock, events, identity)
    if args.native_code:
        resource.native = NativeTier(native_path(args.state_dir))
        if not resource.native.available:
            message = "native code: no C compiler or no Python.h here; the bodies run as Python"
            log.warning(message)
            resource.events.record("native", message, long_term=True)
    power_up(resource, args.state_dir)
    if resource.artifact is None:
        try:
            commission(resource, args.state_dir, args.setup_secret_file)
        except SetupSecretError as exc:
            print(f"padt runtime: {exc}", file=sys.stderr)
            return 2
    resource.store = ConfigurationStore(args.state_dir)

    from runtime.context_saver import ContextSaver
    from runtime.contract.session import open_client
    from runtime.cycle_driver import CycleDriver
    from runtime.link import ResourceLink

    session = open_client(args.zenoh, args.zenoh_config)
    resource.host = safe_host(socket.gethostname())
    resource.zenoh_id = str(session.zid())
    link = ResourceLink(session, args.resource, identity)
    saver = ContextSaver(context_path(args.state_dir))

    def save() -> None:
        context = take_context(resource, deferred=True)
        if context is not None:
            saver.submit(context)

    from runtime import online_writes
    from runtime.field_io import FieldIo
    from runtime.field_io.opcua.kind import OpcuaOptions
    from runtime.field_io.peer_exchange.kind import ExchangeOptions

    resource.field_io = FieldIo(
        lambda: resource.artifact,
        resource.variables,
        resource.io,
        resource.recorder,
        resource.running,
        args.modbus_port,
        args.modbus_rate,
        resource=args.resource,
        accounts=lambda: resource.access.users,
        write=lambda path, value, user: online_writes.write(resource, path, value, user),
        opcua=OpcuaOptions(args.opcua_port, args.state_dir / "opcua"),
        exchange=ExchangeOptions(session, identity, args.state_dir / "exchange-peers"),
    )
    from runtime.recorder import Recordings

    recordings = Recordings(recordings_path(args.state_dir))
    resource.recordings = recordings
    driver = CycleDriver(
        resource, clock, link, save, args.context_period_ms * 1_000_000, args.rt_priority
    )
    log.info("resource %s: %s, Zenoh %s", args.resource, resource.state.value, args.zenoh)
    log.info("runtime priority: %s", priority)
    # all that start-up made (the configuration, Zenoh, the I/O) out of the collector's
    # sight before the first cycle (runtime/collector.py)
    COLLECTOR.manage()
    try:
        driver.run(stop.event)
    finally:
        driver.close()  # an orderly stop saves the context one last time
        resource.field_io.close()
        recordings.close()
        saver.close()
        link.close()
        session.close()
        events.close()  # the last entries on disk before the process ends
    return 0
