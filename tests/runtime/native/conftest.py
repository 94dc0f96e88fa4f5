"""The native tier needs a C compiler and Python's headers. Both are on the development
machines and in CI (scripts/install-c-compiler.sh, which `make test` runs); where they are
missing the tests skip with the reason, except in CI, where they must run."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from runtime.native.tier import NativeTier


@pytest.fixture(scope="session")
def native_tier(tmp_path_factory: pytest.TempPathFactory) -> NativeTier:
    """One tier (and one cache of compiled modules) for the whole session."""
    tier = NativeTier(tmp_path_factory.mktemp("native-cache"))
    if not tier.available:
        if os.environ.get("CI") == "true":
            pytest.fail("the native tier needs a C compiler and Python.h; CI must have both")
        pytest.skip("no C compiler or no Python.h here: the native tier cannot build")
    return tier


@pytest.fixture
def fresh_tier(tmp_path: Path, native_tier: NativeTier) -> NativeTier:
    """A tier of its own (its own module copies), sharing the session's compiled modules."""
    return NativeTier(native_tier.cache, native_tier.toolchain)
