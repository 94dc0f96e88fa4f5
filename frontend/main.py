"""`padt ui`: serve the browser UI for the resources on a Zenoh router. A browser logs in
with a PADT account (the same accounts file as `padt api`), then to each resource with the
user's account there."""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from runtime.contract.session_options import add_zenoh_options


def add_arguments(parser: argparse.ArgumentParser) -> None:
    add_zenoh_options(parser, "Zenoh router the resources are connected to")
    parser.add_argument(
        "--accounts",
        type=Path,
        default=Path("padt-accounts.json"),
        metavar="FILE",
        help="the PADT accounts (made with padt api-user; default ./padt-accounts.json)",
    )
    parser.add_argument(
        "--watch-lists",
        type=Path,
        default=Path("padt-watch-lists.json"),
        metavar="FILE",
        help="where the users' watch lists are kept (default ./padt-watch-lists.json)",
    )
    parser.add_argument("--host", default="127.0.0.1", help="address to serve on")
    parser.add_argument("--port", type=int, default=8080, help="HTTP port (next free if busy)")


def run(args: argparse.Namespace) -> int:
    # imported here: `padt` must start fast for commands that never open a UI
    from backend.engineering.padt_accounts import AccountsError, PadtAccounts
    from backend.engineering.resource_directory import ResourceDirectory
    from backend.engineering.watch_lists import WatchListError, WatchLists
    from frontend.app import PadtUi
    from frontend.ui_context import UiContext
    from runtime.contract.session import open_client
    from runtime.contract.stop_request import StopRequest

    stop = StopRequest()
    try:
        accounts = PadtAccounts(args.accounts, time.monotonic_ns)
    except AccountsError as exc:
        print(f"padt ui: {exc}", file=sys.stderr)
        return 2
    if accounts.empty:
        print(
            f"padt ui: no accounts in {args.accounts}; make one first: "
            f"padt api-user --accounts {args.accounts} NAME --level security-administrator",
            file=sys.stderr,
        )
        return 2
    try:
        watch_lists = WatchLists(args.watch_lists)
    except WatchListError as exc:
        print(f"padt ui: {exc}", file=sys.stderr)
        return 2
    session = open_client(args.zenoh, args.zenoh_config)
    directory = ResourceDirectory(session)
    context = UiContext(directory, accounts, args.zenoh, watch_lists)
    ui = PadtUi(context, host=args.host, port=args.port)
    print(f"PADT UI: {ui.url}", flush=True)
    stop.sleep_until_requested()
    ui.close()
    directory.close()
    session.close()
    return 0
