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

log = logging.getLogger("padt.api")

# the status for each refusal code; anything else is 409: the resource's state or
# configuration does not allow it now
HTTP_STATUS = {
    "unauthenticated": 401,
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
    "not_found": 404,
    "method_not_allowed": 405,
    "compile": 422,
    "project": 422,
    "accounts": 422,
    "unreachable": 504,
    "internal": 500,
}


class ApiError(Exception):
    def __init__(self, code: str, message: str, **details: Any) -> None:
        super().__init__(message)
        self.code = code
        self.message = message
        self.details = details

    @property
    def status(self) -> int:
        return HTTP_STATUS.get(self.code, 409)

    def body(self) -> dict[str, Any]:
        return {"error": {"code": self.code, "message": self.message, **self.details}}


def error_response(error: ApiError) -> JSONResponse:
    headers = {"WWW-Authenticate": "Bearer"} if error.status == 401 else None
    return JSONResponse(error.body(), status_code=error.status, headers=headers)


def install_error_handlers(app: FastAPI) -> None:
    async def api_error(request: Request, exc: Exception) -> JSONResponse:
        assert isinstance(exc, ApiError)
        return error_response(exc)

    async def invalid(request: Request, exc: Exception) -> JSONResponse:
        assert isinstance(exc, RequestValidationError)
        problems = [
            f"{'.'.join(str(part) for part in e.get('loc', ()))}: {e.get('msg')}"
            for e in exc.errors()
        ]
        return error_response(ApiError("bad_request", "; ".join(problems) or "invalid request"))

    async def http_error(request: Request, exc: Exception) -> JSONResponse:
        assert isinstance(exc, HTTPException)
        code = {404: "not_found", 405: "method_not_allowed"}.get(exc.status_code, "bad_request")
        where = f"{request.method} {request.url.path}"
        message = {404: f"no such route: {where}", 405: f"method not allowed: {where}"}
        response = error_response(ApiError(code, message.get(exc.status_code, str(exc.detail))))
        response.status_code = exc.status_code
        return response

    async def unexpected(request: Request, exc: Exception) -> JSONResponse:
        # a defect of the PADT: logged in full here, one line for the caller
        log.exception("%s %s failed", request.method, request.url.path)
        return error_response(ApiError("internal", f"internal error: {type(exc).__name__}"))

    app.add_exception_handler(ApiError, api_error)
    app.add_exception_handler(RequestValidationError, invalid)
    app.add_exception_handler(HTTPException, http_error)
    app.add_exception_handler(Exception, unexpected)
