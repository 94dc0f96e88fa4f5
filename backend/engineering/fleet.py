"""A fleet: the resources on a router mesh, seen and loaded together (`padt fleet`,
`POST /api/resources/load`, docs/cli.md).

**What is online, and what it says** (`survey`). A resource is online while its liveliness
token is there. Its status counts only when it is signed with the resource's key, as the
resource directory takes it (resource_directory.py): here the key is the one pinned in the
known resources (known_resources.py) at an earlier login from this account, or the one a
login made now proves (`login`). A resource whose key is not known is online with status
"not yet verified": its published status could be anyone's.

**One project into several resources** (`download_fleet`). One after another, in the order
given, each the project compiled for it (its name in place of the project's `[resource]
name`: `project.for_resource`) through the compile-twice gate, downloaded and backed up.
The first resource that refuses (the compile, its state, its level, no answer) or whose
backup cannot be written ends it: the resources after it are not tried.

**One online change of several resources** (`reload_fleet`). The same, for a reload: each
resource gets the project compiled for it and its reload plan against what it runs
(`preview_online_change`); a preview only (`confirmed` False) previews every one and
changes nothing; confirmed, each is reloaded in turn, and the first whose plan needs STOP
and a download, whose reload is refused, that does not answer, whose backup cannot be
written or whose kept online values cannot be set again ends it.
"""

from __future__ import annotations

import dataclasses
import threading
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal, TypeVar

import zenoh

from backend.engineering.compile_gate import compile_checked
from backend.engineering.download import download_checked
from backend.engineering.known_resources import KnownResources
from backend.engineering.online_change import (
    OnlineChangePreview,
    online_change,
    preview_online_change,
)
from backend.engineering.project import ProjectError, load_project
from backend.engineering.reload import ReloadOptions, needs_confirmation
from backend.engineering.resource_client import ResourceClient, ResourceUnreachable
from runtime.contract import signatures
from runtime.contract.keyspace import (
    alive_key,
    any_resource,
    resource_name_problem,
    resource_of,
    status_key,
)
from runtime.contract.parameters import RESOURCE_BY_NAME
from runtime.contract.protocol import ResourceState, Status, decode_publication
from runtime.contract.refusal import Refusal
from runtime.contract.wire import encode

# a resource publishes its status at least every second (runtime/cycle_driver.py)
STATUS_WAIT_S = 2.5
LIVELINESS_WAIT_S = 5.0

NOT_VERIFIED = "not yet verified"


@dataclass(frozen=True)
class FleetEntry:
    """A resource online, with its status when one signed with its key arrived; else
    `note` says why there is none (in words)."""

    resource: str
    status: Status | None
    note: str = ""

    @property
    def running(self) -> bool:
        return self.status is not None and self.status.state == ResourceState.RUN

    def as_json(self) -> dict[str, Any]:
        status = self.status
        return {
            "resource": self.resource,
            "verified": status is not None,
            "note": self.note,
            "host": status.host if status else None,
            "zenoh_id": status.zenoh_id if status else None,
            "state": str(status.state) if status else None,
            "crc": status.crc if status else None,
            "project": status.project if status else None,
            "cycle_ms": status.cycle_ms if status else None,
            "mean_ms": status.stats.mean_ms if status else None,
            "status": encode(status) if status else None,
        }


class _Statuses:
    """The newest signed status of each resource whose key is known, as they arrive."""

    def __init__(self) -> None:
        self._lock = threading.Condition()
        self._keys: dict[str, str] = {}
        self._taken: dict[str, Status] = {}
        self._forged: set[str] = set()  # a status came that its known key does not sign
        self._freshness = signatures.Freshness()

    def expect(self, name: str, key: str) -> None:
        with self._lock:
            self._keys[name] = key

    def on_sample(self, sample: zenoh.Sample) -> None:
        name, payload = resource_of(str(sample.key_expr)), sample.payload.to_bytes()
        signed = sample.attachment.to_bytes() if sample.attachment is not None else None
        with self._lock:
            key = self._keys.get(name)
        if key is None:
            return
        stamp = signatures.verified_stamp(key, payload, signed)
        if stamp is None:
            with self._lock:
                self._forged.add(name)
            return
        if not self._freshness.newer(name, stamp):
            return  # a replay
        try:
            status = decode_publication(Status, payload)
        except Refusal:
            return
        with self._lock:
            self._taken[name] = status
            self._lock.notify_all()

    def wait(self, deadline: float) -> None:
        """Until every expected resource's status came, or the deadline."""
        with self._lock:
            while self._keys.keys() - self._taken.keys():
                left = deadline - time.monotonic()
                if left <= 0:
                    return
                self._lock.wait(left)

    def entry(self, name: str, wait_s: float) -> FleetEntry:
        with self._lock:
            status = self._taken.get(name)
            if status is not None:
                return FleetEntry(name, status)
            if name not in self._keys:
                return FleetEntry(name, None, NOT_VERIFIED)
            if name in self._forged:
                return FleetEntry(
                    name, None, "not verified: its statuses are not signed by its known key"
                )
            return FleetEntry(name, None, f"no signed status within {wait_s:g} s")


