"""The REST API against hostile callers: nested bodies, and failed logins that would lock an
administrator out for everyone. The API and the resource behind it go on serving."""

from __future__ import annotations

import json
from collections.abc import Iterator

import httpx
import pytest

from tests.support.rest_plant import PADT_PASSWORDS, Plant, plant

R = "/api/resources/Plant"


@pytest.fixture(scope="module")
def site(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Plant]:
    with plant(tmp_path_factory.mktemp("hostile")) as found:
        yield found


def test_nested_values_are_refused_and_nothing_falls_over(site: Plant) -> None:
    token = site.session("builder", "engineer")
    headers = {"content-type": "application/json", "Authorization": f"Bearer {token}"}
    for depth in (17, 500, 5000, 100_000):
        body = b'{"value": ' + b"[" * depth + b"1" + b"]" * depth + b"}"
        reply = site.http.put(f"{site.url}{R}/values/P.n", content=body, headers=headers)
        assert reply.status_code == 400, (depth, reply.text)
        assert reply.json()["error"]["code"] == "bad_request"
    flat = site.http.put(f"{site.url}{R}/values/P.limit", json={"value": 7}, headers=headers)
    assert flat.status_code == 200, flat.text
    assert site.call("GET", f"{R}/status", token).json()["state"] == "RUN"


def test_failed_logins_lock_a_name_only_for_their_address(site: Plant) -> None:
    for _ in range(6):
        refused = site.http.post(
            f"{site.url}/api/login", json={"user": "keeper", "password": "Guess-0"}
        )
        assert refused.status_code in (401, 429)
    locked = site.http.post(
        f"{site.url}/api/login", json={"user": "keeper", "password": PADT_PASSWORDS["keeper"]}
    )
    assert locked.status_code == 429
    # the administrator elsewhere (another loopback address) is not locked out
    elsewhere = httpx.Client(transport=httpx.HTTPTransport(local_address="127.0.0.2"))
    with elsewhere:
        login = elsewhere.post(
            f"{site.url}/api/login", json={"user": "keeper", "password": PADT_PASSWORDS["keeper"]}
        )
    assert login.status_code == 200, login.text
    assert json.loads(login.text)["level"] == "security-administrator"
