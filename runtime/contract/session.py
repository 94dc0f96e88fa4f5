"""Zenoh session configuration with the secure defaults: explicit endpoints, loopback
unless told otherwise, no multicast scouting.

Transport security comes from an optional Zenoh configuration file (JSON5, Zenoh's own
keys; `--zenoh-config FILE` on every command that opens a session): TLS certificates under
`transport/link/tls`, user and password under `transport/auth/usrpwd`. The file is read
first and the endpoints, mode and scouting set here on top, so it cannot turn the secure
defaults off by accident (it may set `connect/timeout_ms`). docs/zenoh-security.md has
examples.
"""

from __future__ import annotations

import json
from pathlib import Path

import zenoh

from runtime.contract.session_options import RouterUnreachable

CONNECT_TIMEOUT_MS = 10_000


def session_config(
    *,
    mode: str = "client",
    listen: list[str] | None = None,
    connect: list[str] | None = None,
    config_file: Path | None = None,
) -> zenoh.Config:
    config = zenoh.Config.from_file(str(config_file)) if config_file else zenoh.Config()
    config.insert_json5("mode", json.dumps(mode))
    config.insert_json5("listen/endpoints", json.dumps(listen or []))
    config.insert_json5("connect/endpoints", json.dumps(connect or []))
    config.insert_json5("scouting/multicast/enabled", "false")
    config.insert_json5("scouting/delay", "0")
    if mode == "client" and config.get_json("connect/timeout_ms") == "null":
        # wait for the router instead of failing at once when it starts a moment later
        config.insert_json5("connect/timeout_ms", str(CONNECT_TIMEOUT_MS))
    return config


def open_router(
    endpoint: str | list[str], config_file: Path | None = None, connect: list[str] | None = None
) -> zenoh.Session:
    """A Zenoh router inside this Python process (no zenohd binary needed), listening on
    `endpoint` (one or several) and linked to the routers at `connect`, if any (a mesh:
    router to router, reached again whenever one of them comes back)."""
    listen = [endpoint] if isinstance(endpoint, str) else endpoint
    return zenoh.open(
        session_config(mode="router", listen=listen, connect=connect, config_file=config_file)
    )


class RouterNotOpened(Exception):
    """The router could not be opened: a configuration file that Zenoh cannot read, an
    endpoint that is no endpoint or cannot listen (Zenoh's reason, in one line)."""


def open_mesh_router(
    listen: list[str], connect: list[str], config_file: Path | None
) -> zenoh.Session:
    """`open_router` for the command line: Zenoh's error as RouterNotOpened, so that the
    caller needs no import of Zenoh to tell it from a bug."""
    try:
        config = session_config(
            mode="router", listen=listen, connect=connect, config_file=config_file
        )
    except zenoh.ZError as exc:
        raise RouterNotOpened(f"cannot read the Zenoh configuration: {_reason(exc)}") from None
    try:
        return zenoh.open(config)
    except zenoh.ZError as exc:
        raise RouterNotOpened(f"cannot open the router: {_reason(exc)}") from None


def _reason(exc: zenoh.ZError) -> str:
    """Zenoh's message without the Rust source location it appends, on one line."""
    text = " ".join(str(exc).split())
    return text.split(" at /", 1)[0]


def open_client(endpoint: str, config_file: Path | None = None) -> zenoh.Session:
    try:
        return zenoh.open(
            session_config(mode="client", connect=[endpoint], config_file=config_file)
        )
    except zenoh.ZError as exc:
        # zenoh appends the Rust source location of the error: of no use to the user
        reason = str(exc).split(" at /", 1)[0]
        raise RouterUnreachable(f"cannot reach the Zenoh router at {endpoint}: {reason}") from None
