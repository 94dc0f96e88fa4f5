"""The projects the API serves (folders given to `padt api --project`, and those of
`--projects-dir`): compile, the compile-twice check, the unit tests and the printable
documentation (these write nothing; they still need Read+Write, because they cost the server
real work); and editing: new projects from templates, files read and saved with conflicts,
POUs added, renamed and deleted, padt.toml's settings checked and written."""

from __future__ import annotations

from typing import Annotated, Any, Literal

from fastapi import APIRouter, Query, Response
from fastapi import Path as PathParameter
from pydantic import BaseModel, Field

from backend.api.auth import ReadOnly, ReadWrite, Service
from backend.api.service import Caller
from backend.engineering.padt_audit_log import AuditEntry
from backend.engineering.project_access import Editor
from backend.engineering.project_edits import (
    add_declaration,
    delete_declaration,
    rename_declaration,
)
from backend.engineering.project_files import (
    DiskState,
    FileText,
    ProjectFile,
    Saved,
    changed_on_disk,
    delete_file,
    history,
    list_files,
    read_file,
    save_file,
)
from backend.engineering.project_settings import (
    Problem,
    Settings,
    SettingsFile,
    read_settings,
    settings_problems,
    write_settings,
)
from backend.engineering.project_shelf import templates
from backend.engineering.project_tree import ProjectTree, project_tree
from backend.engineering.testing.project_tests import UnitTestChoice

router = APIRouter(prefix="/api/projects", tags=["projects"])


@router.get("", summary="The projects served")
def projects(caller: ReadOnly, service: Service) -> list[dict[str, str]]:
    service.shelf.refresh()  # projects another tool put in the folder for projects
    return [{"name": name} for name in service.projects]


@router.post("/{project}/compile", summary="Compile: diagnostics and CRCs")
def compile_project(project: str, caller: ReadWrite, service: Service) -> dict[str, Any]:
    return service.compile(project)


@router.post("/{project}/check-twice", summary="Compile in two processes and compare CRCs")
def check_twice(project: str, caller: ReadWrite, service: Service) -> dict[str, Any]:
    return service.check_twice(project)


class UnitTestRun(BaseModel):
    """Which unit tests to run: all (no suite), a suite's, or one (suite and test)."""

    suite: str | None = Field(default=None, max_length=64, description="a test suite (an FB)")
    test: str | None = Field(default=None, max_length=64, description="a test of the suite")
    tier: Literal["both", "python", "native"] = "both"
    coverage: bool = Field(default=False, description="measure the lines run (Python tier)")


@router.post(
    "/{project}/tests",
    summary="Run the project's unit tests (all, a suite or one test): the report",
)
def run_tests(
    project: str, caller: ReadWrite, service: Service, body: UnitTestRun | None = None
) -> dict[str, Any]:
    chosen = body or UnitTestRun()
    choice = UnitTestChoice(chosen.suite, chosen.test, chosen.tier, chosen.coverage)
    return service.run_tests(project, choice)


@router.get(
    "/{project}/documentation",
    summary="Printable documentation (PDF or HTML), optionally compared with a version",
    response_class=Response,
    responses={200: {"content": {"application/pdf": {}, "text/html": {}}}},
)
def documentation(
    project: str,
    caller: ReadWrite,
    service: Service,
    format: Literal["pdf", "html"] = "pdf",
    compare: Annotated[
        str | None, Query(max_length=256, description="a project served, or a backup file name")
    ] = None,
) -> Response:
    made = service.documentation(project, compare)
    if format == "html":
        body, media = made.html.encode("utf-8"), "text/html; charset=utf-8"
    else:
        body, media = made.pdf, "application/pdf"
    disposition = f'attachment; filename="{made.name}.{format}"'
    return Response(body, media_type=media, headers={"Content-Disposition": disposition})


# ---- editing: the files of a project, its declarations, its settings, new projects.
# Each route is one call of a project service (backend/engineering/project_*.py), which
# checks the caller's level itself; a refusal comes back as `{"error": ...}` (a conflict
# with `current_hash`, settings with `problems`).


def editor(caller: Caller) -> Editor:
    return Editor(caller.user, caller.level)


FilePath = Annotated[str, PathParameter(max_length=512, description="relative, with /")]
Hash = Annotated[str, Query(max_length=64, pattern="^[0-9a-f]{0,64}$")]


class NewProject(BaseModel):
    name: str = Field(max_length=64)
    template: str = Field(max_length=32, description="empty, tank or sequence")
    resource: str | None = Field(default=None, max_length=64, description="the resource's name")


class FileSave(BaseModel):
    text: str
    base_hash: str | None = Field(
        default=None,
        max_length=64,
        description="the hash of the text the edit started from; none for a new file",
    )


