"""Field I/O in the REST API: `GET /api/resources/{r}/io` is the resource's `io` reply, at
the read level of both the PADT and the resource."""

from __future__ import annotations

from pathlib import Path

from tests.support.rest_plant import plant


def test_io_of_a_resource(tmp_path: Path) -> None:
    with plant(tmp_path) as site:
        path = "/api/resources/Plant/io"
        assert site.call("GET", path).status_code == 401  # no token
        token = site.session("reader", "viewer")
        reply = site.call("GET", path, token)
        assert reply.status_code == 200, reply.text
        # the plant's project locates no variable: nothing served, no device
        assert reply.json() == {"io": None, "points": []}
        documented = site.call("GET", "/openapi.json").json()["paths"]
        assert path.replace("Plant", "{resource}") in documented
