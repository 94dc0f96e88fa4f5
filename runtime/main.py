"""`padt runtime`: run one resource as its own process."""

from __future__ import annotations

import argparse
import logging
import signal
import sys
import threading
from pathlib import Path

from runtime.artifact import ArtifactError, load_artifact
from runtime.clock import RealClock
from runtime.keyspace import valid_resource_name
from runtime.resource import Resource

DEFAULT_ZENOH = "tcp/127.0.0.1:7447"
log = logging.getLogger("padt.runtime")


def artifact_path(state_dir: Path) -> Path:
    """Where the loaded configuration of a resource is kept."""
    return state_dir / "config" / "artifact.json"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--resource", required=True, help="name of the resource to run")
    parser.add_argument(
        "--state-dir",
        required=True,
        type=Path,
        help="folder of the resource's loaded configuration and saved state",
    )
    parser.add_argument(
        "--zenoh",
        default=DEFAULT_ZENOH,
        metavar="ENDPOINT",
        help=f"Zenoh router to connect to (default {DEFAULT_ZENOH})",
    )


def run(args: argparse.Namespace) -> int:
    logging.basicConfig(level=logging.INFO, format="%(asctime)s runtime %(message)s")
    if not valid_resource_name(args.resource):
        print(f"padt runtime: invalid resource name '{args.resource}'", file=sys.stderr)
        return 2
    clock = RealClock()
    resource = Resource(args.resource, clock)
    path = artifact_path(args.state_dir)
    if path.exists():
        try:
            resource.load(load_artifact(path.read_bytes()))
        except ArtifactError as exc:
            log.error("stored configuration refused: %s", exc)
    if resource.artifact is not None and resource.artifact.resource.autostart != "off":
        resource.start()

    from runtime.cycle_driver import CycleDriver
    from runtime.link import ResourceLink
    from runtime.zenoh_config import open_client

    stop = threading.Event()
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: stop.set())
    session = open_client(args.zenoh)
    link = ResourceLink(session, args.resource)
    log.info("resource %s: %s, Zenoh %s", args.resource, resource.state.value, args.zenoh)
    try:
        CycleDriver(resource, clock, link).run(stop)
    finally:
        link.close()
        session.close()
    return 0
