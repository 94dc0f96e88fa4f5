"""Failed logins on the bus slow guessing at an account whatever source the guesser claims,
and cannot be aimed at one client: the source of a request is named by its sender (Zenoh's
`source_info`), so it is no key for a lock. A real router and runtime process; the rogue is
a Zenoh session of the test."""

from __future__ import annotations

import json
import time
from contextlib import ExitStack
from pathlib import Path
from typing import Any

import zenoh

from backend.engineering.resource_client import ResourceClient
from runtime.contract.protocol import GetEvents, GetStatus
from runtime.contract.refusal import Refusal
from tests.runtime.test_hostile_clients import PASSWORD, RESOURCE, raw, target
from tests.support.runtime_process import client_session


def guess(rogue: zenoh.Session, user: str, source: zenoh.SourceInfo) -> str:
    """A login with a wrong proof, in the name of `source`: the code it is refused with."""
    begin = {"cmd": "login_begin", "user": user, "nonce": "g" * 24}
    challenge: dict[str, Any] = raw(rogue, json.dumps(begin).encode(), source=source)
    if not challenge["ok"]:
        return str(challenge["error"]["code"])
    login = {"cmd": "login", "user": user, "nonce": challenge["nonce"], "proof": "A" * 43 + "="}
    answer = raw(rogue, json.dumps(login).encode(), source=source)
    assert not answer["ok"], answer
    return str(answer["error"]["code"])


def test_failures_in_a_victims_name_do_not_lock_it_out(tmp_path: Path, zenoh_endpoint: str) -> None:
    with (
        target(tmp_path, zenoh_endpoint),
        client_session(zenoh_endpoint) as victim_session,
        client_session(zenoh_endpoint) as rogue,
    ):
        victim = ResourceClient(victim_session, RESOURCE)
        victim.command("status")  # one query: its source, the victim's session, is seen by all
        for number in range(5):
            code = guess(rogue, "admin", zenoh.SourceInfo(victim_session.id, 1000 + number))
            assert code == "login_failed"
        victim.login("admin", PASSWORD)
        assert victim.ask(GetStatus()).status.state == "RUN"


def test_guesses_from_made_up_sources_are_throttled(tmp_path: Path, zenoh_endpoint: str) -> None:
    with ExitStack() as stack:
        client = stack.enter_context(target(tmp_path, zenoh_endpoint))
        rogue = stack.enter_context(client_session(zenoh_endpoint))
        # 12 sessions whose ids the rogue claims in turn, 4 guesses each
        ids = [stack.enter_context(client_session(zenoh_endpoint)).id for _ in range(12)]
        codes = []
        for number in range(48):
            made_up = zenoh.SourceInfo(ids[number % 12], number)
            codes.append(guess(rogue, "admin", made_up))
        checked = codes.count("login_failed")
        assert codes.count("locked") > 0, codes
        assert checked < 20, codes  # of 48: the proofs the resource checked at all
        # the real user logs in once the lock has lapsed (at most 30 s after the last
        # failure), and the refusals are reported with the sources they claimed
        admin = ResourceClient(client.session, RESOURCE)
        deadline = time.monotonic() + 60
        while True:
            try:
                admin.login("admin", PASSWORD)
                break
            except Refusal as refused:
                assert refused.code in ("locked", "busy") and time.monotonic() < deadline, refused
                time.sleep(0.5)
        events = admin.ask(GetEvents(limit=1000)).events
        refusals = [e for e in events if "login of 'admin' refused" in e.message]
        assert refusals, [e.message for e in events]
        claimed = {source for e in refusals for source in e.details.get("sources", [])}
        assert len(claimed) >= 12, [e.details for e in refusals]  # and the real user's
