"""Values through the REST API as people write them: every route that gives values gives
each also as the ST literal of its type (TIME as `T#1s500ms`, not nanoseconds; DATE, TOD
and DT as their literals), beside the run-time value; writes and forces take a literal
too. `padt values --json` gives the same."""

from __future__ import annotations

import json
from collections.abc import Iterator
from typing import Any

import pytest
from websockets.sync.client import connect

from tests.conftest import padt
from tests.support.rest_plant import PES_PASSWORDS, Plant, plant

R = "/api/resources/Plant"
EXTRA = (
    "delay : TIME := T#1s500ms; day : DATE := D#2024-01-15; clock : TOD := TOD#12:30:05.5;"
    " stamp : DT := DT#2024-01-15-12:30:05; span : ARRAY[1..2] OF TIME := [T#1s, T#2m];"
)
LITERALS = {
    "P.delay": "T#1s500ms",
    "P.day": "D#2024-01-15",
    "P.clock": "TOD#12:30:05.5",
    "P.stamp": "DT#2024-01-15-12:30:05",
    "P.span": "[T#1s, T#2m]",
}


@pytest.fixture(scope="module")
def site(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Plant]:
    with plant(tmp_path_factory.mktemp("iec-values"), extra=EXTRA) as found:
        yield found


def _values(site: Plant, token: str) -> dict[str, Any]:
    reply = site.call("GET", f"{R}/values", token)
    assert reply.status_code == 200, reply.text
    values: dict[str, Any] = reply.json()
    return values


def test_values_come_with_their_literals(site: Plant) -> None:
    token = site.session("reader", "viewer")
    shown = _values(site, token)
    assert shown["values"]["P.delay"] == 1_500_000_000  # the run-time value, as on the bus
    assert {path: shown["literals"][path] for path in LITERALS} == LITERALS
    assert shown["literals"]["P.flag"] in ("TRUE", "FALSE")
    assert set(shown["literals"]) == set(shown["values"])


def test_writes_and_forces_take_literals(site: Plant) -> None:
    token = site.session("builder", "engineer")
    written = site.call("PUT", f"{R}/values/P.delay", token, json={"literal": "T#2s250ms"})
    assert written.status_code == 200, written.text
    shown = _values(site, token)
    assert (shown["values"]["P.delay"], shown["literals"]["P.delay"]) == (
        2_250_000_000,
        "T#2s250ms",
    )
    wrong = site.call("PUT", f"{R}/values/P.delay", token, json={"literal": "2 seconds"})
    assert wrong.status_code == 400 and wrong.json()["error"]["code"] == "bad_value", wrong.text
    assert "is not an ST literal of type TIME" in wrong.json()["error"]["message"]
    both = site.call("PUT", f"{R}/values/P.delay", token, json={"value": 1, "literal": "T#1s"})
    assert both.status_code == 400 and both.json()["error"]["code"] == "bad_request"
    unknown = site.call("PUT", f"{R}/values/P.nothing", token, json={"literal": "T#1s"})
    assert unknown.status_code == 404, unknown.text
    forced = site.call("PUT", f"{R}/forces/P.day", token, json={"literal": "D#2025-02-03"})
    assert forced.status_code == 200, forced.text
    try:
        entries = site.call("GET", f"{R}/forcing", token).json()["entries"]
        (entry,) = [e for e in entries if e["variable"] == "P.day"]
        assert entry["literal"] == "D#2025-02-03"
    finally:
        site.call("DELETE", f"{R}/forces/P.day", token).raise_for_status()
    # the event log says it as people write it too
    messages = [e["message"] for e in site.call("GET", f"{R}/events", token).json()]
    assert "P.delay written: T#1s500ms -> T#2s250ms" in messages, messages
    assert "P.day forced to D#2025-02-03 (switch ON)" in messages, messages


def test_live_values_come_with_their_literals(site: Plant) -> None:
    token = site.session("reader", "viewer")
    with connect(site.url.replace("http://", "ws://") + f"{R}/live") as ws:
        ws.send(json.dumps({"token": token, "variables": ["P.day", "P.clock"], "period_ms": 50}))
        assert json.loads(ws.recv(timeout=30)) == {"variables": ["P.day", "P.clock"]}
        message = json.loads(ws.recv(timeout=30))
    assert message["values"]["P.day"]["literal"] == "D#2024-01-15"
    assert message["values"]["P.clock"]["literal"] == "TOD#12:30:05.5"


def test_padt_values_json_gives_the_same(site: Plant) -> None:
    token = site.session("reader", "viewer")
    over_rest = _values(site, token)
    command = ["values", "P.day", "P.clock", "P.stamp", "P.span", "--json"]
    command += ["--resource", "Plant", "--zenoh", site.endpoint, "--user", "viewer"]
    shown = padt(*command, env={"PADT_PASSWORD": PES_PASSWORDS["viewer"]})
    assert shown.returncode == 0, shown.stderr
    printed = json.loads(shown.stdout)
    for path in ("P.day", "P.clock", "P.stamp", "P.span"):
        assert printed["values"][path] == over_rest["values"][path]
        assert printed["literals"][path] == over_rest["literals"][path] == LITERALS[path]
