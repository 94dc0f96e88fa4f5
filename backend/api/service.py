"""What the API acts on, behind its routes: the PADT accounts, the resources online, the
projects it serves, and where backups go. One instance per API server; the request
threads share it."""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import zenoh

from backend.api.accounts import PadtAccounts
from backend.api.errors import ApiError
from backend.engineering.backup import BackupError
from backend.engineering.check_twice import check_twice
from backend.engineering.loading import (
    CheckedCompile,
    CompileFailed,
    LoadRefused,
    backup_of,
    checked_reply,
    compile_checked,
    download,
    needs_confirmation,
    preview_reload,
    reload,
)
from backend.engineering.project import ProjectError, compile_project, load_project
from backend.engineering.resource_client import ResourceClient, ResourceUnreachable
from backend.engineering.resource_directory import ResourceDirectory
from runtime.access import AccessDenied


@dataclass(frozen=True)
class Caller:
    """Who sends a request: the API session's token and its account."""

    token: str
    user: str
    level: str


@dataclass(frozen=True)
class ReloadOptions:
    renames: dict[str, str]  # NEW name -> OLD name, as the runtime's rename map has it
    expected_crc: str | None = None
    watchdog_ms: int | None = None
    target_cycle_ms: int | None = None


class PadtService:
    def __init__(
        self,
        session: zenoh.Session,
        accounts: PadtAccounts,
        projects: dict[str, Path],
        backup_dir: Path,
    ) -> None:
        self.session = session
        self.accounts = accounts
        self.projects = dict(sorted(projects.items()))
        self.backup_dir = backup_dir
        self.directory = ResourceDirectory(session)

    def close(self) -> None:
        self.directory.close()

    def caller(self, token: str | None, needed: str) -> Caller:
        """Who holds `token`, if the session exists and its level is at least `needed`."""
        try:
            session = self.accounts.check(token, needed)
        except AccessDenied as denied:
            raise ApiError(denied.code, denied.message) from None
        assert token is not None  # a session exists only for a token
        return Caller(token, session.user, session.level)

    # ---- projects

    def project_path(self, name: str) -> Path:
        if name not in self.projects:
            raise ApiError("unknown_project", f"there is no project '{name}'")
        return self.projects[name]

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

    # ---- resources

    def client(self, caller: Caller, resource: str) -> ResourceClient:
        if not self.directory.is_online(resource):
            raise ApiError("unknown_resource", f"no resource '{resource}' is online")
        client = ResourceClient(self.session, resource)
        client.token = self.accounts.resource_token(caller.token, resource)
        return client

    def command(self, caller: Caller, resource: str, cmd: str, /, **args: Any) -> dict[str, Any]:
        """A command to the resource with the caller's PES session; the reply without
        `ok`, or the resource's refusal as ApiError."""
        with self._refusals(caller, resource):
            reply = checked_reply(self.client(caller, resource).command(cmd, **args))
        return {key: value for key, value in reply.items() if key not in ("ok", "token")}

    def log_in(self, caller: Caller, resource: str, user: str, password: str) -> dict[str, Any]:
        client = self.client(caller, resource)
        with self._refusals(caller, resource):
            reply = checked_reply(client.login(user, password))
        self.accounts.set_resource_token(caller.token, resource, client.token)
        return {"resource": resource, "user": reply["user"], "level": reply["level"]}

    def log_out(self, caller: Caller, resource: str) -> None:
        token = self.accounts.resource_token(caller.token, resource)
        self.accounts.set_resource_token(caller.token, resource, None)
        if token is not None and self.directory.is_online(resource):
            with self._refusals(caller, resource):
                self.client(caller, resource).command("logout", token=token)

    def load(self, caller: Caller, resource: str, project: str) -> dict[str, Any]:
        path = self.project_path(project)
        with self._refusals(caller, resource):
            checked = compile_checked([path])
            reply = download(self.client(caller, resource), checked.artifact)
        outcome = {"status": reply["status"], "warnings": list(checked.diagnostics)}
        return outcome | self._backup(caller, resource, checked, "load", project)

    def preview_reload(
        self, caller: Caller, resource: str, project: str, renames: dict[str, str]
    ) -> dict[str, Any]:
        path = self.project_path(project)
        with self._refusals(caller, resource):
            checked = compile_checked([path])
            plan = preview_reload(self.client(caller, resource), checked.artifact, renames)
        return {"plan": plan, "risks": needs_confirmation(plan)}

    def reload(
        self, caller: Caller, resource: str, project: str, options: ReloadOptions
    ) -> dict[str, Any]:
        path = self.project_path(project)
        with self._refusals(caller, resource):
            checked = compile_checked([path])
            reply = reload(
                self.client(caller, resource),
                checked.artifact,
                options.renames,
                watchdog_ms=options.watchdog_ms,
                target_cycle_ms=options.target_cycle_ms,
                expected_crc=options.expected_crc,
            )
        outcome = {"reload": reply["reload"], "status": reply["status"]}
        return outcome | self._backup(caller, resource, checked, "reload", project)

    def _backup(
        self, caller: Caller, resource: str, checked: CheckedCompile, action: str, project: str
    ) -> dict[str, Any]:
        how = f"REST API: {action} of project {project} by {caller.user}"
        try:
            path = backup_of(checked, self.backup_dir, resource, action, how)
        except BackupError as exc:
            # the resource has the configuration already; only the record of it is missing
            return {"backup": None, "backup_error": str(exc)}
        return {"backup": path.name}

    @contextmanager
    def _refusals(self, caller: Caller, resource: str) -> Iterator[None]:
        """Failures of the layers below (a resource's refusal comes as LoadRefused from
        checked_reply) as ApiErrors. A resource that no longer knows the
        caller's PES session (expired, or the runtime restarted) drops it here too."""
        try:
            with _project_errors():
                yield
        except CompileFailed as exc:
            raise ApiError("compile", exc.message, diagnostics=list(exc.diagnostics)) from None
        except LoadRefused as exc:
            raise self._unauthenticated(caller, resource, ApiError(exc.code, exc.message)) from None
        except ResourceUnreachable as exc:
            raise ApiError("unreachable", str(exc)) from None
        except ApiError as exc:
            raise self._unauthenticated(caller, resource, exc) from None

    def _unauthenticated(self, caller: Caller, resource: str, error: ApiError) -> ApiError:
        if error.code == "unauthenticated":
            self.accounts.set_resource_token(caller.token, resource, None)
            error.message += f" (log in to the resource: POST /api/resources/{resource}/login)"
        return error


@contextmanager
def _project_errors() -> Iterator[None]:
    try:
        yield
    except ProjectError as exc:
        raise ApiError("project", str(exc)) from None
