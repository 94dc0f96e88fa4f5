"""Debugging in the code through the REST API, served on a real HTTP port, against a real
runtime process over Zenoh: a file's breakpoints set, hit, listed and cleared; the stack
and the variables at a break, a write there; step, run to, continue; the timeout and the
keep-alive; the PADT's and the resource's levels; bad bodies refused with a reason."""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from typing import Any

import pytest

from tests.support.rest_plant import Plant, plant

R = "/api/resources/Plant"
D = f"{R}/debug"


@pytest.fixture(scope="module")
def site(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Plant]:
    with plant(tmp_path_factory.mktemp("rest-debug")) as found:
        yield found


@pytest.fixture(scope="module")
def engineer(site: Plant) -> str:
    """A Read+Write PADT session logged in to the resource at read-write."""
    return site.session("builder", "engineer")


@pytest.fixture(autouse=True)
def nothing_armed_after(site: Plant, engineer: str) -> Iterator[None]:
    yield
    assert site.call("DELETE", f"{D}/breakpoints", engineer).status_code == 200


def ok(reply: Any) -> Any:
    assert reply.status_code == 200, reply.text
    return reply.json()


def error(reply: Any, status: int, code: str) -> str:
    assert reply.status_code == status, reply.text
    body = reply.json()
    assert set(body) == {"error"} and body["error"]["code"] == code, body
    message: str = body["error"]["message"]
    assert "Traceback" not in message
    return message


def until(what: Callable[[], Any], timeout_s: float = 60) -> Any:
    deadline = time.monotonic() + timeout_s
    while True:
        found = what()
        if found:
            return found
        assert time.monotonic() < deadline, "not within the time"
        time.sleep(0.1)


def paused(site: Plant, token: str) -> Any:
    return ok(site.call("GET", D, token))["paused"]


def test_a_breakpoint_set_hit_stepped_and_cleared(site: Plant, engineer: str) -> None:
    # plant.st: 3 n := n + 1;  4 IF n > limit THEN ...  5 flag := n > 10;
    never = {"line": 2, "condition": "n < 0"}
    body = {"breakpoints": [{"line": 4, "condition": "n > 5"}, never]}
    state = ok(site.call("PUT", f"{D}/breakpoints/plant.st", engineer, json=body))
    armed = [(b["requested"], b["line"], b["verified"]) for b in state["breakpoints"]]
    assert armed == [(4, 4, True), (2, 3, True)]  # line 2 is a declaration: moved to 3
    listed = ok(site.call("GET", f"{D}/breakpoints/plant.st", engineer))
    assert [b["line"] for b in listed] == [4, 3]
    body = {"breakpoints": [{"line": 4, "condition": "n > 5"}]}
    ok(site.call("PUT", f"{D}/breakpoints/plant.st", engineer, json=body))

    where = until(lambda: paused(site, engineer))
    assert (where["program"], where["file"], where["line"], where["reason"]) == (
        "P",
        "plant.st",
        4,
        "breakpoint",
    )
    programs = ok(site.call("GET", f"{R}/programs", engineer))
    assert programs[0]["state"] == "BKPT" and programs[0]["paused_at"] == "plant.st:4 (POU P)"
    frames = ok(site.call("GET", f"{D}/programs/P/stack", engineer))["frames"]
    assert [(f["name"], f["kind"], f["line"]) for f in frames] == [("P", "program", 4)]
    shown = {
        v["name"]: v
        for v in ok(site.call("GET", f"{D}/programs/P/variables", engineer))["variables"]
    }
    assert shown["n"]["value"] > 5 and shown["n"]["literal"] == str(shown["n"]["value"])
    assert shown["n"]["path"] == "P.n"

    # a write at the break shows in the frame; a step runs the statement
    ok(site.call("PUT", f"{R}/values/P.n", engineer, json={"value": 7}))
    shown = ok(site.call("GET", f"{D}/programs/P/variables", engineer))["variables"]
    assert {v["name"]: v["value"] for v in shown}["n"] == 7
    stepped = ok(site.call("POST", f"{D}/programs/P/step", engineer, json={"kind": "over"}))
    assert stepped["paused"]["line"] == 5
    # run to the first statement: it is there in the next program cycle
    run = {"file": "plant.st", "line": 3}
    ok(site.call("POST", f"{D}/programs/P/run-to", engineer, json=run))
    there = until(lambda: paused(site, engineer))
    assert (there["line"], there["reason"]) in ((3, "run to"), (4, "breakpoint"))
    ok(site.call("POST", f"{D}/programs/P/step", engineer, json={"kind": "cycle"}))
    assert paused(site, engineer)["line"] == 0  # at the end of its program cycle

    # a file's breakpoints cleared: the program still stands until it continues
    assert ok(site.call("DELETE", f"{D}/breakpoints/plant.st", engineer))["breakpoints"] == []
    assert ok(site.call("POST", f"{D}/programs/P/continue", engineer))["paused"] is None
    until(lambda: ok(site.call("GET", f"{R}/programs", engineer))[0]["state"] == "RUN")
    error(site.call("POST", f"{D}/programs/P/continue", engineer), 409, "state")


