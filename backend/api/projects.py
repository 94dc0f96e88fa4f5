"""The projects the API serves (folders given to `padt api --project`): compile, the
compile-twice check and the printable documentation. These write nothing; they still need
Read+Write, because they cost the server real work."""

from __future__ import annotations

from typing import Annotated, Any, Literal

from fastapi import APIRouter, Query, Response

from backend.api.auth import ReadOnly, ReadWrite, Service

router = APIRouter(prefix="/api/projects", tags=["projects"])


@router.get("", summary="The projects served")
def projects(caller: ReadOnly, service: Service) -> list[dict[str, str]]:
    return [{"name": name} for name in service.projects]


@router.post("/{project}/compile", summary="Compile: diagnostics and CRCs")
def compile_project(project: str, caller: ReadWrite, service: Service) -> dict[str, Any]:
    return service.compile(project)


@router.post("/{project}/check-twice", summary="Compile in two processes and compare CRCs")
def check_twice(project: str, caller: ReadWrite, service: Service) -> dict[str, Any]:
    return service.check_twice(project)


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
