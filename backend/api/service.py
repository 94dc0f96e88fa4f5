"""What the API acts on, behind its routes: the PADT accounts, the resources online, the
projects it serves, and where backups go. One instance per API server; the request
threads share it. Every operation is the engineering services' (backend/engineering); this
adds only who the caller is and which PES session it holds for each resource."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any, TypeVar

from backend.engineering.check_twice import check_twice
from backend.engineering.compile_gate import compile_checked
from backend.engineering.documentation.export import (
    Document,
    DocumentError,
    document,
    version_path,
)
from backend.engineering.download import (
    Downloaded,
    DownloadPlan,
    download_checked,
    plan_download,
)
from backend.engineering.fleet import FleetLoad, FleetReload, download_fleet, reload_fleet
from backend.engineering.online_change import (
    OnlineChanged,
    OnlineChangePreview,
    chosen_resets,
    online_change,
    preview_online_change,
)
from backend.engineering.padt_accounts import PadtAccounts
from backend.engineering.project import ProjectError, compile_project, load_project
from backend.engineering.project_shelf import ProjectShelf
from backend.engineering.reload import ReloadOptions
from backend.engineering.resource_client import (
    ResourceClient,
    ResourceLogin,
    ResourceUnreachable,
)
from backend.engineering.resource_directory import ResourceDirectory
from backend.engineering.testing.project_tests import UnitTestChoice, UnitTestRuns
from runtime.contract.protocol import Command, GetParameters, GetStatus, Logout
from runtime.contract.refusal import Refusal

R = TypeVar("R")
Fleet = TypeVar("Fleet", FleetLoad, FleetReload)  # what a fleet operation did to a resource


@dataclass(frozen=True)
class Caller:
    """Who sends a request: the API session's token and its account."""

    token: str
    user: str
    level: str


