"""The plain functions behind the Parameters and Events screens: a new parameter value is
checked before it is sent as the resource would check it, each disabled editor says why,
and the event filters select the newest matching rows."""

from __future__ import annotations

from datetime import datetime
from functools import partial

import pytest
import viser

from backend.engineering.resource_client import ResourceLogin
from frontend.gui_value import set_value
from frontend.permissions import Allowed, allowed
from frontend.screens import events, parameters
from frontend.state_rules import program_allows
from runtime.contract import protocol as p
from runtime.contract.artifact import ProgramConfig, ResourceConfig
from runtime.contract.parameters import RESOURCE_BY_NAME, ParameterError
from tests.conftest import free_port

RESOURCE = ResourceConfig("Tank1", safety_time_ms=600, watchdog_ms=200, target_cycle_ms=100)
PROGRAMS = [ProgramConfig("Main", "Main", 1, max_duration_us=50_000)]
REPLY = p.ParametersReply(RESOURCE, PROGRAMS)


def login(level: str) -> ResourceLogin:
    return ResourceLogin("token", b"key", "public", "anna", level)


@pytest.mark.parametrize(
    ("name", "text", "value"),
    [
        ("watchdog_ms", "300", 300),
        ("watchdog_ms", " 250 ms ", 250),
        ("target_cycle_mode", "dynamic", "dynamic"),
        ("allow_online_settings", "OFF", False),
        ("target_cycle_ms", "0", 0),
    ],
)
def test_a_good_value_passes(name: str, text: str, value: object) -> None:
    assert parameters.check_change(name, text, RESOURCE, PROGRAMS) == value


@pytest.mark.parametrize(
    ("name", "text", "why"),
    [
        ("watchdog_ms", "ten", "whole number of ms"),
        ("watchdog_ms", "5", "must be from 6 to 7500"),
        ("watchdog_ms", "301", "more than half the safety time"),
        ("watchdog_ms", "90", "longer than the watchdog time"),  # target 100 ms
        ("watchdog_ms", "200", "is 200 ms already"),
        ("target_cycle_mode", "fast", "must be one of fixed"),
        ("allow_online_settings", "maybe", "ON or OFF"),
    ],
)
def test_a_bad_value_is_refused_with_the_reason(name: str, text: str, why: str) -> None:
    with pytest.raises(ParameterError, match=why):
        parameters.check_change(name, text, RESOURCE, PROGRAMS)


def test_the_time_slices_of_the_programs_bound_the_watchdog() -> None:
    sliced = [ProgramConfig("Main", "Main", 1, max_duration_us=150_000)]
    resource = ResourceConfig("Tank1", watchdog_ms=200, target_cycle_ms=0)
    with pytest.raises(ParameterError, match="time slices"):
        parameters.check_change("watchdog_ms", "100", resource, sliced)


def test_each_disabled_editor_says_why() -> None:
    def verdict(name: str, reply: p.ParametersReply, level: str) -> str:
        check = partial(allowed, "read-write", login(level), open_access=False)
        spec = RESOURCE_BY_NAME.get(name)
        result = parameters.verdict(name, spec, reply, lambda c: check(c))
        return "" if result.ok else result.reason

    assert verdict("watchdog_ms", REPLY, "read-write") == ""
    assert verdict("watchdog_ms", REPLY, "operator") == (
        "needs read-write at the resource; anna is operator"
    )
    assert "needs administrator" in verdict("allow_online_settings", REPLY, "read-write")
    assert verdict("allow_online_settings", REPLY, "administrator") == ""
    assert "changes only with a download" in verdict("safety_time_ms", REPLY, "administrator")
    assert "program parameters" in verdict("Main / priority", REPLY, "administrator")
    closed = p.ParametersReply(ResourceConfig("Tank1", allow_online_settings=False), PROGRAMS)
    assert "Allow Online Settings is OFF" in verdict("watchdog_ms", closed, "administrator")
    assert verdict("allow_online_settings", closed, "administrator") == ""


def event(seq: int, kind: str, user: str | None, age_s: int) -> p.Event:
    return p.Event(seq, NOW - age_s * 10**9, kind, f"event {seq}", user, {})


