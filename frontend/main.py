"""`padt ui`: serve the browser UI for the resources on a Zenoh router. A browser logs in
with a PADT account (the same accounts file as `padt api`), then to each resource with the
user's account there."""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from backend.engineering.client_address import add_trusted_proxy_option
from backend.engineering.project_list import add_shelf_options, named_folder
from runtime.contract.session_options import add_zenoh_options

DEFAULT_BACKUP_DIR = Path("padt-backups")  # as backend.engineering.backup's, without loading it


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
    parser.add_argument(
        "--project",
        type=named_folder,
        action="append",
        default=[],
        metavar="[NAME=]DIR",
        help="a project for the Reload and Code screens, named NAME or by its folder (repeatable)",
    )
    add_shelf_options(parser)
    parser.add_argument(
        "--backup-dir",
        type=Path,
        default=DEFAULT_BACKUP_DIR,
        metavar="DIR",
        help="folder for the backup archive of what was reloaded (default ./padt-backups)",
    )
    parser.add_argument("--host", default="127.0.0.1", help="address to serve on")
    parser.add_argument("--port", type=int, default=8080, help="HTTP port (next free if busy)")
    add_trusted_proxy_option(parser)


def run(args: argparse.Namespace) -> int:
    # imported here: `padt` must start fast for commands that never open a UI
    from backend.engineering.client_address import TrustedProxies
    from backend.engineering.padt_accounts import AccountsError, PadtAccounts
    from backend.engineering.project_list import projects_by_name
    from backend.engineering.project_shelf import shelf_of
    from backend.engineering.resource_directory import ResourceDirectory
    from backend.engineering.start_up_freeze import freeze_start_up
    from backend.engineering.watch_lists import WatchLists
    from frontend.app import PadtUi
    from frontend.ui_context import UiContext
    from runtime.contract.session import open_client
    from runtime.contract.stop_request import StopRequest

    stop = StopRequest()
    try:
        accounts = PadtAccounts(args.accounts, time.monotonic_ns)
        projects = shelf_of(projects_by_name(args.project), args.projects_dir, args.audit_log)
        watch_lists = WatchLists(args.watch_lists)
    except (AccountsError, ValueError, OSError) as exc:  # WatchListError is a ValueError
        print(f"padt ui: {exc}", file=sys.stderr)
        return 2
    if accounts.empty:
        print(
            f"padt ui: no accounts in {args.accounts}; make one first: "
            f"padt api-user --accounts {args.accounts} NAME --level security-administrator",
            file=sys.stderr,
        )
        return 2
    session = open_client(args.zenoh, args.zenoh_config)
    directory = ResourceDirectory(session)
    context = UiContext(directory, accounts, args.zenoh, watch_lists, projects, args.backup_dir)
    trusted = TrustedProxies(tuple(args.trusted_proxy))
    ui = PadtUi(context, host=args.host, port=args.port, trusted=trusted)
    freeze_start_up()
    print(f"PADT UI: {ui.url}", flush=True)
    stop.sleep_until_requested()
    ui.close()
    directory.close()
    session.close()
    return 0
