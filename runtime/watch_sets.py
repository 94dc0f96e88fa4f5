"""Watch sets: what each client views, so that only that is sent (spec section 12).

A client registers a set of variables and a period; after the CPU cycle in which a period
has passed, the runtime sends the set's values (those of that cycle) in one message, each
with its quality. A set belongs to the session that made it and ends with it; the client
also holds a liveliness token for each of its sets, and when the client goes away Zenoh
withdraws the token and the runtime drops the set. Quotas per session (protocol.py) keep
what one client can ask for inside what the cycle can afford; quotas per account and a
share per level keep one account, or all the readers together, from taking the sets the
others need (docs/protocol.md#quotas). A session sees and stops its own sets only.
"""

from __future__ import annotations

import json
from collections.abc import Callable, KeysView
from dataclasses import dataclass
from typing import Any

from runtime.contract.protocol import (
    MAX_SET_VARIABLES,
    MAX_SETS_PER_SESSION,
    MAX_VALUES_PER_SECOND,
    encode_list,
)
from runtime.contract.refusal import Refusal
from runtime.contract.values import jsonable

MAX_SETS = 64  # on one resource, of all sessions
MAX_SETS_PER_ACCOUNT = 16  # of all the sessions of one account
# the sets of all sessions of a level and the levels below it: the rest is kept for the
# levels above (an operator can watch however many sets the readers hold)
LEVEL_SHARES = {"read": 32, "operator": 48, "read-write": 56, "administrator": MAX_SETS}


@dataclass
class WatchSet:
    watch_id: str
    paths: tuple[str, ...]  # canonical variable paths, in the client's order
    period_ns: int
    owner: str | None = None  # the session token that made it; None when access is open
    account: str | None = None  # the user of that session, and its level
    level: str | None = None
    registered_ns: int = 0
    next_due_ns: int = 0  # clock time after which it is sent again
    revision: int = 1  # counts the changes of the set

    @property
    def values_per_second(self) -> float:
        return len(self.paths) * 1e9 / self.period_ns


@dataclass(frozen=True)
class WatchSnapshot:
    """A set's values as one cycle left them, read between two cycles; the message is
    built from it elsewhere (on the link's publisher thread)."""

    cycle: int
    revision: int
    values: list[Any]  # in the order of the set's paths
    qualities: str  # one letter per value (protocol.QUALITY_LETTERS)

    def message(self) -> bytes:
        """The encoded WatchPublication: encoder calls alone for the common case, a
        conversion of non-finite REALs to text only when there are some."""
        head = {"cycle": self.cycle, "revision": self.revision, "qualities": self.qualities}
        try:
            values = encode_list(self.values)
        except ValueError:  # a NaN or an infinity: as text, since strict JSON has none
            values = encode_list([jsonable(value) for value in self.values])
        return (json.dumps(head)[:-1] + ', "values": ' + values + "}").encode()


class WatchSets:
    def __init__(self) -> None:
        self._sets: dict[str, WatchSet] = {}

    def set(self, watch_set: WatchSet) -> None:
        """Register (or replace) a set within the quotas; it is due at once."""
        existing = self._sets.get(watch_set.watch_id)
        if existing is not None and existing.owner != watch_set.owner:
            raise Refusal("forbidden", f"watch set {watch_set.watch_id} is another session's")
        if existing is None:
            self._within_shares(watch_set)
        others = [s for s in self.owned_by(watch_set.owner) if s.watch_id != watch_set.watch_id]
        if len(others) >= MAX_SETS_PER_SESSION:
            raise Refusal("quota", f"a session may watch at most {MAX_SETS_PER_SESSION} sets")
        if len(watch_set.paths) > MAX_SET_VARIABLES:
            raise Refusal("quota", f"a watch set holds at most {MAX_SET_VARIABLES} variables")
        rate = watch_set.values_per_second + sum(s.values_per_second for s in others)
        if rate > MAX_VALUES_PER_SECOND:
            raise Refusal(
                "quota",
                f"a session may watch at most {MAX_VALUES_PER_SECOND} values per second "
                f"(this set would make it {rate:.0f}): fewer variables or a longer period",
            )
        self._sets[watch_set.watch_id] = watch_set

    def _within_shares(self, new: WatchSet) -> None:
        """A new set within the resource's limit, its account's and its level's share."""
        if len(self._sets) >= MAX_SETS:
            raise Refusal("too_many", "too many watch sets on this resource")
        if new.account is not None:
            of_account = sum(1 for s in self._sets.values() if s.account == new.account)
            if of_account >= MAX_SETS_PER_ACCOUNT:
                raise Refusal(
                    "quota",
                    f"the sessions of {new.account} may watch at most {MAX_SETS_PER_ACCOUNT} "
                    "sets together",
                )
        if new.level in LEVEL_SHARES:
            below = tuple(LEVEL_SHARES)[: tuple(LEVEL_SHARES).index(new.level) + 1]
            held = sum(1 for s in self._sets.values() if s.level in below)
            if held >= LEVEL_SHARES[new.level]:
                raise Refusal(
                    "too_many",
                    f"the sessions of level {new.level} and below hold "
                    f"{LEVEL_SHARES[new.level]} watch sets, their share of this resource's "
                    f"{MAX_SETS}; the rest is kept for higher levels",
                )

    def owned_by(self, owner: str | None) -> list[WatchSet]:
        return [s for _, s in sorted(self._sets.items()) if s.owner == owner]

    def drop(self, watch_id: str, owner: str | None) -> bool:
        """Stop a set of the session `owner`; another session's is refused."""
        watch_set = self._sets.get(watch_id)
        if watch_set is None:
            return False
        if watch_set.owner != owner:
            raise Refusal("forbidden", f"watch set {watch_id} is another session's")
        del self._sets[watch_id]
        return True

    def drop_where(self, gone: Callable[[WatchSet], bool]) -> None:
        for watch_id in [i for i, s in sorted(self._sets.items()) if gone(s)]:
            del self._sets[watch_id]

    def ids(self, owner: str | None) -> list[str]:
        """The ids of the sets of the session `owner`."""
        return [s.watch_id for s in self.owned_by(owner)]

    def __len__(self) -> int:
        return len(self._sets)

    def every_id(self) -> KeysView[str]:
        """The ids of every session's sets (a live view, for the link to follow)."""
        return self._sets.keys()

    def get(self, watch_id: str) -> WatchSet | None:
        return self._sets.get(watch_id)

    def due(self, now_ns: int, all_of_them: bool = False) -> list[WatchSet]:
        """The sets to send now (`all_of_them`: after a command, which may have changed
        what they show), longest waiting first; `sent` marks those that went."""
        due = [s for s in self._sets.values() if all_of_them or now_ns >= s.next_due_ns]
        return sorted(due, key=lambda s: (s.next_due_ns, s.watch_id))

    @staticmethod
    def sent(watch_set: WatchSet, now_ns: int) -> None:
        """A set that was due is next due one period after it was due, so the rate does
        not drift by the part of a cycle it waited; one that fell a whole period behind
        starts afresh. One sent early, after a command, keeps its time."""
        if now_ns < watch_set.next_due_ns:
            return
        following = watch_set.next_due_ns + watch_set.period_ns
        watch_set.next_due_ns = following if following > now_ns else now_ns + watch_set.period_ns
