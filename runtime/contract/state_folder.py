"""The state folder of a resource (`padt runtime --state-dir DIR`): where it keeps the
configuration it was given (to power up with it), the context it saves (for a warm start)
and its long-term event log. A configuration placed here before the runtime starts is the
one it powers up with (the demo does that)."""

from __future__ import annotations

import os
from pathlib import Path

# A folder for the native tier's compiled modules instead of STATE_DIR/native: runtimes that
# build the same bodies (a test session's hundreds of runtimes and demos) share one cache.
NATIVE_CACHE_ENV = "PADT_NATIVE_CACHE"


def artifact_path(state_dir: Path) -> Path:
    """Where the loaded configuration of a resource is kept."""
    return state_dir / "config" / "artifact.json"


def context_path(state_dir: Path) -> Path:
    """Where the saved context (for a warm start) is kept."""
    return state_dir / "context" / "context.json"


def events_path(state_dir: Path) -> Path:
    """The long-term event log."""
    return state_dir / "events.jsonl"


def identity_path(state_dir: Path) -> Path:
    """The resource's signing key (owner-only)."""
    return state_dir / "identity.key"


def native_path(state_dir: Path) -> Path:
    """The compiled modules of the native tier (docs/native-code.md), a cache: the folder
    PADT_NATIVE_CACHE names when it is set, else `native` in the state folder."""
    shared = os.environ.get(NATIVE_CACHE_ENV)
    return Path(shared) if shared else state_dir / "native"


def recordings_path(state_dir: Path) -> Path:
    """The MCAP files of the resource's recordings (docs/recording.md)."""
    return state_dir / "recordings"


def setup_secret_path(state_dir: Path) -> Path:
    """The setup secret of a runtime without a configuration (owner-only; gone once the
    first configuration is loaded): what the first download proves it knows."""
    return state_dir / "setup-secret"
