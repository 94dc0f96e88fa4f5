"""Online values (spec section 12): what clients view, as watch sets, and the values of a
set as one cycle left them, each with its quality. Only the reading happens between two
cycles; the message is built on the link's publisher thread (`WatchSnapshot.message`)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from runtime.code.instances import BoundVariable
from runtime.contract.protocol import LETTER_OF_QUALITY, ProgramState, Quality
from runtime.force_table import ForceTable
from runtime.variables import Variables
from runtime.watch_sets import WatchSet, WatchSets, WatchSnapshot

_RUNNING = (ProgramState.RUN,)  # a frozen program changes its values only when stepped: stale
_LIVE, _FORCED, _STALE, _DELETED, _BAD = (
    LETTER_OF_QUALITY[q]
    for q in (Quality.LIVE, Quality.FORCED, Quality.STALE, Quality.DELETED, Quality.BAD)
)


@dataclass
class _Plan:
    """How to read one watch set, made once per set and configuration (not per cycle)."""

    paths: tuple[str, ...]
    bound_of: list[BoundVariable]  # the configuration's variable list it was made for
    found: list[BoundVariable | None]  # per path; None: deleted by a reload
    read: Callable[[], list[Any]]  # the values of the paths found, in order
    owners: list[int]  # per path: id of its program, 0 for a global, -1 when deleted
    upper: list[str]  # per path, upper case: how forcing and lost devices name it


class OnlineValues:
    def __init__(self, variables: Variables) -> None:
        self._variables = variables
        self.watches = WatchSets()
        self._plans: dict[str, _Plan] = {}
        self._planning: set[str] = set()  # sets whose plan is being made on another thread
        self._failed: set[str] = set()  # sets whose plan failed there: made here, to raise

    def watch(
        self,
        watch_id: str,
        names: list[str],
        period_ms: int,
        append: bool,
        owner: str | None,
        now_ns: int,
        account: tuple[str, str] | None = None,
    ) -> tuple[list[str], int]:
        """Register what a client views, for the session `owner` (of `account`: its user
        and level, for their quotas); returns the canonical
        paths (all names must exist: a typo gets an error, not a silently empty field) and
        the set's revision. `append` adds to a set (a large set arrives in several
        requests)."""
        paths = tuple(self._variables.lookup(name).path.path for name in names)
        existing = self.watches.get(watch_id)
        if existing is not None and append:
            paths = existing.paths + paths
        revision = existing.revision + 1 if existing is not None else 1
        period = period_ms * 1_000_000
        user, level = account if account is not None else (None, None)
        self.watches.set(
            WatchSet(watch_id, paths, period, owner, user, level, now_ns, revision=revision)
        )
        return list(paths), revision

    def snapshot(
        self,
        watch_set: WatchSet,
        cycle: int,
        running: bool,
        forces: ForceTable,
        bad: frozenset[str] = frozenset(),
    ) -> WatchSnapshot:
        """A set's values now: live; forced; stale when nothing that could change it runs;
        deleted by a reload; bad: an input of a lost remote device (`bad`: upper-case
        paths), holding its safe value. This runs on the cycle thread for every watched
        value: the common case (all live) costs one read of the values and no more."""
        plan = self._plan(watch_set)
        found = plan.read()
        values = found if len(found) == len(plan.paths) else _with_deleted(plan, found)
        forcing = bool(forces.started_levels())
        halted = {id(p) for p in self._variables.programs if p.state not in _RUNNING}
        if running and not forcing and not bad and not halted and len(found) == len(values):
            qualities = _LIVE * len(values)
        else:
            qualities = "".join(
                _quality(owner, upper, running, halted, forcing and forces.is_forced(upper), bad)
                for owner, upper in zip(plan.owners, plan.upper, strict=True)
            )
        return WatchSnapshot(cycle, watch_set.revision, values, qualities)

    def planned(
        self, watch_set: WatchSet, elsewhere: Callable[[Callable[[], None]], object]
    ) -> bool:
        """Whether the set's reading plan is made. If not, its making is handed to
        `elsewhere` (another thread: 10 ms for 10,000 values, which the cycle thread would
        otherwise spend between two cycles the first time a set is sent)."""
        if self._current(watch_set) is not None:
            return True
        if watch_set.watch_id in self._failed:  # `snapshot` makes it, and meets the error
            self._failed.discard(watch_set.watch_id)
            return True
        if watch_set.watch_id not in self._planning:
            self._planning.add(watch_set.watch_id)
            elsewhere(lambda: self._plan_elsewhere(watch_set))
        return False

    def _plan_elsewhere(self, watch_set: WatchSet) -> None:
        try:
            self._plan(watch_set)
        except Exception:
            self._failed.add(watch_set.watch_id)
        finally:
            self._planning.discard(watch_set.watch_id)

    def _current(self, watch_set: WatchSet) -> _Plan | None:
        plan = self._plans.get(watch_set.watch_id)
        if (
            plan is None
            or plan.paths is not watch_set.paths
            or plan.bound_of is not self._variables.bound
        ):
            return None
        return plan

    def _plan(self, watch_set: WatchSet) -> _Plan:
        """The set's plan, made now unless it is current; any thread may make it (it
        reads only what a configuration holds, never a value)."""
        plan = self._current(watch_set)
        if plan is None:
            variables = self._variables
            bound_of = variables.bound  # first (see Variables.adopt)
            if len(self._plans) > 2 * len(self.watches) + 8:  # sets that are gone
                self._plans = {k: v for k, v in self._plans.items() if self.watches.get(k)}
            found = [variables.find(path) for path in watch_set.paths]
            present = [bound for bound in found if bound is not None]
            plan = _Plan(
                paths=watch_set.paths,
                bound_of=bound_of,
                found=found,
                read=variables.memory.reader(present),
                owners=[
                    -1 if b is None else id(b.program) if b.program is not None else 0
                    for b in found
                ],
                upper=[path.upper() for path in watch_set.paths],
            )
            self._plans[watch_set.watch_id] = plan
        return plan


def _with_deleted(plan: _Plan, found: list[Any]) -> list[Any]:
    present = iter(found)
    return [next(present) if bound is not None else None for bound in plan.found]


def _quality(
    owner: int, upper: str, running: bool, halted: set[int], forced: bool, bad: frozenset[str]
) -> str:
    if owner == -1:
        return _DELETED
    if forced:
        return _FORCED
    if upper in bad:
        return _BAD
    if not running or owner in halted:
        return _STALE
    return _LIVE
