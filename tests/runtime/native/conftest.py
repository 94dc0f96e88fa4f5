"""A tier of its own per test; the session's tier (`native_tier`) is in tests/conftest.py."""

from __future__ import annotations

from pathlib import Path

import pytest

from runtime.code.native.tier import NativeTier


@pytest.fixture
def fresh_tier(tmp_path: Path, native_tier: NativeTier) -> NativeTier:
    """A tier of its own (its own module copies), sharing the session's compiled modules."""
    return NativeTier(native_tier.cache, native_tier.toolchain)
