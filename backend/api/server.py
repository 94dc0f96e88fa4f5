"""`padt api`: serve the REST API; and `ApiServer`, the same server on a thread of another
process (`padt demo`, tests)."""

from __future__ import annotations

import argparse
import logging
import socket
import sys
import threading
import time

import uvicorn

from backend.api.app import create_app
from backend.api.service import PadtService
from backend.engineering.client_address import NO_PROXIES, TrustedProxies
from backend.engineering.padt_accounts import AccountsError, PadtAccounts
from backend.engineering.project_list import projects_by_name
from backend.engineering.project_shelf import shelf_of
from backend.engineering.resource_directory import ResourceDirectory
from backend.engineering.start_up_freeze import freeze_start_up


class ApiServer:
    """Uvicorn on a thread, on a socket bound before it starts (so port 0 works and the
    URL is known at once)."""

    def __init__(
        self,
        service: PadtService,
        host: str = "127.0.0.1",
        port: int = 0,
        trusted: TrustedProxies = NO_PROXIES,
    ) -> None:
        self._socket = _listening_socket(host, port)
        bound_host, bound_port = self._socket.getsockname()[:2]
        self.url = f"http://{bound_host}:{bound_port}"
        # proxy_headers off: uvicorn would take X-Forwarded-For from any local caller as
        # the client's address; the app reads it from the proxies it was told to trust
        config = uvicorn.Config(
            create_app(service, trusted),
            log_level="warning",
            ws="websockets-sansio",
            proxy_headers=False,
        )
        self._server = uvicorn.Server(config)
        self._thread = threading.Thread(
            target=self._server.run, kwargs={"sockets": [self._socket]}, daemon=True
        )
        self._thread.start()
        deadline = time.monotonic() + 10
        while not self._server.started and self._thread.is_alive():
            if time.monotonic() > deadline:
                raise RuntimeError("the API server did not start")
            time.sleep(0.01)

    def close(self) -> None:
        self._server.should_exit = True
        self._thread.join(timeout=10)
        self._socket.close()


def _listening_socket(host: str, port: int) -> socket.socket:
    # with protocol IPPROTO_TCP, not 0 as socket.create_server makes it: asyncio turns
    # Nagle's algorithm off only for such sockets, and with it on every response on a
    # kept-alive connection waited 40 ms for a delayed ACK
    family = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM)[0][0]
    listening = socket.socket(family, socket.SOCK_STREAM, socket.IPPROTO_TCP)
    try:
        listening.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        listening.bind((host, port))
        listening.listen(128)
    except OSError:
        listening.close()
        raise
    return listening


def run(args: argparse.Namespace) -> int:
    from runtime.contract.session import open_client
    from runtime.contract.stop_request import StopRequest

    stop = StopRequest()
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(name)s %(message)s")
    try:
        accounts = PadtAccounts(args.accounts, time.monotonic_ns)
        projects = shelf_of(projects_by_name(args.project), args.projects_dir, args.audit_log)
    except (AccountsError, ValueError, OSError) as exc:
        print(f"padt api: {exc}", file=sys.stderr)
        return 2
    if accounts.empty:
        print(
            f"padt api: no accounts in {args.accounts}; make a Security Administrator first: "
            f"padt api-user --accounts {args.accounts} NAME --level security-administrator",
            file=sys.stderr,
        )
        return 2
    session = open_client(args.zenoh, args.zenoh_config)
    directory = ResourceDirectory(session)
    service = PadtService(directory, accounts, projects, args.backup_dir)
    try:
        server = ApiServer(service, args.host, args.port, TrustedProxies(tuple(args.trusted_proxy)))
    except OSError as exc:
        print(f"padt api: cannot serve on {args.host}:{args.port}: {exc}", file=sys.stderr)
        service.close()
        session.close()
        return 1
    freeze_start_up()
    print(f"padt api: {server.url} (OpenAPI at {server.url}/docs)", flush=True)
    stop.sleep_until_requested()
    server.close()
    service.close()
    session.close()
    return 0