NOW = 1_750_000_000 * 10**9
LOG = [
    event(1, "load", None, 7200),
    event(2, "login", "anna", 3000),
    event(3, "stop", "anna", 300),
    event(4, "start", "ben", 10),
]


def seqs(chosen: events.Filter) -> list[int]:
    shown, matched = events.select(LOG, chosen, NOW)
    assert matched == len(shown)
    return [x.seq for x in shown]


def test_filters_select_the_newest_first() -> None:
    assert seqs(events.Filter()) == [4, 3, 2, 1]
    assert seqs(events.Filter(kind="stop")) == [3]
    assert seqs(events.Filter(user="anna")) == [3, 2]
    assert seqs(events.Filter(user=events.NO_USER)) == [1]
    assert seqs(events.Filter(since_s=600)) == [4, 3]
    assert seqs(events.Filter(since_s=3600, user="anna")) == [3, 2]


def test_a_range_from_to_in_local_time_takes_in_whole_days_and_minutes() -> None:
    ago = NOW - 3000 * 10**9  # event 2
    assert seqs(events.Filter(from_ns=ago)) == [4, 3, 2]
    assert seqs(events.Filter(from_ns=ago + 1)) == [4, 3]
    assert seqs(events.Filter(from_ns=ago, to_ns=NOW - 300 * 10**9)) == [3, 2]
    day = datetime.fromtimestamp(NOW / 1e9).astimezone().strftime("%Y-%m-%d")
    first, _ = events.parse_moment(day, end=False)
    last, _ = events.parse_moment(f" {day} ", end=True)
    assert first is not None and last is not None and last - first == 86_400 * 10**9 - 1
    minute, _ = events.parse_moment(f"{day} 14:05", end=True)
    second, _ = events.parse_moment(f"{day} 14:05:59", end=False)
    assert minute == second + 10**9 - 1 if minute and second else False
    assert events.parse_moment("", end=False) == (None, "")
    moment, error = events.parse_moment("yesterday", end=False)
    assert moment is None and "'yesterday' is no date and time" in error


def test_a_long_log_shows_a_bounded_number_of_rows_and_counts_the_rest() -> None:
    many = [event(n, "write", "anna", 0) for n in range(1, events.MAX_ROWS + 51)]
    shown, matched = events.select(many, events.Filter(), NOW)
    assert len(shown) == events.MAX_ROWS and matched == events.MAX_ROWS + 50
    assert shown[0].seq == events.MAX_ROWS + 50
    page = events.render(shown, matched, len(many), "short-term")
    assert f"{matched} of {len(many)} events" in page and "the newest 200 shown" in page


def test_what_a_user_wrote_is_escaped() -> None:
    hostile = p.Event(1, NOW, "write", "<script>x</script>", "<b>", {"v": "<i>"})
    page = events.render([hostile], 1, 1, "short-term")
    assert "<script>" not in page and "<b>" not in page and "<i>" not in page


def test_a_program_at_a_breakpoint_can_be_stopped_not_frozen() -> None:
    stats = p.CycleStatistics(1, 0.1, 0.1, 0.1, 0.1, 100.0, 0.0, 0, 0)
    held = p.ProgramStatus("Main", 1, 0, p.ProgramState.BKPT, "0000ABCD", 5, 1, None, "m.st:3")
    status = p.Status("R", p.ResourceState.RUN, "0000ABCD", None, "x", 9, 100.0, stats, False,
                      "open", None, [held])  # fmt: skip
    assert program_allows(p.StopProgram, status, held).ok
    assert program_allows(p.Freeze, status, held) == Allowed(False, "Main is not running")


def test_a_filter_chosen_stays_when_new_users_come_and_goes_with_its_user() -> None:
    """New options keep the choice while it is offered (viser does; the screen writes no
    value back, which would undo a choice the browser made meanwhile)."""
    server = viser.ViserServer(port=free_port(), verbose=False)
    try:
        user = server.gui.add_dropdown("By user", (events.ALL_USERS, "admin"))
        set_value(user, "admin")
        events._options(user, (events.ALL_USERS, "admin", "anna", events.NO_USER))
        assert user.value == "admin"
        events._options(user, (events.ALL_USERS, "anna"))
        assert user.value == events.ALL_USERS
    finally:
        server.stop()