def online_resources(session: zenoh.Session, timeout_s: float = LIVELINESS_WAIT_S) -> list[str]:
    """The resources whose liveliness token is there now, sorted by name."""
    names: set[str] = set()
    for reply in session.liveliness().get(any_resource(alive_key), timeout=timeout_s):
        if reply.ok is not None:
            names.add(resource_of(str(reply.ok.key_expr)))
    return sorted(names)


def survey(
    session: zenoh.Session,
    known: KnownResources | None = None,
    login: Callable[[ResourceClient], None] | None = None,
    wait_s: float = STATUS_WAIT_S,
) -> list[FleetEntry]:
    """Every resource online (sorted by name) with its status when it is signed with its
    known key. `login`: log in to each resource whose key is not known yet (which proves
    and pins it); a refused login is that resource's note."""
    known = known if known is not None else KnownResources()
    statuses = _Statuses()
    subscriber = session.declare_subscriber(any_resource(status_key), statuses.on_sample)
    try:
        names = online_resources(session)
        notes: dict[str, str] = {}
        for name in names:
            key = known.key_of(name)
            if key is None and login is not None:
                client = ResourceClient(session, name, known)
                try:
                    login(client)
                except Refusal as refused:
                    why = f"login refused ({refused.code}): {refused.message}"
                    notes[name] = f"{NOT_VERIFIED}: {why}"
                except ResourceUnreachable as exc:
                    notes[name] = f"{NOT_VERIFIED}: {exc}"
                if client.logged_in is not None:
                    key = client.logged_in.publication_key
            if key is not None:
                statuses.expect(name, key)
        statuses.wait(time.monotonic() + wait_s)
        entries = [statuses.entry(name, wait_s) for name in names]
    finally:
        subscriber.undeclare()
    return [
        FleetEntry(e.resource, e.status, notes[e.resource])
        if e.status is None and e.resource in notes
        else e
        for e in entries
    ]


# ---- one project into several resources

R = TypeVar("R")  # a resource's result of a fleet command
Outcome = Literal["done", "refused", "not tried"]


@dataclass(frozen=True)
class FleetLoad:
    """What the fleet load did to one resource."""

    resource: str
    outcome: Outcome
    crc: str | None = None  # the configuration compiled for it
    state: str | None = None  # its state after the load
    code: str | None = None  # why refused: the refusal's code
    message: str | None = None
    backup: Path | None = None
    backup_error: str | None = None  # done, but its backup could not be written
    warnings: tuple[str, ...] = field(default=())
    diagnostics: tuple[str, ...] = field(default=())  # of a project that does not compile

    def as_json(self) -> dict[str, Any]:
        return {
            "resource": self.resource,
            "outcome": self.outcome,
            "crc": self.crc,
            "state": self.state,
            "code": self.code,
            "message": self.message,
            "backup": self.backup.name if self.backup is not None else None,
            "backup_error": self.backup_error,
            "warnings": list(self.warnings),
            "diagnostics": list(self.diagnostics),
        }


def fleet_refusal(targets: Sequence[str]) -> Refusal | None:
    """Why a list of resources cannot be a fleet load's, or None."""
    if not targets:
        return Refusal("bad_request", "name at least one resource")
    seen: set[str] = set()
    for name in targets:
        problem = resource_name_problem(name)
        if problem is not None:
            return Refusal("bad_request", problem)
        if name in seen:
            return Refusal("bad_request", f"resource {name} is named twice")
        seen.add(name)
    return None


def download_fleet(
    paths: Sequence[Path],
    targets: Sequence[str],
    client_of: Callable[[str], ResourceClient],
    backups: Path,
    how: str,
    told: Callable[[FleetLoad], None] | None = None,
) -> list[FleetLoad]:
    """Load the project of `paths` into each resource of `targets` in turn, each compiled
    for it; stop at the first that is not done in full. `client_of(name)` is a client of
    that resource as the caller may use it (logged in); its Refusal or ResourceUnreachable
    is that resource's refusal. `told` hears each resource's outcome as soon as it is
    known. Raises ProjectError when the project cannot be read (before anything is
    sent), Refusal for a list of resources that is not one (`fleet_refusal`)."""
    wrong = fleet_refusal(targets)
    if wrong is not None:
        raise wrong
    load_project(list(paths))  # an unreadable project: nothing tried, nothing sent
    return _in_turn(
        targets,
        lambda name: _load_one(paths, name, client_of, backups, how),
        lambda name: FleetLoad(name, "not tried"),
        lambda result: not fleet_done([result]),
        told,
    )


