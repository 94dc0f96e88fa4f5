"""`padt router`: a Zenoh router from this project's own Python, for hosts without zenohd.

It listens where it is told (loopback unless told otherwise), links to other routers with
`--connect` (a mesh), and takes Zenoh's own configuration (TLS, usrpwd, access_control)
from `--zenoh-config`, with mode, endpoints and scouting set on top as for every other
command (runtime/contract/session.py). It runs until SIGTERM or SIGINT.
"""

from __future__ import annotations

import argparse
import signal
import sys
import threading
from pathlib import Path
from types import FrameType

from runtime.contract.session_options import DEFAULT_ENDPOINT

# the signals that end the router: a service manager's stop, and Ctrl-C
_STOP_SIGNALS = (signal.SIGTERM, signal.SIGINT)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--listen",
        action="append",
        metavar="ENDPOINT",
        help=f"listen for clients and routers on ENDPOINT (repeatable; default {DEFAULT_ENDPOINT})",
    )
    parser.add_argument(
        "--connect",
        action="append",
        default=[],
        metavar="ENDPOINT",
        help="link to the router at ENDPOINT (repeatable): a mesh of routers",
    )
    parser.add_argument(
        "--zenoh-config",
        type=Path,
        metavar="FILE",
        help="Zenoh configuration (JSON5) with TLS, usrpwd and access_control settings",
    )


def run(args: argparse.Namespace) -> int:
    # imported here: Zenoh loads only for a command that opens a session
    from runtime.contract.session import RouterNotOpened, open_mesh_router

    listen: list[str] = args.listen or [DEFAULT_ENDPOINT]
    connect: list[str] = args.connect
    config_file: Path | None = args.zenoh_config
    if config_file is not None and not config_file.is_file():
        # Zenoh's own message for a missing file names neither the file nor the option
        print(f"padt router: no configuration file {config_file}", file=sys.stderr)
        return 2
    stop = threading.Event()

    def on_signal(signum: int, frame: FrameType | None) -> None:
        stop.set()

    # set before the session opens, so that a stop during the opening is not lost
    for number in _STOP_SIGNALS:
        signal.signal(number, on_signal)
    try:
        session = open_mesh_router(listen, connect, config_file)
    except RouterNotOpened as exc:
        print(f"padt router: {exc}", file=sys.stderr)
        return 2
    try:
        line = f"padt router: listening on {', '.join(listen)}"
        if connect:
            line += f", connecting to {', '.join(connect)}"
        print(line, flush=True)
        # a wait with a timeout: the signal handler runs in this thread between waits
        while not stop.wait(1):
            pass
    finally:
        session.close()
    return 0
