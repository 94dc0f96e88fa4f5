"""The language services over HTTP: what `padt lsp` offers an editor, for a client that
speaks REST (a script, a CI job, another editor's plug-in). Each request names a file of
a project served and may bring the file's text as the client has it (unsaved); nothing is
written. Lines and columns count from 1, in characters; a range ends before `end_col`."""

from __future__ import annotations

from collections.abc import Callable
from typing import Annotated, Any, TypeVar

from fastapi import APIRouter
from pydantic import BaseModel, Field

from backend.api.auth import ReadOnly, Service
from backend.engineering.language_service import (
    LanguageError,
    Location,
    OutlineSymbol,
    ProjectLanguage,
    ProjectUnreadable,
)
from runtime.contract.refusal import Refusal

router = APIRouter(prefix="/api/projects/{project}/language", tags=["language services"])

T = TypeVar("T")
# the body limit (1 MiB) bounds the text; this bounds the places a client may name
Place = Annotated[int, Field(ge=1, le=10_000_000)]
Json = dict[str, Any]


class FileText(BaseModel):
    file: str = Field(max_length=1024, description="the file's path in the project, with /")
    text: str | None = Field(
        default=None, description="the file's text as the client has it; none: as saved"
    )


class AtPlace(FileText):
    line: Place
    col: Place


class RenameAt(AtPlace):
    new_name: str = Field(max_length=128)


def _ask(
    service: Service, project: str, request: FileText, ask: Callable[[ProjectLanguage, str], T]
) -> T:
    """A service's answer on the project served, its file with the request's text."""
    try:
        language = ProjectLanguage(service.project_path(project))
    except ProjectUnreadable as exc:
        raise Refusal("project", str(exc)) from None
    try:
        name = language.checked_name(request.file)
        with language.with_text(name, request.text):
            return ask(language, name)
    except LanguageError as exc:
        raise Refusal("path", str(exc)) from None


def _range(found: tuple[int, int, int, int]) -> Json:
    line, col, end_line, end_col = found
    return {"line": line, "col": col, "end_line": end_line, "end_col": end_col}


def _location(found: Location) -> Json:
    return {"file": found.file, **_range(found.range)}


def _symbol(symbol: OutlineSymbol) -> Json:
    return {
        "name": symbol.name,
        "kind": symbol.kind,
        "detail": symbol.detail,
        "range": _range(symbol.range),
        "selection_range": _range(symbol.selection_range),
        "children": [_symbol(child) for child in symbol.children],
    }


@router.post("/diagnostics", summary="The diagnostics of a file, in order of position")
def diagnostics(project: str, request: FileText, caller: ReadOnly, service: Service) -> Json:
    def ask(language: ProjectLanguage, name: str) -> Json:
        found = language.diagnostics(name)
        return {
            "diagnostics": [{**d.as_json(), **_range(language.diagnostic_range(d))} for d in found]
        }

    return _ask(service, project, request, ask)


@router.post("/completion", summary="What may be written at a place, most relevant first")
def completion(project: str, request: AtPlace, caller: ReadOnly, service: Service) -> Json:
    def ask(language: ProjectLanguage, name: str) -> Json:
        found = language.complete(name, request.line, request.col)
        return {
            "items": [
                {
                    "label": item.label,
                    "kind": item.kind,
                    "detail": item.detail,
                    "insert_text": item.insert_text,
                    "snippet": item.snippet,
                    "documentation": item.documentation,
                }
                for item in found
            ]
        }

    return _ask(service, project, request, ask)


@router.post("/hover", summary="What the name at a place is")
def hover(project: str, request: AtPlace, caller: ReadOnly, service: Service) -> Json:
    def ask(language: ProjectLanguage, name: str) -> Json:
        found = language.hover(name, request.line, request.col)
        if found is None:
            return {"hover": None}
        declared = None if found.declared is None else _location(found.declared)
        return {
            "hover": {
                **_range(found.range),
                "kind": found.kind,
                "signature": found.signature,
                "owner": found.owner,
                "comment": found.comment,
                "declared": declared,
                "markdown": found.markdown,
            }
        }

    return _ask(service, project, request, ask)


@router.post("/definition", summary="Where the symbol at a place is declared")
def definition(project: str, request: AtPlace, caller: ReadOnly, service: Service) -> Json:
    def ask(language: ProjectLanguage, name: str) -> Json:
        found = language.definition(name, request.line, request.col)
        return {"location": None if found is None else _location(found)}

    return _ask(service, project, request, ask)


@router.post("/references", summary="Every place that names the symbol at a place")
def references(project: str, request: AtPlace, caller: ReadOnly, service: Service) -> Json:
    def ask(language: ProjectLanguage, name: str) -> Json:
        found = language.references(name, request.line, request.col)
        return {"locations": [_location(location) for location in found]}

    return _ask(service, project, request, ask)


@router.post(
    "/rename",
    summary="The edits that rename the symbol at a place, checked by the compiler (not written)",
)
def rename(project: str, request: RenameAt, caller: ReadOnly, service: Service) -> Json:
    def ask(language: ProjectLanguage, name: str) -> Json:
        found = language.rename(name, request.line, request.col, request.new_name)
        if found.refusal:
            raise Refusal("rename", found.refusal)
        return {
            "files": [
                {
                    "file": edits.file,
                    "edits": [
                        {**_range(edit.range), "new_text": edit.new_text} for edit in edits.edits
                    ],
                }
                for edits in found.files
            ]
        }

    return _ask(service, project, request, ask)


@router.post("/outline", summary="What a file declares, nested")
def outline(project: str, request: FileText, caller: ReadOnly, service: Service) -> Json:
    def ask(language: ProjectLanguage, name: str) -> Json:
        return {"symbols": [_symbol(symbol) for symbol in language.outline(name)]}

    return _ask(service, project, request, ask)
