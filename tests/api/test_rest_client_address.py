"""The lock on failed logins of the REST API counts them by the caller's real address: an
`X-Forwarded-For` (or `Forwarded`, `X-Real-IP`) a caller writes itself neither spreads its
failures over made-up addresses nor aims the lock at someone else's; behind a proxy named
with `--trusted-proxy`, the address that proxy saw counts."""

from __future__ import annotations

import subprocess
import sys
import time
from collections.abc import Iterator
from contextlib import ExitStack, contextmanager
from pathlib import Path

import httpx
import pytest

from backend.api.server import ApiServer
from backend.api.service import PadtService
from backend.engineering.client_address import TrustedProxies, client_address, trusted_proxy
from backend.engineering.padt_accounts import PadtAccounts
from backend.engineering.resource_directory import ResourceDirectory
from runtime.contract.session import open_client
from tests.conftest import REPO, free_port
from tests.support.rest_plant import PADT_PASSWORDS, padt_accounts_file
from tests.support.runtime_process import router

ATTEMPTS = 48  # wrong passwords: far more than the 5 that lock a name for an address


@contextmanager
def api(base: Path, trusted: TrustedProxies) -> Iterator[str]:
    """An API server (no resource behind it: logins to the PADT need none)."""
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    with ExitStack() as stack:
        stack.enter_context(router(endpoint))
        session = open_client(endpoint)
        stack.callback(session.close)
        accounts_file = padt_accounts_file(base / "padt-accounts.json")
        accounts = PadtAccounts(accounts_file, time.monotonic_ns)
        service = PadtService(ResourceDirectory(session), accounts, {}, base / "backups")
        stack.callback(service.close)
        server = ApiServer(service, trusted=trusted)
        stack.callback(server.close)
        yield server.url


def _from(address: str) -> httpx.Client:
    """A client whose connections come from `address` (any of 127.0.0.0/8 on Linux)."""
    return httpx.Client(transport=httpx.HTTPTransport(local_address=address), timeout=60)


def _guesses(client: httpx.Client, url: str, user: str, headers: list[dict[str, str]]) -> set[int]:
    """The statuses of ATTEMPTS wrong passwords, each with the next of `headers` in turn."""
    statuses = set()
    for attempt in range(ATTEMPTS):
        reply = client.post(
            f"{url}/api/login",
            json={"user": user, "password": f"Guess-{attempt}"},
            headers=headers[attempt % len(headers)],
        )
        statuses.add(reply.status_code)
    return statuses


def _logs_in(client: httpx.Client, url: str, user: str, headers: dict[str, str]) -> int:
    body = {"user": user, "password": PADT_PASSWORDS[user]}
    return client.post(f"{url}/api/login", json=body, headers=headers).status_code


@pytest.fixture(scope="module")
def untrusting(tmp_path_factory: pytest.TempPathFactory) -> Iterator[str]:
    with api(tmp_path_factory.mktemp("untrusting"), TrustedProxies()) as url:
        yield url


def test_made_up_forwarded_addresses_do_not_dodge_the_lock(untrusting: str) -> None:
    made_up = [{"X-Forwarded-For": f"10.0.0.{n}"} for n in range(1, 13)]
    with _from("127.0.0.1") as guesser:
        assert 429 in _guesses(guesser, untrusting, "reader", made_up)


def test_a_forwarded_address_does_not_aim_the_lock_at_its_owner(untrusting: str) -> None:
    victim = "127.0.0.3"
    aimed = [
        {"X-Forwarded-For": victim},
        {"Forwarded": f"for={victim}"},
        {"X-Real-IP": victim},
        {"X-Forwarded-For": f"{victim}, {victim}"},
    ]
    with _from("127.0.0.1") as guesser:
        assert 429 in _guesses(guesser, untrusting, "builder", aimed)
    with _from(victim) as owner:
        assert _logs_in(owner, untrusting, "builder", {}) == 200


def test_behind_a_trusted_proxy_the_address_it_saw_counts(tmp_path: Path) -> None:
    proxy, client, forged = "127.0.0.1", "10.9.9.9", "127.0.0.5"
    with api(tmp_path, TrustedProxies((trusted_proxy(proxy),))) as url, _from(proxy) as via:
        # the client wrote the forged address; the proxy appended the one it saw
        chain = {"X-Forwarded-For": f"{forged}, {client}"}
        assert 429 in _guesses(via, url, "keeper", [chain])
        assert _logs_in(via, url, "keeper", {"X-Forwarded-For": forged}) == 200
        # a caller that is no trusted proxy counts as itself, whatever it forwards
        with _from("127.0.0.2") as direct:
            made_up = [{"X-Forwarded-For": f"10.1.1.{n}"} for n in range(1, 13)]
            assert 429 in _guesses(direct, url, "reader", made_up)
        assert _logs_in(via, url, "reader", {"X-Forwarded-For": "10.1.1.1"}) == 200


def test_padt_api_takes_trusted_proxies_and_refuses_a_wrong_one() -> None:
    command = [sys.executable, "-m", "padt.cli", "api"]
    helped = subprocess.run([*command, "--help"], cwd=REPO, capture_output=True, text=True)
    assert "--trusted-proxy" in helped.stdout
    wrong = subprocess.run(
        [*command, "--trusted-proxy", "proxy.example"], cwd=REPO, capture_output=True, text=True
    )
    assert wrong.returncode == 2
    assert "'proxy.example' is no IP address or network" in wrong.stderr


def test_the_chain_is_read_from_the_right_through_trusted_proxies_only() -> None:
    trusted = TrustedProxies((trusted_proxy("10.0.0.0/8"), trusted_proxy("::1")))
    chain = ["203.0.113.9, 198.51.100.7", "10.1.1.1"]  # two header lines count as one list
    assert client_address("10.0.0.2", chain, trusted) == "198.51.100.7"
    assert client_address("::1", ["10.2.2.2, 10.3.3.3"], trusted) == "10.2.2.2"  # all trusted
    assert client_address("::ffff:10.0.0.2", ["192.0.2.1"], trusted) == "192.0.2.1"
    assert client_address("192.0.2.50", ["10.0.0.2"], trusted) == "192.0.2.50"  # not a proxy
    assert client_address("10.0.0.2", ["not-an-address, 10.0.0.3"], trusted) == "not-an-address"
    assert client_address("10.0.0.2", [], trusted) == "10.0.0.2"
    assert len(client_address("10.0.0.2", ["x" * 5000], trusted)) == 64
    assert client_address("10.0.0.2", ["192.0.2.1"], TrustedProxies()) == "10.0.0.2"
