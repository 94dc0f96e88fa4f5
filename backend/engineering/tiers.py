"""The tiers the engineering tools run a configuration's code on, as a runtime does
(docs/native-code.md): Python, or native, where the bodies of programs and function blocks
that translate run as C compiled on this machine. `padt test` runs both and compares them
(`testing/tiers.py`); `padt sim` and `padt replay` run one, by default the one `padt
runtime` runs by default: native where it can be built, else Python."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Literal

from runtime.code.native.tier import NativeReport, NativeTier
from runtime.contract.state_folder import NATIVE_CACHE_ENV

Tier = Literal["python", "native"]

# why the native tier does not run, in the words of the runtime's event
NO_COMPILER = "no C compiler or no Python.h here"


def native_cache() -> Path:
    """Where the tools keep the native tier's compiled modules between runs: the folder
    PADT_NATIVE_CACHE names (which runtimes on this machine share), else the user's cache."""
    shared = os.environ.get(NATIVE_CACHE_ENV)
    if shared:
        return Path(shared)
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "padt" / "native"


def native_tier(cache: Path | None = None) -> NativeTier:
    """The native tier, its modules kept in `cache` (default: `native_cache()`); not
    `available` where there is no C compiler or no Python.h."""
    folder = cache or native_cache()
    folder.mkdir(parents=True, exist_ok=True)
    return NativeTier(folder)


def one_tier(asked: Tier) -> tuple[NativeTier | None, str]:
    """For a tool that runs one tier: the native tier to give its resource (None: Python),
    and what to say once on stderr when native was asked for but cannot be built here,
    where the bodies run as Python, as `padt runtime` runs them then."""
    if asked == "python":
        return None, ""
    native = native_tier()
    if native.available:
        return native, ""
    return None, f"{NO_COMPILER}: the bodies run as Python"


def left_as_python(report: NativeReport | None) -> list[str]:
    """What a tool that ran the native tier says of the bodies that did not run as C, a
    line each, with the reason the runtime's event gives (none where all ran as C)."""
    if report is None:
        return []
    lines = [f"{pou} runs as Python: {reason}" for pou, reason in report.left]
    return lines + [f"not built: {failed}" for failed in report.failed]
