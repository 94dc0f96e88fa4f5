"""`padt ui`: serve the browser UI for one resource reached over Zenoh."""

from __future__ import annotations

import argparse
import getpass
import os

from runtime.contract.session_options import add_zenoh_options


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--resource", required=True, help="resource to show")
    add_zenoh_options(parser, "Zenoh router the resource is connected to")
    parser.add_argument(
        "--user",
        metavar="NAME",
        help="the account the UI acts with (password from PADT_PASSWORD, else asked for)",
    )
    parser.add_argument("--host", default="127.0.0.1", help="address to serve on")
    parser.add_argument("--port", type=int, default=8080, help="HTTP port (next free if busy)")


def run(args: argparse.Namespace) -> int:
    # imported here: `padt` must start fast for commands that never open a UI
    from backend.engineering.resource_client import ResourceClient
    from frontend.app import PadtUi
    from runtime.contract.session import open_client
    from runtime.contract.stop_request import StopRequest

    stop = StopRequest()
    session = open_client(args.zenoh, args.zenoh_config)
    client = ResourceClient(session, args.resource)
    if args.user is not None:
        password = os.environ.get("PADT_PASSWORD") or getpass.getpass(f"password of {args.user}: ")
        client.use_credentials(args.user, password)
    ui = PadtUi(client, host=args.host, port=args.port)
    print(f"PADT UI: {ui.url}", flush=True)
    stop.sleep_until_requested()
    ui.close()
    session.close()
    return 0
