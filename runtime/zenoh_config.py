"""Zenoh session configuration with the secure defaults: explicit endpoints, loopback
unless told otherwise, no multicast scouting."""

from __future__ import annotations

import json

import zenoh


def session_config(
    *, mode: str = "client", listen: list[str] | None = None, connect: list[str] | None = None
) -> zenoh.Config:
    config = zenoh.Config()
    config.insert_json5("mode", json.dumps(mode))
    config.insert_json5("listen/endpoints", json.dumps(listen or []))
    config.insert_json5("connect/endpoints", json.dumps(connect or []))
    config.insert_json5("scouting/multicast/enabled", "false")
    config.insert_json5("scouting/delay", "0")
    if mode == "client":
        # wait for the router instead of failing at once when it starts a moment later
        config.insert_json5("connect/timeout_ms", "10000")
    return config


def open_router(endpoint: str) -> zenoh.Session:
    """A Zenoh router inside this Python process (no zenohd binary needed)."""
    return zenoh.open(session_config(mode="router", listen=[endpoint]))


def open_client(endpoint: str) -> zenoh.Session:
    return zenoh.open(session_config(mode="client", connect=[endpoint]))
