"""A tier of its own per test; the session's tier (`native_tier`) is in tests/conftest.py."""

from __future__ import annotations

from pathlib import Path
from types import ModuleType

import pytest

from runtime.code.native.image_views import memory_module
from runtime.code.native.tier import NativeTier


@pytest.fixture
def fresh_tier(tmp_path: Path, native_tier: NativeTier) -> NativeTier:
    """A tier of its own (its own module copies), sharing the session's compiled modules."""
    return NativeTier(native_tier.cache, native_tier.toolchain)


@pytest.fixture(scope="session")
def padt_memory(native_tier: NativeTier) -> ModuleType:
    """The views of memory images, built into the session's cache."""
    assert native_tier.toolchain is not None  # the tier skips (or fails in CI) without one
    return memory_module(native_tier.cache, native_tier.toolchain)
