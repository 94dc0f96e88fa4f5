"""The projects the API serves (folders given to `padt api --project`): compile and the
compile-twice check. Compiling writes nothing; it still needs Read+Write, because it costs
the server real work."""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter

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
