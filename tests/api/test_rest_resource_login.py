"""A valid API session without a login to the resource is told what is missing: the
resource login (`401 resource_login_required`, "log in to resource Plant first"), not that
its token is invalid; over the live WebSocket as well."""

from __future__ import annotations

import json
from collections.abc import Iterator

import pytest
from websockets.sync.client import connect

from tests.support.rest_plant import Plant, plant

R = "/api/resources/Plant"


@pytest.fixture(scope="module")
def site(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Plant]:
    with plant(tmp_path_factory.mktemp("resource-login")) as found:
        yield found


def _refusal(site: Plant, token: str, method: str, path: str) -> dict[str, str]:
    reply = site.call(method, path, token)
    assert reply.status_code == 401, reply.text
    error: dict[str, str] = reply.json()["error"]
    return error


def test_a_missing_resource_login_is_named_as_such(site: Plant) -> None:
    token = site.session("builder")  # the PADT session is valid; no login to Plant
    for method, path in [("GET", f"{R}/status"), ("GET", f"{R}/values"), ("POST", f"{R}/stop")]:
        error = _refusal(site, token, method, path)
        assert error["code"] == "resource_login_required", error
        assert "log in to resource Plant first" in error["message"]
        assert "no valid session token" not in error["message"]
    # the API session itself is fine
    assert site.call("GET", "/api/session", token).json()["user"] == "builder"
    # logged in, then out again: missing once more
    site.call("POST", f"{R}/login", token, json={"user": "op", "password": "Turn-2"})
    assert site.call("GET", f"{R}/status", token).status_code == 200
    assert site.call("POST", f"{R}/logout", token).status_code == 204
    assert _refusal(site, token, "GET", f"{R}/status")["code"] == "resource_login_required"
    # a token the API does not know is still `unauthenticated`
    assert _refusal(site, "forged", "GET", f"{R}/status")["code"] == "unauthenticated"


def test_the_live_websocket_names_a_missing_resource_login(site: Plant) -> None:
    token = site.session("reader")
    with connect(site.url.replace("http://", "ws://") + f"{R}/live") as ws:
        ws.send(json.dumps({"token": token, "variables": ["P.n"]}))
        error = json.loads(ws.recv(timeout=30))["error"]
    assert error["code"] == "resource_login_required", error
    assert "log in to resource Plant first" in error["message"]
