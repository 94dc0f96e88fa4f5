"""A client checks the chain of a resource's long-term event log from what the resource
sends (each entry with its `prev`): intact, across pages, and broken where a line of the
file was changed."""

from __future__ import annotations

from pathlib import Path

from backend.engineering.event_chain import ChainState, check_chain
from runtime.contract import protocol as p
from runtime.contract.protocol import Event
from runtime.contract.wire import decode
from runtime.event_log import EventLog
from tests.support.resource_harness import harness

T0 = 1_750_000_000 * 10**9


def filled(path: Path, count: int) -> EventLog:
    log = EventLog(lambda: T0, long_path=path)
    for i in range(count):
        log.record("login", f"entry {i}", user="anna", long_term=True)
        log.record("state", "short-term only, a gap in the long-term seqs")
    return log


def page(log: EventLog, after: int, limit: int) -> tuple[list[Event], list[str]]:
    entries = log.long_term_after(after, limit)
    return [event for event, _ in entries], [prev for _, prev in entries]


def test_an_intact_log_verifies_page_by_page(tmp_path: Path) -> None:
    log = filled(tmp_path / "events.jsonl", 7)
    state, after = ChainState(), 0
    while True:
        events, prevs = page(log, after, 3)
        if not events:
            break
        state, after = check_chain(events, prevs, state), events[-1].seq
    assert state.ok and state.entries == 7
    assert state.last_digest == log.head  # the chain ends where the resource says it does
    assert state.describe() == "verified, 7 entries up to seq 13"
    assert ChainState().describe().startswith("not checked")


def test_a_changed_line_breaks_the_chain_at_the_entry_after_it(tmp_path: Path) -> None:
    path = tmp_path / "events.jsonl"
    filled(path, 4)
    lines = path.read_bytes().splitlines()
    lines[1] = lines[1].replace(b"entry 1", b"entry X")  # still a canonical entry
    path.write_bytes(b"".join(line + b"\n" for line in lines))
    reloaded = EventLog(lambda: T0, long_path=path)  # the resource after a restart
    events, prevs = page(reloaded, 0, 100)
    state = check_chain(events, prevs)
    assert not state.ok
    assert state.broken_seq == events[2].seq
    assert state.describe().startswith(f"broken at seq {events[2].seq}: prev is not")


def test_the_events_command_pages_through_the_long_term_log_with_its_chain() -> None:
    h = harness("PROGRAM P VAR n : INT; END_VAR n := n + 1; END_PROGRAM")
    for value in (30, 40, 50):
        h.ok("set_parameter", name="com_slice_ms", value=value)
    h.ok("stop")
    state, after, pages = ChainState(), 0, 0
    while True:
        reply = decode(
            p.EventsReply,
            {
                k: v
                for k, v in h.ok("events", after=after, limit=2, log="long").items()
                if k != "ok"
            },
        )
        if not reply.events:
            break
        assert len(reply.prev) == len(reply.events)
        state, after, pages = (
            check_chain(reply.events, reply.prev, state),
            reply.events[-1].seq,
            pages + 1,
        )
    assert state.ok and pages >= 2
    assert [e.kind for e in h.resource.events.long_term()][-4:] == ["parameter"] * 3 + ["stop"]
    assert state.entries == len(h.resource.events.long_term())
    short = h.ok("events")  # the short-term log as before, without prev
    assert short.get("prev", []) == [] and len(short["events"]) >= state.entries
