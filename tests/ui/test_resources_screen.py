"""The Resources screen's table as HTML: the host column, a long host name cut with its
whole name in the tooltip, and a resource not yet verified."""

from __future__ import annotations

from frontend.screens.resources import render
from runtime.contract import protocol as p


def _status(host: str | None) -> p.Status:
    stats = p.CycleStatistics(1, 0.1, 0.1, 0.1, 0.1, 20.0, 0.0, 0, 0)
    return p.Status(
        "Line1", p.ResourceState.RUN, "0A1B2C3D", None, "P", 1, 20.0, stats, False, "users",
        None, [], None, host=host,
    )  # fmt: skip


def test_the_host_is_a_column_beside_the_resource() -> None:
    page = render([("Line1", _status("plc-hall1")), ("Line2", None)], "Line1")
    assert "<th" in page and ">Host</th>" in page
    assert 'data-host="Line1" title="plc-hall1">plc-hall1</td>' in page
    long = "a" * 200 + ".example"
    page = render([("Line1", _status(long))], "Line1")
    assert f'title="{long}">{long}</td>' in page and "text-overflow:ellipsis" in page
    # an older runtime says no host; one not verified has no row of values at all
    assert 'data-host="Line1" title="">-</td>' in render([("Line1", _status(None))], None)
    assert "log in to the resource to see its state" in render([("Line2", None)], None)
