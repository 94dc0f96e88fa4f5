"""Fair share for the lowest level (issue 30, items 10-12), against a runtime process over a
real Zenoh router: a reader sees and stops only its own watch sets, readers cannot take the
watch sets an operator needs, and a flood of logins does not push the operators' actions
out of the long-term event log."""

from __future__ import annotations

import time
from collections.abc import Iterator
from contextlib import ExitStack, contextmanager
from pathlib import Path
from typing import Any

import pytest
import zenoh

from backend.compiler.pipeline import compile_sources
from backend.compiler.source import SourceFile
from backend.engineering.resource_client import ResourceClient, WatchHandle
from runtime.contract import scram
from runtime.contract.accounts import hash_password
from runtime.contract.artifact import ResourceConfig, UserAccount
from runtime.contract.protocol import Event, GetEvents, GetWatches, ResetStats, Unwatch
from runtime.contract.refusal import Refusal
from runtime.contract.state_folder import events_path
from runtime.event_log import EventLog
from runtime.resource import MAX_SESSIONS_PER_ACCOUNT
from tests.support.runtime_process import running_resource, store_artifact

TEXT = "PROGRAM P VAR n : INT; END_VAR n := n + 1; END_PROGRAM"
RESOURCE = "Shared"
PASSWORD = "Share-1"
READERS = ["r1", "r2", "r3", "r4"]
LONG_CAPACITY = 10_000  # the runtime's long-term event log
ACCOUNTS = {**dict.fromkeys(READERS, "read"), "op": "operator", "admin": "administrator"}


@contextmanager
def guarded_runtime(state: Path, endpoint: str) -> Iterator[ResourceClient]:
    config = ResourceConfig(name=RESOURCE, autostart="cold", target_cycle_ms=20)
    users = [UserAccount(n, level, hash_password(PASSWORD)) for n, level in ACCOUNTS.items()]
    result = compile_sources([SourceFile("p.st", TEXT)], resource=config, users=users)
    assert result.artifact is not None
    store_artifact(state, result.artifact)
    with running_resource(RESOURCE, state, endpoint) as (_, client):
        yield client


def logged_in(session: zenoh.Session, user: str) -> ResourceClient:
    client = ResourceClient(session, RESOURCE)
    client.login(user, PASSWORD)
    return client


def watch(client: ResourceClient, stack: ExitStack) -> WatchHandle:
    handle = client.watch(["P.n"], lambda values: None, period_ms=1000)
    stack.callback(handle.close)
    return handle


def test_a_reader_sees_and_stops_only_its_own_watch_sets(
    tmp_path: Path, zenoh_endpoint: str
) -> None:
    with guarded_runtime(tmp_path, zenoh_endpoint) as client, ExitStack() as stack:
        anna, bert = logged_in(client.session, "r1"), logged_in(client.session, "r2")
        hers = watch(anna, stack)
        his = watch(bert, stack)
        assert bert.ask(GetWatches()).watches == [his.watch_id]
        assert anna.ask(GetWatches()).watches == [hers.watch_id]
        with pytest.raises(Refusal) as refused:
            bert.ask(Unwatch(hers.watch_id))
        assert refused.value.code == "forbidden"
        assert hers.watch_id in anna.ask(GetWatches()).watches  # still there
        assert anna.ask(Unwatch(hers.watch_id)).dropped


def test_readers_leave_watch_sets_for_an_operator(tmp_path: Path, zenoh_endpoint: str) -> None:
    """8 reader logins (two of each of four accounts) ask for 8 sets each: 64, the
    resource's limit. An account, and the read level, get a share of it only."""
    with guarded_runtime(tmp_path, zenoh_endpoint) as client, ExitStack() as stack:
        refusals: dict[str, list[str]] = {}
        for reader in READERS * 2:
            session = logged_in(client.session, reader)
            for _ in range(8):
                try:
                    watch(session, stack)
                except Refusal as refused:
                    refusals.setdefault(reader, []).append(refused.code)
        assert refusals, "the readers took every watch set of the resource"
        operator = logged_in(client.session, "op")
        for _ in range(8):
            watch(operator, stack)  # none refused
        watch(logged_in(client.session, "admin"), stack)


