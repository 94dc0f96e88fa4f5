"""The FastAPI application: routes, error handlers, and the service behind them."""

from __future__ import annotations

from fastapi import FastAPI
from fastapi_offline import FastAPIOffline

from backend.api import auth, debugging, language, live, projects, resources
from backend.api.body_limit import BodyLimit
from backend.api.errors import install_error_handlers
from backend.api.service import PadtService
from backend.engineering.client_address import NO_PROXIES, TrustedProxies

API_VERSION = "1"
DESCRIPTION = """The PADT's operations over HTTP: projects (compile, check-twice, CRCs),
resources (status, load, start and stop, programs and single step, reload preview and
reload, parameters, forcing, values, events, statistics, debugging in the code) and live
values (WebSocket `/api/resources/{resource}/live`). Log in with `POST /api/login` and send
the token as `Authorization: Bearer <token>`; acting on a resource needs a login to it as well
(`POST /api/resources/{resource}/login`). Every error is `{"error": {"code", "message"}}`.
The reference is docs/rest-api.md."""


def create_app(service: PadtService, trusted: TrustedProxies = NO_PROXIES) -> FastAPI:
    """`trusted`: the proxies whose X-Forwarded-For names the caller (for the login lock)."""
    # Swagger UI and ReDoc from the package's own files: /docs works without internet
    app = FastAPIOffline(title="PADT REST API", version=API_VERSION, description=DESCRIPTION)
    app.state.service = service
    app.state.trusted_proxies = trusted
    install_error_handlers(app)
    app.add_middleware(BodyLimit)
    routers = (auth, projects, language, resources, debugging, live)
    for router in (module.router for module in routers):
        app.include_router(router)
    return app