def _in_turn(
    targets: Sequence[str],
    attempt: Callable[[str], R],
    not_tried: Callable[[str], R],
    ends: Callable[[R], bool],
    told: Callable[[R], None] | None,
) -> list[R]:
    """Each target's result, attempted in turn; once one `ends` the run, the rest are
    `not_tried`. `told` hears each result as soon as it is known."""
    results: list[R] = []
    stopped = False
    for name in targets:
        result = not_tried(name) if stopped else attempt(name)
        stopped = stopped or ends(result)
        results.append(result)
        if told is not None:
            told(result)
    return results


def _load_one(
    paths: Sequence[Path],
    name: str,
    client_of: Callable[[str], ResourceClient],
    backups: Path,
    how: str,
) -> FleetLoad:
    crc = None
    try:
        checked = compile_checked(paths, name)
        crc = checked.artifact.crc
        done = download_checked(client_of(name), checked, backups, f"{how} (resource {name})")
    except Refusal as refused:
        diagnostics = tuple(str(d) for d in refused.details.get("diagnostics", ()))
        return FleetLoad(
            name, "refused", crc, code=refused.code, message=refused.message,
            diagnostics=diagnostics,
        )  # fmt: skip
    except ProjectError as exc:  # the project changed meanwhile and can no longer be read
        return FleetLoad(name, "refused", crc, code="project", message=str(exc))
    except ResourceUnreachable as exc:
        return FleetLoad(name, "refused", crc, code="unreachable", message=str(exc))
    return FleetLoad(
        name,
        "done",
        done.status.crc,
        str(done.status.state),
        backup=done.backup.path,
        backup_error=done.backup.error,
        warnings=done.warnings,
    )


def fleet_done(results: Sequence[FleetLoad]) -> bool:
    return all(r.outcome == "done" and r.backup_error is None for r in results)


# ---- one online change of several resources

ReloadOutcome = Literal["done", "refused", "not tried", "previewed"]


@dataclass(frozen=True)
class FleetReload:
    """What the fleet reload did to one resource: `previewed` (a preview only: `preview`
    says whether the plan is possible), `done`, `refused` or `not tried`."""

    resource: str
    outcome: ReloadOutcome
    preview: OnlineChangePreview | None = None  # its plan, when the resource gave one
    code: str | None = None  # why refused: the refusal's code
    message: str | None = None
    old_crc: str | None = None  # done: the configuration it ran, and runs now
    new_crc: str | None = None
    pause_us: float | None = None
    carried: int | None = None
    state: str | None = None  # its state after the reload
    backup: Path | None = None
    backup_error: str | None = None  # done, but its backup could not be written
    kept_online: tuple[str, ...] = field(default=())
    not_kept_online: tuple[str, ...] = field(default=())  # done, these not set again
    diagnostics: tuple[str, ...] = field(default=())  # of a project that does not compile

    @property
    def complete(self) -> bool:
        """Done in full: reloaded, backed up, every kept online value set again."""
        return self.outcome == "done" and self.backup_error is None and not self.not_kept_online

    @property
    def possible(self) -> bool:
        """A plan came, and it can be made online."""
        return self.preview is not None and self.preview.possible

    def as_json(self) -> dict[str, Any]:
        preview = self.preview
        plan: dict[str, Any] = {
            "possible": False,
            "plan": None,
            "risks": [],
            "why_not_online": [],
            "parameter_resets": [],
            "running_sources": None,
        }
        if preview is not None:
            plan = {
                "possible": preview.possible,
                "plan": encode(preview.plan),
                "risks": needs_confirmation(preview.plan),
                "why_not_online": list(preview.why_not),
                "parameter_resets": [dataclasses.asdict(reset) for reset in preview.resets],
                "running_sources": preview.running_from or None,
            }
        return {
            "resource": self.resource,
            "outcome": self.outcome,
            "code": self.code,
            "message": self.message,
            **plan,
            "old_crc": self.old_crc,
            "new_crc": self.new_crc,
            "pause_us": self.pause_us,
            "carried": self.carried,
            "state": self.state,
            "backup": self.backup.name if self.backup is not None else None,
            "backup_error": self.backup_error,
            "kept_online": list(self.kept_online),
            "not_kept_online": list(self.not_kept_online),
            "diagnostics": list(self.diagnostics),
        }


def keep_online_refusal(names: Sequence[str]) -> Refusal | None:
    """Why names to keep online are not: each must be a resource parameter that changes
    online (which ones a reload resets differs from resource to resource)."""
    for name in names:
        spec = RESOURCE_BY_NAME.get(name)
        if spec is None or not spec.online:
            return Refusal("bad_request", f"{name[:64]} is no resource parameter set online")
    return None