def test_the_timeout_and_the_keep_alive(site: Plant, engineer: str) -> None:
    assert ok(site.call("PUT", f"{D}/timeout", engineer, json={"timeout_s": 60}))["timeout_s"] == 60
    try:
        ok(site.call("PUT", f"{D}/breakpoints/plant.st", engineer, json={"breakpoints": []}))
        alive = ok(site.call("POST", f"{D}/keep-alive", engineer))
        assert alive["timeout_s"] == 60 and alive["silent_s"] < 60
    finally:
        ok(site.call("PUT", f"{D}/timeout", engineer, json={"timeout_s": 120}))
    message = error(
        site.call("PUT", f"{D}/timeout", engineer, json={"timeout_s": 2}), 400, "bad_request"
    )
    assert "timeout_s" in message


def test_levels_of_the_padt_and_of_the_resource(site: Plant) -> None:
    body = {"breakpoints": [{"line": 3}]}
    reader = site.session("reader", "admin")  # the resource would allow it; the PADT not
    for method, path, json in (
        ("PUT", f"{D}/breakpoints/plant.st", body),
        ("DELETE", f"{D}/breakpoints", None),
        ("POST", f"{D}/programs/P/continue", None),
        ("POST", f"{D}/programs/P/step", None),
        ("PUT", f"{D}/timeout", {"timeout_s": 60}),
        ("POST", f"{D}/keep-alive", None),
    ):
        assert "reader (read-only)" in error(
            site.call(method, path, reader, json=json), 403, "forbidden"
        )
    assert ok(site.call("GET", D, reader))["breakpoints"] == []
    operator = site.session("builder", "op")  # below read-write on the resource
    error(site.call("PUT", f"{D}/breakpoints/plant.st", operator, json=body), 403, "forbidden")
    error(site.call("POST", f"{D}/keep-alive", operator), 403, "forbidden")
    viewer = site.session("reader", "viewer")  # reading needs read only
    assert ok(site.call("GET", f"{D}/breakpoints/plant.st", viewer)) == []
    error(site.call("GET", f"{D}/programs/P/stack", viewer), 409, "state")  # not in BKPT


def test_bad_input_is_refused_with_a_reason(site: Plant, engineer: str) -> None:
    put = f"{D}/breakpoints/plant.st"
    for body in (
        {"breakpoints": [{"line": 0}]},
        {"breakpoints": [{"line": 3, "condition": "x" * 600}]},
        {"breakpoints": [{"line": 3, "log": ["n"] * 17}]},
        {"breakpoints": [{"line": 3}] * 257},
        {"breakpoints": "all"},
        {},
    ):
        error(site.call("PUT", put, engineer, json=body), 400, "bad_request")
    step = site.call("POST", f"{D}/programs/P/step", engineer, json={"kind": "sideways"})
    error(step, 400, "bad_request")
    odd = ok(
        site.call("PUT", put, engineer, json={"breakpoints": [{"line": 3, "condition": "n >"}]})
    )
    assert odd["breakpoints"][0]["message"] == "'n >': more expected"
    nowhere = ok(
        site.call("PUT", f"{D}/breakpoints/none.st", engineer, json={"breakpoints": [{"line": 1}]})
    )
    assert not nowhere["breakpoints"][-1]["verified"]
    error(site.call("GET", f"{D}/programs/Nobody/stack", engineer), 409, "state")
    frame = site.call("GET", f"{D}/programs/P/variables?frame=-1", engineer)
    error(frame, 400, "bad_request")
