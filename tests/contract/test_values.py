"""How values read on a screen: what an engineer would type back, at a useful precision."""

from __future__ import annotations

import pytest

from runtime.contract.values import format_for_display, format_value, to_real32


@pytest.mark.parametrize(
    ("value", "type_name", "shown"),
    [
        (22_704_898_659, "TIME", "T#22s704ms"),
        (-1_250_999_999, "TIME", "T#-1s250ms"),
        (999_999, "TIME", "T#0s"),
        (2**63 - 1, "LTIME", "LTIME#106751d23h47m16s854ms"),
        (True, "BOOL", "TRUE"),
        (False, "BOOL", "FALSE"),
        (to_real32(0.1), "REAL", "0.1"),
        (to_real32(123456.789), "REAL", "123456.8"),
        (0.1 + 0.2, "LREAL", "0.3"),
        (float("inf"), "REAL", "inf"),
        (-32768, "INT", "-32768"),
        ("abc", "STRING", "'abc'"),
    ],
)
def test_values_read_as_an_engineer_expects(value: object, type_name: str, shown: str) -> None:
    assert format_for_display(value, type_name) == shown


def test_more_time_resolution_on_request() -> None:
    assert format_for_display(22_704_898_659, "TIME", 1) == "T#22s704ms898us659ns"
    assert format_value(22_704_898_659, "TIME") == "T#22s704ms898us659ns"  # exact stays exact
