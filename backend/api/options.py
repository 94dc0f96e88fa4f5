"""The command-line options of `padt api` and `padt api-user` (apart from the server, so
that building the parser does not load FastAPI)."""

from __future__ import annotations

import argparse
from pathlib import Path

from backend.engineering.client_address import add_trusted_proxy_option
from backend.engineering.padt_levels import PADT_LEVELS
from backend.engineering.project_list import add_shelf_options, named_folder
from runtime.contract.session_options import add_zenoh_options

DEFAULT_ACCOUNTS = Path("padt-accounts.json")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--accounts",
        type=Path,
        default=DEFAULT_ACCOUNTS,
        help="the PADT accounts file (made with `padt api-user`)",
    )
    parser.add_argument(
        "--project",
        type=named_folder,
        action="append",
        default=[],
        metavar="[NAME=]DIR",
        help="a project folder to serve, named NAME or by its folder (repeatable)",
    )
    add_shelf_options(parser)
    parser.add_argument(
        "--backup-dir", type=Path, default=Path("padt-backups"), help="where backups go"
    )
    add_zenoh_options(parser, "Zenoh router the resources are connected to")
    parser.add_argument("--host", default="127.0.0.1", help="address to serve on")
    parser.add_argument("--port", type=int, default=8000, help="HTTP port")
    add_trusted_proxy_option(parser)


def add_user_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("user", metavar="NAME")
    parser.add_argument("--level", default="read-only", choices=PADT_LEVELS)
    parser.add_argument("--accounts", type=Path, default=DEFAULT_ACCOUNTS, help="the accounts file")
    parser.add_argument("--delete", action="store_true", help="delete the account")
