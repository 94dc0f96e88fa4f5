"""The browser UI counts failed logins by the browser's real address, as the REST API does:
the `X-Forwarded-For` of the websocket's handshake counts only from a proxy given with
`--trusted-proxy`. A websocket client speaking viser's subprotocol stands in for a browser
(viser counts a client as connected at its first camera message; the UI takes the address
then, before it draws any page)."""

from __future__ import annotations

import asyncio
import time
from collections.abc import Iterator
from contextlib import ExitStack, contextmanager
from pathlib import Path

import msgspec.msgpack
import viser
from viser._messages import ViewerCameraMessage
from websockets.asyncio.client import connect

from backend.engineering.client_address import TrustedProxies, trusted_proxy
from backend.engineering.padt_accounts import PadtAccounts
from backend.engineering.resource_directory import ResourceDirectory
from backend.engineering.watch_lists import WatchLists
from frontend.app import PadtUi
from frontend.ui_context import UiContext
from runtime.contract.session import open_client
from tests.conftest import free_port
from tests.support.rest_plant import padt_accounts_file
from tests.support.runtime_process import router

ORIGIN, UP = (0.0, 0.0, 0.0), (0.0, 0.0, 1.0)
CAMERA = ViewerCameraMessage((1.0, 0.0, 0.0, 0.0), UP, 1.0, 0.01, 100.0, 480, 640, ORIGIN, UP)


@contextmanager
def ui(base: Path, trusted: TrustedProxies) -> Iterator[PadtUi]:
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    with ExitStack() as stack:
        stack.enter_context(router(endpoint))
        session = open_client(endpoint)
        stack.callback(session.close)
        accounts = PadtAccounts(padt_accounts_file(base / "accounts.json"), time.monotonic_ns)
        directory = ResourceDirectory(session)
        stack.callback(directory.close)
        lists = WatchLists(base / "watch-lists.json")
        context = UiContext(directory, accounts, endpoint, lists, {}, base / "backups")
        served = PadtUi(context, port=free_port(), trusted=trusted)
        stack.callback(served.close)
        yield served


def _address_seen(served: PadtUi, forwarded_for: str) -> str:
    """The address the UI gave the session of a browser whose handshake says
    `X-Forwarded-For: forwarded_for`."""
    url = served.url.replace("http://", "ws://")

    async def visit() -> str:
        async with connect(
            url,
            subprotocols=[f"viser-v{viser.__version__}"],  # type: ignore[list-item]
            additional_headers={"X-Forwarded-For": forwarded_for},
        ) as browser:
            await browser.send(msgspec.msgpack.encode(CAMERA.as_serializable_dict()))
            deadline = time.monotonic() + 30
            while not served.browsers:
                assert time.monotonic() < deadline, "the UI made no session for the browser"
                await asyncio.sleep(0.02)
            (session,) = served.browsers.values()
            return session.address

    return asyncio.run(visit())


def test_a_forwarded_address_counts_only_from_a_trusted_proxy(tmp_path: Path) -> None:
    with ui(tmp_path / "plain", TrustedProxies()) as served:
        assert _address_seen(served, "10.0.0.7") == "127.0.0.1"
    trusted = TrustedProxies((trusted_proxy("127.0.0.1"),))
    with ui(tmp_path / "proxied", trusted) as served:
        # the browser wrote 10.0.0.7 itself; the proxy appended the address it saw
        assert _address_seen(served, "10.0.0.7, 10.8.8.8") == "10.8.8.8"
