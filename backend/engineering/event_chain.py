"""Checking the hash chain of a resource's long-term event log from what the resource sends
(`GetEvents(log="long")`: each entry with its `prev`), page by page, without the file: each
entry's `prev` must be the SHA-256 of the line of the entry before it, and `seq` must rise.
The first entry's `prev` is the anchor (older entries may have been dropped by the 3-day
rule, docs/event-log.md)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

from runtime.contract.event_chain import entry_line, line_digest
from runtime.contract.protocol import Event


@dataclass(frozen=True)
class ChainState:
    entries: int = 0  # entries checked so far
    last_seq: int = 0
    last_digest: str | None = None  # digest of the last checked line (None: nothing yet)
    broken_seq: int | None = None  # seq of the first entry that does not follow
    problem: str = ""

    @property
    def ok(self) -> bool:
        return self.broken_seq is None

    def describe(self) -> str:
        """For people: 'verified, 12 entries', 'broken at seq 7: ...', 'not checked'."""
        if self.broken_seq is not None:
            return f"broken at seq {self.broken_seq}: {self.problem}"
        if self.entries == 0:
            return "not checked (no long-term entries yet)"
        return f"verified, {self.entries} entries up to seq {self.last_seq}"


def check_chain(
    events: Sequence[Event], prevs: Sequence[str], before: ChainState | None = None
) -> ChainState:
    """The state after checking the next page of long-term entries (`events` with their
    `prevs`, oldest first) following what `before` checked. A break stays the first one."""
    if len(events) != len(prevs):
        return replace(
            before or ChainState(),
            broken_seq=events[0].seq if events else 0,
            problem="the resource sent entries without their prev",
        )
    state = before or ChainState()
    for event, prev in zip(events, prevs, strict=True):
        if state.broken_seq is None:
            if state.last_digest is not None and prev != state.last_digest:
                state = replace(
                    state,
                    broken_seq=event.seq,
                    problem=f"prev is not the SHA-256 of the entry before (seq {state.last_seq})",
                )
            elif event.seq <= state.last_seq:
                state = replace(
                    state,
                    broken_seq=event.seq,
                    problem=f"seq {event.seq} does not follow seq {state.last_seq}",
                )
        try:
            digest = line_digest(entry_line(event, prev))
        except ValueError:  # not JSON any more (NaN): the next entry cannot match it
            digest = ""
        state = replace(state, entries=state.entries + 1, last_seq=event.seq, last_digest=digest)
    return state