def long_term(client: ResourceClient) -> list[Event]:
    entries: list[Event] = []
    while batch := client.ask(GetEvents(after=entries[-1].seq if entries else 0, log="long")):
        if not batch.events:
            return entries
        entries += batch.events
    return entries


def nearly_full_log(state: Path, free: int) -> None:
    """A long-term log of young entries, `free` places short of its capacity."""
    log = EventLog(time.time_ns, long_path=events_path(state), write_behind=True)
    for number in range(LONG_CAPACITY - free):
        log.record("parameter", f"earlier action {number}", user="op", long_term=True)
    log.close()


def quick_login(client: ResourceClient, user: str) -> dict[str, Any]:
    """One login by challenge and response, the password's scrypt derived once per salt
    (a flood costs its sender little: the resource's side of a login is cheap)."""
    client_nonce = scram.new_nonce()
    challenge = client.command("login_begin", user=user, nonce=client_nonce)
    if not challenge["ok"]:
        return challenge
    nonce, salt = challenge["nonce"], scram.unb64(challenge["salt"])
    cost = (challenge["n"], challenge["r"], challenge["p"])
    if salt not in SALTED:
        SALTED[salt] = scram.salted_password(PASSWORD, salt, *cost)
    auth = scram.auth_message(RESOURCE, user, client_nonce, nonce, salt, *cost)
    proof = scram.ClientExchange(SALTED[salt], auth).proof
    return client.command("login", user=user, nonce=nonce, proof=proof)


SALTED: dict[bytes, bytes] = {}


def test_a_login_flood_does_not_displace_the_operators_actions(
    tmp_path: Path, zenoh_endpoint: str
) -> None:
    """A long-term log 300 entries short of full, then 2,000 logins of a reader: the
    operator's next action still goes into the long-term log."""
    nearly_full_log(tmp_path, free=300)
    with guarded_runtime(tmp_path, zenoh_endpoint) as client:
        for _ in range(2000):
            quick_login(client, "r1")
        operator = logged_in(client.session, "op")
        operator.ask(ResetStats())
        entries = long_term(operator)
        assert entries[-1].kind == "stats" and entries[-1].user == "op"
        assert not [e for e in entries if e.kind == "rejected"]
        logins = [e for e in entries if e.kind == "login"]
        assert len(logins) < 10, "every login took a place in the long-term log"
        assert "r1" in {e.user for e in logins}  # logins are there all the same


def test_logins_take_a_share_of_the_long_term_log_only(tmp_path: Path) -> None:
    """The rule itself on a small log: logins beyond their share stay short-term, and
    the next one kept counts them."""
    log = EventLog(time.time_ns, long_path=tmp_path / "events.jsonl", shares={"login": 3})
    for number in range(5):
        log.record("login", f"login {number}", user="r1", long_term=True)
    log.record("stats", "cycle statistics reset", user="op", long_term=True)
    kept = [e.message for e in log.long_term()]
    assert kept == ["login 0", "login 1", "login 2", "cycle statistics reset"]
    assert [e.message for e in log.recent()][3:5] == ["login 3", "login 4"]
    again = EventLog(time.time_ns, long_path=tmp_path / "events.jsonl", shares={"login": 3})
    again.record("login", "login 5", user="r1", long_term=True)  # the share holds a restart
    assert len(again.long_term()) == 4


def test_an_account_holds_a_bounded_number_of_sessions(tmp_path: Path, zenoh_endpoint: str) -> None:
    """Past 64 sessions of one account its oldest end: a flood of logins (here slowed to
    the account's login rate after its first 30) holds no memory for 8 hours."""
    with guarded_runtime(tmp_path, zenoh_endpoint) as client:
        first = logged_in(client.session, "r1")
        assert first.ask(GetWatches()).watches == []
        logins = 1
        while logins <= MAX_SESSIONS_PER_ACCOUNT:
            reply = quick_login(client, "r1")
            logins += reply["ok"]
            if not reply["ok"]:
                assert reply["error"]["code"] == "busy", reply
                time.sleep(0.5)
        with pytest.raises(Refusal) as ended:
            first.ask(GetWatches())
        assert ended.value.code == "unauthenticated"
        logged_in(client.session, "op").ask(GetWatches())  # other accounts unaffected
