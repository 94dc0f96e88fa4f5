"""Recordings over the REST API, against a real runtime process and a real HTTP server:
start, list, stop, download (an MCAP file the recording reader reads), delete; the PADT's
and the resource's levels; structured refusals."""

from __future__ import annotations

import io
import os
import time
from collections.abc import Iterator
from typing import Any

import pytest

from runtime.contract.protocol import MAX_RECORDING_READ
from runtime.contract.recording import read_recording
from tests.support.rest_plant import Plant, plant

R = "/api/resources/Plant"


@pytest.fixture(scope="module")
def site(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Plant]:
    with plant(tmp_path_factory.mktemp("rest-recordings")) as found:
        yield found


def ok(reply: Any) -> Any:
    assert reply.status_code == 200, reply.text
    return reply.json()


def error(reply: Any, status: int, code: str) -> str:
    assert reply.status_code == status, reply.text
    body = reply.json()
    assert set(body) == {"error"} and body["error"]["code"] == code, body
    message: str = body["error"]["message"]
    return message


def listed(site: Plant, token: str) -> dict[str, dict[str, Any]]:
    return {r["id"]: r for r in ok(site.call("GET", f"{R}/recordings", token))}


def ended(site: Plant, token: str, recording_id: str) -> dict[str, Any]:
    deadline = time.monotonic() + 30
    while time.monotonic() < deadline:
        found = listed(site, token)[recording_id]
        if found["state"] in ("done", "failed"):
            return found
        time.sleep(0.1)
    raise AssertionError(f"recording {recording_id} did not end")


def test_record_list_download_and_delete(site: Plant) -> None:
    operator = site.session("builder", "op")
    reader = site.session("reader", "viewer")
    body = {"variables": ["P.n", "P.flag"], "cycles": 50, "id": "rest"}
    started = ok(site.call("POST", f"{R}/recordings", operator, json=body))
    assert started["id"] == "rest" and started["variables"] == 2
    assert started["state"] == "recording" and started["all_inputs"] is False

    done = ended(site, reader, "rest")  # a read-only PADT user may follow it
    assert (done["state"], done["cycles"], done["dropped"]) == ("done", 50, 0)
    [file] = done["files"]
    assert file["name"] == "rest-1.mcap"

    download = site.call("GET", f"{R}/recordings/files/rest-1.mcap", reader)
    assert download.status_code == 200, download.text
    assert download.headers["content-type"] == "application/octet-stream"
    assert download.headers["content-disposition"] == 'attachment; filename="rest-1.mcap"'
    assert int(download.headers["content-length"]) == len(download.content) == file["size"]
    recording = read_recording(io.BytesIO(download.content))
    assert recording.complete and len(recording.rows) == 50
    counts = recording.column("P.n")
    assert counts == list(range(counts[0], counts[0] + 50))
    assert recording.column("P.flag") == [n > 10 for n in counts]

    left = ok(site.call("DELETE", f"{R}/recordings/rest", operator))
    assert "rest" not in {r["id"] for r in left}
    assert "rest" not in {r["id"] for r in ok(site.call("GET", f"{R}/recordings", reader))}


def test_stop_a_running_recording(site: Plant) -> None:
    operator = site.session("builder", "op")
    ok(site.call("POST", f"{R}/recordings", operator, json={"variables": ["P*"], "id": "open"}))
    while listed(site, operator)["open"]["cycles"] < 10:  # some cycles in, then stop it
        time.sleep(0.05)
    stopped = ok(site.call("POST", f"{R}/recordings/open/stop", operator))
    assert stopped["id"] == "open" and stopped["state"] in ("recording", "done")
    done = ended(site, operator, "open")
    assert done["state"] == "done" and done["cycles"] >= 10
    [file] = done["files"]
    data = site.call("GET", f"{R}/recordings/files/{file['name']}", operator).content
    recording = read_recording(io.BytesIO(data))
    assert recording.complete and len(recording.rows) == done["cycles"]
    assert {"P.n", "P.limit", "P.flag"} <= {path for path, _ in recording.header.variables}
    ok(site.call("DELETE", f"{R}/recordings/open", operator))


def test_refusals_are_structured(site: Plant) -> None:
    body = {"variables": ["P.n"], "cycles": 5}
    # the PADT's level: a read-only PADT user starts nothing
    reader = site.session("reader", "op")
    assert "read-only" in error(site.call("POST", f"{R}/recordings", reader, json=body), 403,
                                "forbidden")  # fmt: skip
    # the resource's level: recording needs an operator
    viewer = site.session("builder", "viewer")
    message = error(site.call("POST", f"{R}/recordings", viewer, json=body), 403, "forbidden")
    assert "operator" in message
    operator = site.session("builder", "op")
    trigger = {**body, "trigger": "P.n >> 3"}
    message = error(site.call("POST", f"{R}/recordings", operator, json=trigger), 400,
                    "bad_request")  # fmt: skip
    assert "trigger" in message and "OP one of" in message
    out_of_range = {**body, "cycles": 0}
    error(site.call("POST", f"{R}/recordings", operator, json=out_of_range), 400, "bad_request")
    unknown = {"variables": ["P.nothing"], "cycles": 5}
    reply = site.call("POST", f"{R}/recordings", operator, json=unknown)
    assert "P.nothing" in error(reply, 404, "unknown_variable")
    error(site.call("GET", f"{R}/recordings/files/identity.key", operator), 400, "bad_request")
    missing = site.call("GET", f"{R}/recordings/files/never-1.mcap", operator)
    assert "never-1.mcap" in error(missing, 404, "unknown_recording")
    absent = site.call("POST", f"{R}/recordings/never/stop", operator)
    assert "never" in error(absent, 404, "unknown_recording")
    error(site.call("DELETE", f"{R}/recordings/never", operator), 404, "unknown_recording")
    error(site.call("GET", f"{R}/recordings", None), 401, "unauthenticated")


def test_a_file_of_many_chunks_streams_whole(site: Plant) -> None:
    # a file as a long recording leaves it: larger than one record_read of the resource
    folder = site.state_dir / "recordings"
    folder.mkdir(parents=True, exist_ok=True)
    data = os.urandom(5 * MAX_RECORDING_READ + 77)
    (folder / "long-1.mcap").write_bytes(data)
    reader = site.session("reader", "viewer")
    assert [f["name"] for f in listed(site, reader)["long"]["files"]] == ["long-1.mcap"]
    download = site.call("GET", f"{R}/recordings/files/long-1.mcap", reader)
    assert download.status_code == 200
    assert int(download.headers["content-length"]) == len(data)
    assert download.content == data
    ok(site.call("DELETE", f"{R}/recordings/long", site.session("builder", "op")))
    assert not (folder / "long-1.mcap").exists()
