"""What one session may ask of a resource's online values (quotas), which session owns a
watch set, overruns counted by the period, and a defect of a command handler turned into an
`internal` refusal instead of the end of the runtime."""

from __future__ import annotations

import pytest

from runtime import commands
from runtime.contract import protocol as p
from runtime.contract.accounts import hash_password
from runtime.contract.artifact import UserAccount
from tests.support.resource_harness import Harness, harness

TEXT = "PROGRAM P VAR n : INT; END_VAR n := n + 1; END_PROGRAM"
USERS = [
    UserAccount("anna", "read", hash_password("Secret-1")),
    UserAccount("bert", "administrator", hash_password("Secret-1")),
]


def logged_in(h: Harness, name: str) -> str:
    h.token = h.login(name, "Secret-1")
    return h.token


@pytest.fixture
def guarded() -> Harness:
    return harness(TEXT, users=USERS)


def test_a_session_watches_at_most_eight_sets(guarded: Harness) -> None:
    logged_in(guarded, "anna")
    for number in range(p.MAX_SETS_PER_SESSION):
        guarded.ok("watch", id=f"a{number}", variables=["P.n"])
    assert guarded.refused("watch", id="a8", variables=["P.n"]) == "quota"
    guarded.ok("watch", id="a0", variables=["P.n"], period_ms=50)  # replacing one is fine
    logged_in(guarded, "bert")  # another session has its own quota
    guarded.ok("watch", id="b0", variables=["P.n"])


def test_a_set_grows_only_within_its_limits(guarded: Harness) -> None:
    logged_in(guarded, "anna")
    batch = ["P.n"] * p.MAX_WATCHED
    guarded.ok("watch", id="big", variables=batch, period_ms=1000)
    for _ in range(p.MAX_SET_VARIABLES // p.MAX_WATCHED - 1):
        guarded.ok("watch", id="big", variables=batch, period_ms=1000, append=True)
    reply = guarded.cmd("watch", id="big", variables=batch, period_ms=1000, append=True)
    assert (
        reply["error"]["code"] == "quota" and "at most 20000 variables" in reply["error"]["message"]
    )


def test_the_values_per_second_of_a_session_are_limited(guarded: Harness) -> None:
    logged_in(guarded, "anna")
    fast = ["P.n"] * 2001  # 2,001 values every 10 ms: 200,100 a second
    assert guarded.refused("watch", id="fast", variables=fast, period_ms=10) == "quota"
    guarded.ok("watch", id="fast", variables=fast, period_ms=20)
    # the session's sets count together: another 100,000 a second is too much now
    assert guarded.refused("watch", id="more", variables=fast, period_ms=20) == "quota"


def test_a_set_belongs_to_its_session(guarded: Harness) -> None:
    logged_in(guarded, "anna")
    guarded.ok("watch", id="mine", variables=["P.n"])
    logged_in(guarded, "bert")
    assert guarded.refused("watch", id="mine", variables=["P.n"], append=True) == "forbidden"
    owners = {s.watch_id: s.owner for s in guarded.resource.online.watches.owned_by(guarded.token)}
    assert "mine" not in owners


def test_a_late_period_is_an_overrun() -> None:
    h = harness(TEXT, target_cycle_ms=100)
    h.cycle(3)
    assert h.resource.status().stats.overruns == 0
    h.clock.advance(20_000_000)  # a period of 120 ms: within a quarter of the target
    h.cycle()
    assert h.resource.status().stats.overruns == 0
    h.clock.advance(200_000_000)  # 300 ms after the last start
    h.cycle()
    assert h.resource.status().stats.overruns == 1


def test_online_changes_of_the_target_cycle_count_no_overrun() -> None:
    """What `test_target_cycle_modes_and_an_online_change` does to a runtime process, here
    on a virtual clock: there the real one makes a late period a matter of machine load."""
    h = harness(TEXT, target_cycle_ms=50, target_cycle_mode="fixed")
    h.cycle(3)
    h.ok("set_parameter", name="target_cycle_mode", value="dynamic")
    h.cycle_ns = 1_000_000  # no waiting for the target any more
    h.cycle(5)
    h.ok("set_parameter", name="target_cycle_mode", value="fixed")
    h.ok("set_parameter", name="target_cycle_ms", value=100)
    h.cycle_ns = 100_000_000
    h.cycle(3)
    assert h.resource.status().stats.overruns == 0


def test_a_defect_in_a_handler_is_an_internal_refusal(monkeypatch: pytest.MonkeyPatch) -> None:
    h = harness(TEXT)

    def broken(resource: object, command: object) -> object:
        raise KeyError("a defect")

    monkeypatch.setitem(commands.HANDLERS, p.GetForcing, broken)
    reply = h.cmd("forcing")
    assert reply["error"]["code"] == "internal"
    assert "KeyError" in reply["error"]["message"]
    events = h.ok("events")["events"]
    assert events[-1]["kind"] == "error" and "a defect" in events[-1]["message"]
    assert h.ok("status")["status"]["state"] == "RUN"
    h.cycle()
    assert h.value("P.n") >= 1
