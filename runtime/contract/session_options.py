"""The command-line options of every `padt` command that opens a Zenoh session (kept apart
from runtime/zenoh_config.py, so that building the parser does not import Zenoh)."""

from __future__ import annotations

import argparse
from pathlib import Path

DEFAULT_ENDPOINT = "tcp/127.0.0.1:7447"


def add_zenoh_options(parser: argparse.ArgumentParser, router: str) -> None:
    """`--zenoh ENDPOINT` and `--zenoh-config FILE`, for every command with a session;
    `router` says which router (for the help text)."""
    parser.add_argument(
        "--zenoh",
        default=DEFAULT_ENDPOINT,
        metavar="ENDPOINT",
        help=f"{router} (default {DEFAULT_ENDPOINT})",
    )
    parser.add_argument(
        "--zenoh-config",
        type=Path,
        metavar="FILE",
        help="Zenoh configuration (JSON5) with TLS and user/password settings",
    )


class RouterUnreachable(Exception):
    """No Zenoh router answered at the endpoint within the connect timeout (raised by
    zenoh_config.open_client; here, so the command line can catch it without Zenoh)."""
