"""The session's native tier, as the native tests have it."""

from tests.runtime.native.conftest import native_tier  # noqa: F401
