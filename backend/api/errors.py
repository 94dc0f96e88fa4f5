"""Every error of the API is JSON of one shape, `{"error": {"code", "message"}}`, with an
HTTP status that says whose problem it is; never a traceback.

A resource's refusal keeps the resource's own code (docs/architecture.md lists them);
the PADT's refusals (compile, check-twice, accounts) use codes of their own.
"""

from __future__ import annotations

import logging
from typing import Any

from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse
from starlette.exceptions import HTTPException

from runtime.contract.refusal import Refusal

log = logging.getLogger("padt.api")

# the status for each refusal code; anything else is 409: the resource's state or
# configuration does not allow it now
HTTP_STATUS = {
    "unauthenticated": 401,
    "resource_login_required": 401,  # the API session is fine; the resource's is missing
    "login_failed": 401,
    "forbidden": 403,
    "locked": 429,
    "bad_request": 400,
    "bad_value": 400,
    "too_large": 413,
    "unknown_command": 400,
    "unknown_parameter": 404,
    "unknown_program": 404,
    "unknown_variable": 404,
    "unknown_project": 404,
    "unknown_resource": 404,
    "unknown_recording": 404,
    "unknown_test": 404,
    "not_found": 404,
    "method_not_allowed": 405,
    "compile": 422,
    "project": 422,
    "accounts": 422,
    "path": 400,  # a project file's path: outside the project, or no file it edits
    "settings": 422,  # padt.toml's settings with problems (listed in `problems`)
    "audit": 503,  # the audit log cannot be written: the change was not made
    "tests_busy": 503,  # as many unit test runs as the server runs at once are under way
    "unreachable": 504,
    # the resource's side did not answer as the resource: another party, or a lie
    "impostor": 502,
    "bad_challenge": 502,
    "bad_reply": 502,
    "internal": 500,
}


def http_status(refusal: Refusal) -> int:
    return HTTP_STATUS.get(refusal.code, 409)


def error_body(refusal: Refusal) -> dict[str, Any]:
    return {"error": refusal.as_json()}


def error_response(refusal: Refusal) -> JSONResponse:
    status = http_status(refusal)
    headers = {"WWW-Authenticate": "Bearer"} if status == 401 else None
    return JSONResponse(error_body(refusal), status_code=status, headers=headers)


def install_error_handlers(app: FastAPI) -> None:
    async def refused(request: Request, exc: Exception) -> JSONResponse:
        assert isinstance(exc, Refusal)
        return error_response(exc)

    async def invalid(request: Request, exc: Exception) -> JSONResponse:
        assert isinstance(exc, RequestValidationError)
        problems = [
            f"{'.'.join(str(part) for part in e.get('loc', ()))}: {e.get('msg')}"
            for e in exc.errors()
        ]
        return error_response(Refusal("bad_request", "; ".join(problems) or "invalid request"))

    async def http_error(request: Request, exc: Exception) -> JSONResponse:
        assert isinstance(exc, HTTPException)
        code = {404: "not_found", 405: "method_not_allowed"}.get(exc.status_code, "bad_request")
        where = f"{request.method} {request.url.path}"
        message = {404: f"no such route: {where}", 405: f"method not allowed: {where}"}
        response = error_response(Refusal(code, message.get(exc.status_code, str(exc.detail))))
        response.status_code = exc.status_code
        return response

    async def unexpected(request: Request, exc: Exception) -> JSONResponse:
        # a defect of the PADT: logged in full here, one line for the caller
        log.exception("%s %s failed", request.method, request.url.path)
        return error_response(Refusal("internal", f"internal error: {type(exc).__name__}"))

    app.add_exception_handler(Refusal, refused)
    app.add_exception_handler(RequestValidationError, invalid)
    app.add_exception_handler(HTTPException, http_error)
    app.add_exception_handler(Exception, unexpected)