def reload_fleet(
    paths: Sequence[Path],
    targets: Sequence[str],
    client_of: Callable[[str], ResourceClient],
    backups: Path,
    how: str,
    *,
    confirmed: bool,
    renames: Mapping[str, str] | None = None,
    keep_online: Sequence[str] = (),
    expected: Mapping[str, str] | None = None,
    projects: Mapping[str, Path] | None = None,
    told: Callable[[FleetReload], None] | None = None,
) -> list[FleetReload]:
    """The online change of the project of `paths` in each resource of `targets`, each
    compiled for it. Not `confirmed`: every resource's plan, nothing changed (`previewed`,
    or `refused` when no plan came). `confirmed`: each previewed and reloaded in turn,
    stopping at the first that is not done in full (`FleetReload.complete`); a plan that
    needs STOP and a download is refused `needs_download` without a reload being tried.

    `renames` NEW -> OLD, the same for each; `keep_online` the parameters whose online
    value is set again after the switch-over where the reload resets them; `expected`
    each resource's configuration CRC of the plan its caller confirmed (the reload is
    refused `changed` when it runs another by now), else the CRC of the plan just made.
    `client_of`, `backups`, `how`, `told` and what is raised before anything is sent are
    as for `download_fleet`, and names to keep that are no online parameters, or
    `expected` not naming each resource, are refused too."""
    wrong = fleet_refusal(targets) or keep_online_refusal(keep_online)
    if wrong is None and expected is not None and set(expected) != set(targets):
        wrong = Refusal("bad_request", "give the expected CRC of each resource, and only them")
    if wrong is not None:
        raise wrong
    load_project(list(paths))  # an unreadable project: nothing tried, nothing sent
    return _in_turn(
        targets,
        lambda name: _reload_one(
            paths,
            name,
            client_of,
            backups,
            how,
            confirmed,
            dict(renames or {}),
            keep_online,
            (expected or {}).get(name),
            projects or {},
        ),
        lambda name: FleetReload(name, "not tried"),
        lambda result: confirmed and not result.complete,
        told,
    )


def _reload_one(
    paths: Sequence[Path],
    name: str,
    client_of: Callable[[str], ResourceClient],
    backups: Path,
    how: str,
    confirmed: bool,
    renames: dict[str, str],
    keep_online: Sequence[str],
    expected: str | None,
    projects: Mapping[str, Path],
) -> FleetReload:
    preview = None
    try:
        checked = compile_checked(paths, name)
        client = client_of(name)
        preview = preview_online_change(
            client, checked, checked.project.name, renames, backups, projects
        )
        plan = preview.plan
        if not confirmed:
            return FleetReload(name, "previewed", preview)
        if plan.refusals:
            raise Refusal("needs_download", "needs STOP and download: " + "; ".join(plan.refusals))
        options = ReloadOptions(renames, expected or plan.old_crc)
        keep = [reset for reset in preview.resets if reset.name in keep_online]
        changed = online_change(client, checked, options, keep, backups, f"{how} (resource {name})")
    except Refusal as refused:
        diagnostics = tuple(str(d) for d in refused.details.get("diagnostics", ()))
        return FleetReload(
            name, "refused", preview, refused.code, refused.message, diagnostics=diagnostics
        )
    except ProjectError as exc:  # the project changed meanwhile and can no longer be read
        return FleetReload(name, "refused", preview, "project", str(exc))
    except ResourceUnreachable as exc:
        return FleetReload(name, "refused", preview, "unreachable", str(exc))
    done = changed.reloaded
    outcome = done.reply.reload
    return FleetReload(
        name,
        "done",
        preview,
        old_crc=outcome.old_crc,
        new_crc=outcome.new_crc,
        pause_us=outcome.pause_us,
        carried=outcome.carried,
        state=str(done.reply.status.state),
        backup=done.backup.path,
        backup_error=done.backup.error,
        kept_online=changed.kept,
        not_kept_online=changed.not_kept,
    )


def reload_fleet_done(results: Sequence[FleetReload]) -> bool:
    return all(result.complete for result in results)


def fleet_confirmation(results: Sequence[FleetReload]) -> str:
    """What a confirmation of the previewed fleet reload accepts, resource by resource:
    `LineA: 1 value initialised; LineB: needs STOP and download` ("" when nothing)."""
    said = []
    for result in results:
        if result.preview is None:
            continue
        if result.preview.plan.refusals:
            said.append(f"{result.resource}: needs STOP and download")
            continue
        risks = needs_confirmation(result.preview.plan)
        if risks:
            said.append(f"{result.resource}: {', '.join(risks)}")
    return "; ".join(said)
