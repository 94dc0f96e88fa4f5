"""Logging in to the PADT, the level each route needs, and the PADT accounts.

A client logs in with `POST /api/login` and sends the token it gets as `Authorization:
Bearer <token>`. Read-only may view; Read+Write may also compile, load and act on
resources; Security Administrator may also manage the PADT accounts. Acting on a resource
needs, besides, a login to that resource: the resource checks its own accounts."""

from __future__ import annotations

import logging
from collections.abc import Callable
from typing import Annotated, Any, Literal

from fastapi import APIRouter, Depends, Request, Response
from fastapi import Path as PathParameter
from fastapi.security import HTTPAuthorizationCredentials, HTTPBearer
from pydantic import BaseModel, Field

from backend.api.service import Caller, PadtService
from backend.engineering.client_address import TrustedProxies, client_address
from backend.engineering.padt_accounts import AccountsError
from backend.engineering.padt_levels import PADT_LEVELS
from runtime.contract.accounts import NAME, SESSION_NS
from runtime.contract.refusal import Refusal

log = logging.getLogger("padt.api")
_bearer = HTTPBearer(auto_error=False, description="the token from POST /api/login")


def service_of(request: Request) -> PadtService:
    service: PadtService = request.app.state.service
    return service


def _caller(needed: str) -> Callable[..., Caller]:
    def dependency(
        request: Request,
        credentials: Annotated[HTTPAuthorizationCredentials | None, Depends(_bearer)],
    ) -> Caller:
        token = credentials.credentials if credentials is not None else None
        return service_of(request).caller(token, needed)

    return dependency


ReadOnly = Annotated[Caller, Depends(_caller("read-only"))]
ReadWrite = Annotated[Caller, Depends(_caller("read-write"))]
SecurityAdministrator = Annotated[Caller, Depends(_caller("security-administrator"))]
Service = Annotated[PadtService, Depends(service_of)]


class Credentials(BaseModel):
    user: str = Field(max_length=64)
    password: str = Field(max_length=64)


class SessionInfo(BaseModel):
    token: str
    user: str
    level: str
    expires_in_s: int


class Account(BaseModel):
    name: str
    level: str


class AccountChange(BaseModel):
    level: Literal["read-only", "read-write", "security-administrator"]
    password: str | None = Field(
        default=None, max_length=64, description="a new password; none keeps the current one"
    )


router = APIRouter(prefix="/api", tags=["session and accounts"])


@router.post("/login", summary="Log in to the PADT")
def login(credentials: Credentials, service: Service, request: Request) -> SessionInfo:
    # failed logins lock the name for the address they come from, not for everyone
    address = _caller_address(request)
    try:
        token, session = service.accounts.login(credentials.user, credentials.password, address)
    except Refusal as denied:
        # the name only: it is what an administrator looks for; never the password
        log.warning("login to the PADT refused for %r: %s", credentials.user[:32], denied.code)
        raise
    log.info("login to the PADT: %s (%s)", session.user, session.level)
    return SessionInfo(
        token=token, user=session.user, level=session.level, expires_in_s=SESSION_NS // 10**9
    )


def _caller_address(request: Request) -> str:
    trusted: TrustedProxies = request.app.state.trusted_proxies
    peer = request.client.host if request.client is not None else "unknown"
    return client_address(peer, request.headers.getlist("x-forwarded-for"), trusted)


@router.post("/logout", status_code=204, summary="End this session")
def logout(caller: ReadOnly, service: Service) -> Response:
    service.accounts.logout(caller.token)
    return Response(status_code=204)


@router.get("/session", summary="Who this session is")
def session(caller: ReadOnly) -> dict[str, Any]:
    return {"user": caller.user, "level": caller.level, "levels": list(PADT_LEVELS)}


@router.get("/accounts", summary="The PADT accounts (names and levels)")
def accounts(caller: SecurityAdministrator, service: Service) -> list[Account]:
    return [Account(name=a.name, level=a.level) for a in service.accounts.accounts()]


@router.put("/accounts/{name}", summary="Add or change a PADT account")
def put_account(
    name: Annotated[str, PathParameter(pattern=NAME.pattern)],
    change: AccountChange,
    caller: SecurityAdministrator,
    service: Service,
) -> Account:
    try:
        service.accounts.put(name, change.level, change.password)
    except AccountsError as exc:
        raise Refusal("accounts", str(exc)) from None
    log.info("PADT account %s set to %s by %s", name, change.level, caller.user)
    return Account(name=name, level=change.level)


@router.delete("/accounts/{name}", status_code=204, summary="Remove a PADT account")
def delete_account(name: str, caller: SecurityAdministrator, service: Service) -> Response:
    if all(account.name != name for account in service.accounts.accounts()):
        raise Refusal("not_found", f"there is no account '{name}'")
    try:
        service.accounts.delete(name)
    except AccountsError as exc:
        raise Refusal("accounts", str(exc)) from None
    log.info("PADT account %s removed by %s", name, caller.user)
    return Response(status_code=204)