class PadtService:
    def __init__(
        self,
        directory: ResourceDirectory,
        accounts: PadtAccounts,
        projects: Mapping[str, Path],
        backup_dir: Path,
        test_runs: UnitTestRuns | None = None,
    ) -> None:
        self.accounts = accounts
        # a plain mapping is a shelf with no folder for new projects and no audit log
        self.shelf = projects if isinstance(projects, ProjectShelf) else ProjectShelf(projects)
        self.projects: Mapping[str, Path] = self.shelf
        self.backup_dir = backup_dir
        self.directory = directory
        self.test_runs = test_runs or UnitTestRuns()  # this server's: a bound on runs at once

    def close(self) -> None:
        self.directory.close()

    def caller(self, token: str | None, needed: str) -> Caller:
        """Who holds `token`, if the session exists and its level is at least `needed`."""
        session = self.accounts.check(token, needed)
        assert token is not None  # a session exists only for a token
        return Caller(token, session.user, session.level)

    # ---- projects

    def project_path(self, name: str) -> Path:
        return self.shelf.folder(name)

    def compile(self, name: str) -> dict[str, Any]:
        with _project_errors():
            result = compile_project(load_project([self.project_path(name)]))
        return result.as_json()

    def check_twice(self, name: str) -> dict[str, Any]:
        result = check_twice([self.project_path(name)])
        return {
            "ok": result.ok,
            "compiled": result.compiled,
            "mismatches": list(result.mismatches),
            "runs": [dataclasses.asdict(run) for run in (result.first, result.second)],
        }

    def run_tests(self, name: str, choice: UnitTestChoice) -> dict[str, Any]:
        """The report of the project's unit tests (all, a suite's or one), run in a
        process of their own while the request's thread waits."""
        return self.test_runs.run(self.project_path(name), choice)

    def documentation(self, name: str, compare: str | None) -> Document:
        """The document of a project served, compared with another project served or a
        backup in the backup folder (by file name)."""
        try:
            previous = None
            if compare is not None:
                previous = version_path(compare, self.projects, self.backup_dir)
            return document([self.project_path(name)], previous)
        except DocumentError as exc:
            raise Refusal("project", str(exc)) from None

    # ---- resources

    def client(self, caller: Caller, resource: str) -> ResourceClient:
        client = self.directory.client(resource)
        client.logged_in = self.accounts.resource_login(caller.token, resource)
        return client

    def ask(self, caller: Caller, resource: str, command: Command[R]) -> R:
        """A command to the resource with the caller's PES session: its checked reply, or
        its refusal."""
        with self._refusals(caller, resource):
            return self.client(caller, resource).ask(command)

    def act(self, caller: Caller, resource: str, operation: Callable[[ResourceClient], R]) -> R:
        """An operation of a service on the resource (several commands, as a download) with
        the caller's PES session: its result, or its refusal."""
        with self._refusals(caller, resource):
            return operation(self.client(caller, resource))

    def log_in(self, caller: Caller, resource: str, user: str, password: str) -> ResourceLogin:
        client = self.client(caller, resource)
        with self._refusals(caller, resource):
            login = client.login(user, password)
        self.accounts.set_resource_login(caller.token, resource, login)
        # what it proved: the resource's publications can be told from forgeries now
        self.directory.trust(resource, login.publication_key)
        return login

    def log_out(self, caller: Caller, resource: str) -> None:
        login = self.accounts.resource_login(caller.token, resource)
        if login is not None and self.directory.is_online(resource):
            try:
                with self._refusals(caller, resource):
                    self.client(caller, resource).ask(Logout())
            except Refusal as refused:
                if refused.code != "unauthenticated":  # a session already gone: logged out
                    raise
        self.accounts.set_resource_login(caller.token, resource, None)

    def load(self, caller: Caller, resource: str, project: str) -> Downloaded:
        path = self.project_path(project)
        with self._refusals(caller, resource):
            checked = compile_checked([path])
            how = f"REST API: load of project {project} by {caller.user}"
            return download_checked(self.client(caller, resource), checked, self.backup_dir, how)

    def load_fleet(self, caller: Caller, resources: list[str], project: str) -> list[FleetLoad]:
        """One project into several resources in turn, each compiled for it, up to the
        first refusal (`fleet.download_fleet`); the caller's PES session of each."""
        path = self.project_path(project)
        how = f"REST API: fleet load of project {project} by {caller.user}"

        with _project_errors():
            results = download_fleet(
                [path], resources, lambda name: self.client(caller, name), self.backup_dir, how
            )
        return [self._as_caller_reads(caller, result) for result in results]

    def reload_fleet(
        self,
        caller: Caller,
        resources: list[str],
        project: str,
        renames: dict[str, str],
        expected: dict[str, str] | None,
        keep_online: list[str],
    ) -> list[FleetReload]:
        """Each resource's reload plan of the project compiled for it (`expected` None: a
        preview, nothing changed); else each reloaded in turn, provided it still runs the
        configuration of `expected`, up to the first refusal (`fleet.reload_fleet`)."""
        path = self.project_path(project)
        how = f"REST API: fleet reload of project {project} by {caller.user}"
        with _project_errors():
            results = reload_fleet(
                [path],
                resources,
                lambda name: self.client(caller, name),
                self.backup_dir,
                how,
                confirmed=expected is not None,
                renames=renames,
                keep_online=keep_online,
                expected=expected,
                projects=self.projects,
            )
        return [self._as_caller_reads(caller, result) for result in results]

    def _as_caller_reads(self, caller: Caller, result: Fleet) -> Fleet:
        """A resource's `unauthenticated` as `resource_refusal` words it."""
        if result.code != "unauthenticated":
            return result
        refusal = Refusal(result.code, result.message or "")
        worded = self.resource_refusal(caller, result.resource, refusal)
        return dataclasses.replace(result, code=worded.code, message=worded.message)

    def preview_load(self, caller: Caller, resource: str, project: str) -> DownloadPlan:
        """What a download would do, or why it cannot be done now (the level on the
        resource is the resource's to check)."""
        path = self.project_path(project)
        with self._refusals(caller, resource):
            checked = compile_checked([path])
            client = self.client(caller, resource)
            status = client.ask(GetStatus()).status
            parameters = client.ask(GetParameters()).resource if status.crc else None
            return plan_download(checked, status, parameters)

    def preview_reload(
        self, caller: Caller, resource: str, project: str, renames: dict[str, str]
    ) -> OnlineChangePreview:
        """The plan with the source diff, the parameter resets and why not online."""
        path = self.project_path(project)
        with self._refusals(caller, resource):
            checked = compile_checked([path])
            client = self.client(caller, resource)
            return preview_online_change(
                client, checked, project, renames, self.backup_dir, self.projects
            )

    def reload(
        self,
        caller: Caller,
        resource: str,
        project: str,
        options: ReloadOptions,
        keep_online: list[str],
    ) -> OnlineChanged:
        path = self.project_path(project)
        with self._refusals(caller, resource):
            checked = compile_checked([path])
            how = f"REST API: reload of project {project} by {caller.user}"
            client = self.client(caller, resource)
            keep = chosen_resets(client, checked, keep_online)
            return online_change(client, checked, options, keep, self.backup_dir, how)

    @contextmanager
    def _refusals(self, caller: Caller, resource: str) -> Iterator[None]:
        """Failures of the layers below as refusals. A resource that no longer knows the
        caller's PES session (expired, or the runtime restarted) drops it here too."""
        try:
            with _project_errors():
                yield
        except ResourceUnreachable as exc:
            raise Refusal("unreachable", str(exc)) from None
        except Refusal as refusal:
            raise self.resource_refusal(caller, resource, refusal) from None

    def resource_refusal(self, caller: Caller, resource: str, refusal: Refusal) -> Refusal:
        """A resource's refusal as the caller should read it. `unauthenticated` means that
        the caller has no login to the resource yet (`resource_login_required`: its API
        session is fine), or that the resource no longer knows the one it had."""
        if refusal.code != "unauthenticated":
            return refusal
        login = f"POST /api/resources/{resource}/login"
        if self.accounts.resource_login(caller.token, resource) is None:
            return Refusal(
                "resource_login_required", f"log in to resource {resource} first: {login}"
            )
        self.accounts.set_resource_login(caller.token, resource, None)
        refusal.message += f" (the resource no longer knows this login; log in again: {login})"
        return refusal


@contextmanager
def _project_errors() -> Iterator[None]:
    try:
        yield
    except ProjectError as exc:
        raise Refusal("project", str(exc)) from None