class NewDeclaration(BaseModel):
    kind: Literal["PROGRAM", "FUNCTION_BLOCK", "FUNCTION", "STRUCT", "ENUM", "GLOBALS"]
    name: str = Field(max_length=64)
    return_type: str = Field(default="", max_length=64, description="of a FUNCTION")
    folder: str = Field(default="", max_length=256, description="a sub-folder for the file")


class Rename(BaseModel):
    new_name: str = Field(max_length=64)


class SettingsWrite(BaseModel):
    settings: Settings
    base_hash: str = Field(max_length=64)


@router.get("/templates", summary="The templates a new project starts from")
def project_templates(caller: ReadOnly) -> list[dict[str, str]]:
    return [{"name": t.name, "title": t.title} for t in templates()]


@router.post("", status_code=201, summary="A new project from a template")
def new_project(body: NewProject, caller: ReadWrite, service: Service) -> dict[str, str]:
    service.shelf.new_project(body.name, body.template, editor(caller), body.resource)
    return {"name": body.name}


@router.get("/{project}/tree", summary="The project tree: POUs, types, globals, resource")
def tree(project: str, caller: ReadOnly, service: Service) -> ProjectTree:
    return project_tree(service.shelf, project, editor(caller))


@router.get("/{project}/files", summary="The editable files: padt.toml and the .st files")
def files(project: str, caller: ReadOnly, service: Service) -> list[ProjectFile]:
    return list_files(service.shelf, project, editor(caller))


@router.get("/{project}/files/{path:path}", summary="A file's text and hash")
def get_file(project: str, path: FilePath, caller: ReadOnly, service: Service) -> FileText:
    return read_file(service.shelf, project, path, editor(caller))


@router.put(
    "/{project}/files/{path:path}",
    summary="Save a file against the hash it was opened with (409 conflict when changed)",
)
def put_file(
    project: str, path: FilePath, body: FileSave, caller: ReadWrite, service: Service
) -> Saved:
    return save_file(service.shelf, project, path, body.text, body.base_hash, editor(caller))


@router.delete("/{project}/files/{path:path}", summary="Delete a .st file still as opened")
def delete_project_file(
    project: str, path: FilePath, base_hash: Hash, caller: ReadWrite, service: Service
) -> Saved:
    return delete_file(service.shelf, project, path, base_hash, editor(caller))


@router.get("/{project}/changed", summary="Whether a file differs from the hash an editor has")
def changed(
    project: str,
    path: Annotated[str, Query(max_length=512)],
    known_hash: Hash,
    caller: ReadOnly,
    service: Service,
) -> DiskState:
    return changed_on_disk(service.shelf, project, path, known_hash, editor(caller))


@router.get("/{project}/history", summary="Who changed which file: the audit log's entries")
def file_history(
    project: str,
    caller: ReadOnly,
    service: Service,
    file: Annotated[str | None, Query(max_length=512)] = None,
    limit: Annotated[int, Query(ge=1, le=10_000)] = 200,
) -> list[AuditEntry]:
    return history(service.shelf, project, editor(caller), file, limit)


@router.post(
    "/{project}/declarations",
    status_code=201,
    summary="Add a POU, type or global list as a new file",
)
def add(project: str, body: NewDeclaration, caller: ReadWrite, service: Service) -> Saved:
    return add_declaration(
        service.shelf, project, body.kind, body.name, editor(caller), body.return_type, body.folder
    )


@router.post(
    "/{project}/declarations/{name}/rename",
    summary="Rename a POU, type or global list (declaration, file, program instances)",
)
def rename(
    project: str, name: str, body: Rename, caller: ReadWrite, service: Service
) -> list[Saved]:
    return rename_declaration(service.shelf, project, name, body.new_name, editor(caller))


@router.delete(
    "/{project}/declarations/{name}",
    summary="Delete a POU, type or global list (refused while the resource runs it)",
)
def delete(project: str, name: str, caller: ReadWrite, service: Service) -> Saved:
    return delete_declaration(service.shelf, project, name, editor(caller))


@router.get("/{project}/settings", summary="padt.toml's settings and its hash")
def get_settings(project: str, caller: ReadOnly, service: Service) -> SettingsFile:
    return read_settings(service.shelf, project, editor(caller))


@router.post("/{project}/settings/check", summary="The problems of a draft, by field")
def check_settings(
    project: str, draft: Settings, caller: ReadOnly, service: Service
) -> list[Problem]:
    return settings_problems(service.shelf, project, draft, editor(caller))


@router.put("/{project}/settings", summary="Write padt.toml's settings (comments kept)")
def put_settings(project: str, body: SettingsWrite, caller: ReadWrite, service: Service) -> Saved:
    return write_settings(service.shelf, project, body.settings, body.base_hash, editor(caller))
