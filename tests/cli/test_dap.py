"""`padt dap` as VS Code drives it: the Debug Adapter Protocol's JSON over the process's
stdin/stdout (or a TCP port), against a real runtime process over real Zenoh. A program
stops at a conditional breakpoint while the other runs on, shows its stack and variables,
steps into a method called through an interface and out again, logs at a logpoint, and runs
on once the client disconnects."""

from __future__ import annotations

import json
import os
import queue
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import IO, Any

import pytest

from backend.engineering.project import compile_project, load_project, user_entry
from backend.engineering.resource_client import ResourceClient
from runtime.contract import protocol as p
from runtime.contract.accounts import hash_password
from runtime.contract.artifact import UserAccount
from tests.conftest import REPO, free_port
from tests.support.debugged_program import COUNTERS as SOURCE
from tests.support.runtime_process import running_resource, store_artifact

RESOURCE = "Bench"
PASSWORDS = {"admin": "Admin-1", "engineer": "Engineer-2", "viewer": "Viewer-3"}
LEVELS = {"admin": "administrator", "engineer": "read-write", "viewer": "read"}
WAIT_S = 60  # a loaded machine: patience, never a timing assertion

PADT_TOML = """\
[project]
name = "Debugging"

[resource]
name = "Bench"
target_cycle_ms = 50
safety_operation = false
autostart = "cold"

[[resource.program]]
name = "Main"
pou = "Main"
id = 1
priority = 0

[[resource.program]]
name = "Other"
pou = "Other"
id = 2
priority = 1
"""


GLOBALS = """\
TYPE Point :
STRUCT
  x : INT;
  y : INT;
END_STRUCT
END_TYPE

VAR_GLOBAL
  limit : INT := 7;
  spot : Point;
END_VAR
"""


class Bench:
    def __init__(self, project: Path, endpoint: str, client: ResourceClient) -> None:
        self.project, self.endpoint, self.client = project, endpoint, client
        self.source = str(project / "prog.st")

    def program(self, name: str) -> p.ProgramStatus:
        status = self.client.ask(p.GetStatus()).status
        return next(x for x in status.programs if x.name == name)


@pytest.fixture(scope="module")
def bench(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Bench]:
    folder = tmp_path_factory.mktemp("dap") / "project"
    folder.mkdir()
    accounts = "".join(
        "\n" + user_entry(UserAccount(name, LEVELS[name], hash_password(password)))
        for name, password in PASSWORDS.items()
    )
    (folder / "padt.toml").write_text(PADT_TOML + accounts)
    (folder / "prog.st").write_text(SOURCE)
    (folder / "globals.st").write_text(GLOBALS)
    result = compile_project(load_project([folder]))
    assert result.artifact is not None, result.diagnostics
    state = folder.parent / "state"
    store_artifact(state, result.artifact)
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    # the bodies as Python: the tier's switch is the runtime tests' (test_breakpoints.py);
    # here no C compiler runs beside the tests on a loaded machine
    with running_resource(RESOURCE, state, endpoint, "--no-native-code") as (_, client):
        client.login("engineer", PASSWORDS["engineer"])
        bench = Bench(folder, endpoint, client)
        wait_for(lambda: bench.program("Main").cycles > 0, "Main runs")
        yield bench


def wait_for(condition: Callable[[], bool], what: str) -> None:
    deadline = time.monotonic() + WAIT_S
    while not condition():
        assert time.monotonic() < deadline, f"not in {WAIT_S} s: {what}"
        time.sleep(0.05)


# ---- a DAP client, as small as the protocol allows


def frame(message: dict[str, Any] | bytes) -> bytes:
    body = message if isinstance(message, bytes) else json.dumps(message).encode()
    return b"Content-Length: %d\r\n\r\n" % len(body) + body


def read_frames(stream: IO[bytes], into: queue.Queue[dict[str, Any] | None]) -> None:
    """Every message of `stream` into `into`, None at its end; anything on the stream that
    is not a framed message fails the test (nothing else may be written to stdout)."""
    while True:
        header = stream.readline()
        if not header:
            into.put(None)
            return
        assert header.startswith(b"Content-Length: "), header
        length = int(header.split(b":")[1])
        assert stream.readline() == b"\r\n"
        into.put(json.loads(stream.read(length)))


class DapClient:
    def __init__(
        self,
        reading: IO[bytes],
        writing: IO[bytes],
        process: subprocess.Popen[bytes] | None = None,
    ) -> None:
        self.process = process
        self._writing = writing
        self._arrived: queue.Queue[dict[str, Any] | None] = queue.Queue()
        self._seq = 0
        self.events: list[dict[str, Any]] = []
        threading.Thread(target=read_frames, args=(reading, self._arrived), daemon=True).start()

    def send(self, data: bytes) -> None:
        self._writing.write(data)
        self._writing.flush()

    def request(self, command: str, **arguments: Any) -> dict[str, Any]:
        self._seq += 1
        self.send(frame({"seq": self._seq, "type": "request", "command": command, **arguments}))
        return self.response(self._seq)

    def ask(self, command: str, **arguments: Any) -> dict[str, Any]:
        """A request that must succeed: its body."""
        answer = self.request(command, arguments=arguments)
        assert answer["success"], answer
        body: dict[str, Any] = answer.get("body", {})
        return body

    def response(self, seq: int) -> dict[str, Any]:
        while True:
            message = self._next()
            if message["type"] == "response" and message["request_seq"] == seq:
                return message
            assert message["type"] == "event", message
            self.events.append(message)

    def event(self, name: str, check: Callable[[dict[str, Any]], bool] = lambda body: True) -> Any:
        """The first event `name` (since the last taken) whose body passes `check`."""
        while True:
            for index, message in enumerate(self.events):
                if message["event"] == name and check(message.get("body", {})):
                    del self.events[: index + 1]
                    return message.get("body", {})
            message = self._next()
            assert message["type"] == "event", message
            self.events.append(message)

    def _next(self) -> dict[str, Any]:
        try:
            message = self._arrived.get(timeout=WAIT_S)
        except queue.Empty:
            raise AssertionError(f"padt dap said nothing for {WAIT_S} s") from None
        assert message is not None, "padt dap ended"
        return message


def padt_dap(*options: str, password: str) -> subprocess.Popen[bytes]:
    return subprocess.Popen(
        [sys.executable, "-m", "padt.cli", "dap", *options],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=subprocess.DEVNULL,
        cwd=REPO,
        env={**os.environ, "PADT_PASSWORD": password},
    )


@pytest.fixture
def dap() -> Iterator[Callable[[], DapClient]]:
    """`padt dap` on stdio with the engineer's password: its client, the process ended
    afterwards."""
    started: list[subprocess.Popen[bytes]] = []

    def start() -> DapClient:
        process = padt_dap(password=PASSWORDS["engineer"])
        started.append(process)
        assert process.stdout is not None and process.stdin is not None
        return DapClient(process.stdout, process.stdin, process)

    yield start
    for process in started:
        assert process.stdin is not None
        process.stdin.close()
        try:
            process.wait(timeout=WAIT_S)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait()


def attached(client: DapClient, bench: Bench, user: str = "engineer") -> dict[str, Any]:
    capabilities = client.ask("initialize", adapterID="padt", linesStartAt1=True)
    arguments = {
        "resource": RESOURCE,
        "zenoh": bench.endpoint,
        "user": user,
        "project": str(bench.project),
    }
    answer = client.request("attach", arguments=arguments)
    if answer["success"]:
        client.event("initialized")
    return {"capabilities": capabilities, "attach": answer}


def stopped_at(client: DapClient) -> tuple[dict[str, Any], list[dict[str, Any]]]:
    """The next stop and the stack it shows."""
    stop = client.event("stopped")
    frames = client.ask("stackTrace", threadId=stop["threadId"])["stackFrames"]
    return stop, frames


def variables(client: DapClient, reference: int) -> dict[str, dict[str, Any]]:
    return {
        v["name"]: v for v in client.ask("variables", variablesReference=reference)["variables"]
    }


def locals_of(client: DapClient, frame_id: int) -> dict[str, dict[str, Any]]:
    scopes = client.ask("scopes", frameId=frame_id)["scopes"]
    assert [s["name"] for s in scopes] == ["Locals", "Globals"]
    return variables(client, scopes[0]["variablesReference"])


def scope_of(client: DapClient, frame_id: int) -> int:
    reference: int = client.ask("scopes", frameId=frame_id)["scopes"][0]["variablesReference"]
    return reference


def runs_on_after_disconnect(client: DapClient, bench: Bench) -> None:
    """The client's breakpoints go with it: the program never stays stopped."""
    client.ask("disconnect")
    wait_for(lambda: bench.program("Main").state == p.ProgramState.RUN, "Main runs again")
    assert client.process is not None and client.process.wait(WAIT_S) == 0
    assert bench.client.ask(p.DebugGet()).debug.breakpoints == []


# ---- the tests


def test_a_conditional_breakpoint_stops_one_program_and_shows_its_stack_and_variables(
    bench: Bench, dap: Callable[[], DapClient]
) -> None:
    client = dap()
    capabilities = attached(client, bench)["capabilities"]
    assert capabilities["supportsConditionalBreakpoints"] is True
    assert capabilities["supportsLogPoints"] is True
    assert capabilities["supportsTerminateRequest"] is False
    # in the FB's body, only for the instance called with step := 2 (Main.b)
    armed = client.ask(
        "setBreakpoints",
        source={"path": bench.source},
        breakpoints=[{"line": 17, "condition": "step = 2"}, {"line": 900}],
    )["breakpoints"]
    assert [(b["verified"], b["line"]) for b in armed] == [(True, 17), (False, 900)]
    assert "no statement at or after line 900" in armed[1]["message"]
    client.ask("configurationDone")

    stop, frames = stopped_at(client)
    assert stop["reason"] == "breakpoint" and stop["threadId"] == 1
    assert stop["allThreadsStopped"] is False and stop["hitBreakpointIds"] == [armed[0]["id"]]
    assert [(f["name"], f["line"], f["source"]["path"]) for f in frames] == [
        ("Counter (Main.b)", 17, bench.source),
        ("Main", 29, bench.source),
    ]
    threads = client.ask("threads")["threads"]
    assert threads == [{"id": 1, "name": "Main"}, {"id": 2, "name": "Other"}]
    # pausing stops the program, not the world
    assert bench.program("Main").state == p.ProgramState.BKPT
    ticks = bench.program("Other").cycles
    wait_for(lambda: bench.program("Other").cycles > ticks + 5, "Other runs on")

    inner = locals_of(client, frames[0]["id"])
    assert (inner["step"]["value"], inner["step"]["type"]) == ("2", "INT")
    outer = locals_of(client, frames[1]["id"])
    assert outer["a"]["variablesReference"] > 0 and outer["i"]["variablesReference"] == 0
    members = variables(client, outer["a"]["variablesReference"])
    assert members["step"]["value"] == "1" and members["step"]["evaluateName"] == "a.step"
    hover = client.ask("evaluate", expression="a.step", frameId=frames[1]["id"], context="hover")
    assert hover["result"] == "1"
    missing = client.request(
        "evaluate", arguments={"expression": "nope", "frameId": frames[1]["id"]}
    )
    assert not missing["success"] and "no variable 'nope'" in missing["message"]
    # a write at a break, as an online write
    a_members = outer["a"]["variablesReference"]
    written = client.ask("setVariable", variablesReference=a_members, name="total", value="500")
    assert written["value"] == "500"
    assert client.ask("evaluate", expression="a.total", frameId=frames[1]["id"])["result"] == "500"
    wrong = client.request(
        "setVariable", arguments={"variablesReference": a_members, "name": "step", "value": "x"}
    )
    assert not wrong["success"] and "not an ST literal of type INT" in wrong["message"]
    # the resource's globals beside each frame's locals
    scopes = client.ask("scopes", frameId=frames[0]["id"])["scopes"]
    shared = variables(client, scopes[1]["variablesReference"])
    assert sorted(shared) == ["limit", "spot"] and shared["limit"]["value"] == "7"
    spot = variables(client, shared["spot"]["variablesReference"])
    assert {name: v["value"] for name, v in spot.items()} == {"x": "0", "y": "0"}
    assert spot["x"]["evaluateName"] == "spot.x"
    changed = client.ask(
        "setVariable", variablesReference=scopes[1]["variablesReference"], name="limit", value="9"
    )
    assert changed["value"] == "9"
    assert client.ask("evaluate", expression="limit", frameId=frames[0]["id"])["result"] == "9"
    paused = client.request("pause", arguments={"threadId": 1})
    assert not paused["success"] and "not supported" in paused["message"]

    # a breakpoint in the FUNCTION the FB calls next (asked at line 6, it stands at 10)
    armed = client.ask(
        "setBreakpoints",
        source={"path": bench.source},
        breakpoints=[{"line": 17, "condition": "step = 2"}, {"line": 6}],
    )["breakpoints"]
    assert [(b["verified"], b["line"]) for b in armed] == [(True, 17), (True, 10)]
    client.ask("continue", threadId=1)
    stop, frames = stopped_at(client)
    assert [(f["name"], f["line"]) for f in frames] == [
        ("Twice", 10),
        ("Counter (Main.b)", 18),
        ("Main", 29),
    ]
    caller = locals_of(client, frames[1]["id"])
    assert locals_of(client, frames[0]["id"])["x"]["value"] == caller["total"]["value"]
    refused = client.request(
        "setVariable",
        arguments={
            "variablesReference": scope_of(client, frames[0]["id"]),
            "name": "tmp",
            "value": "1",
        },
    )
    assert not refused["success"] and "a local of a function" in refused["message"]
    # another client (here the test's) lets it run on: the debugger is told, then of the
    # next stop
    bench.client.ask(p.DebugContinue("Main"))
    assert client.event("continued") == {"threadId": 1, "allThreadsContinued": False}
    stop, frames = stopped_at(client)  # in Twice again, called by a in the next cycle
    assert stop["reason"] == "breakpoint"
    assert [(f["name"], f["line"]) for f in frames][:2] == [("Twice", 10), ("Counter (Main.a)", 18)]
    # the debugger ends the adapter without a word (as VS Code does when it gives up on
    # it): the program must not stay stopped
    assert client.process is not None
    client.process.terminate()
    assert client.process.wait(WAIT_S) == 0
    wait_for(lambda: bench.program("Main").state == p.ProgramState.RUN, "Main runs again")
    assert bench.client.ask(p.DebugGet()).debug.breakpoints == []


def test_steps_into_a_method_through_an_interface_and_out_and_a_logpoint_logs(
    bench: Bench, dap: Callable[[], DapClient]
) -> None:
    client = dap()
    attached(client, bench)
    source = {"path": bench.source}
    client.ask("setBreakpoints", source=source, breakpoints=[{"line": 31}])  # n := c.Bump(...)
    client.ask("configurationDone")
    stop, frames = stopped_at(client)
    assert (frames[0]["name"], frames[0]["line"]) == ("Main", 31)

    client.ask("stepIn", threadId=1)
    stop, frames = stopped_at(client)
    assert stop["reason"] == "step" and stop["threadId"] == 1
    assert (frames[0]["name"], frames[0]["line"]) == ("Counter.BUMP (Main.a)", 21)
    assert locals_of(client, frames[0]["id"])["by"]["value"] == "3"
    client.ask("next", threadId=1)
    stop, frames = stopped_at(client)
    assert (frames[0]["name"], frames[0]["line"]) == ("Counter.BUMP (Main.a)", 22)
    client.ask("stepOut", threadId=1)
    stop, frames = stopped_at(client)
    assert [(f["name"], f["line"]) for f in frames] == [("Main", 32)]  # the FOR is next
    # out of the program itself: to the end of its cycle, where its variables still show
    client.ask("stepOut", threadId=1)
    stop, frames = stopped_at(client)
    assert stop["reason"] == "step" and "end of its program cycle" in stop["description"]
    assert [(f["name"], f["line"]) for f in frames] == [("Main (end of the program cycle)", 0)]
    assert locals_of(client, frames[0]["id"])["i"]["value"] == "4"  # the FOR ran out
    client.ask("next", threadId=1)  # the first statement of the next cycle
    stop, frames = stopped_at(client)
    assert [(f["name"], f["line"]) for f in frames] == [("Main", 28)]

    # a hit count: from the second pass on (the FOR's i = 2)
    client.ask("setBreakpoints", source=source, breakpoints=[{"line": 33, "hitCondition": "2"}])
    client.ask("continue", threadId=1)
    stop, frames = stopped_at(client)
    assert stop["reason"] == "breakpoint" and frames[0]["line"] == 33
    assert locals_of(client, frames[0]["id"])["i"]["value"] == "2"

    # a logpoint records without stopping: its lines in the debug console
    logpoint = {"line": 33, "logMessage": "i is {i}, twice n is {n * 2}"}
    client.ask("setBreakpoints", source=source, breakpoints=[logpoint])
    client.ask("continue", threadId=1)
    logged = client.event("output", lambda body: "prog.st:33 in Main: i = " in body["output"])
    assert logged["category"] == "console" and "n * 2 = " in logged["output"]
    assert (logged["source"]["path"], logged["line"]) == (bench.source, 33)
    assert bench.program("Main").state == p.ProgramState.RUN
    assert not [e for e in client.events if e["event"] == "stopped"]
    runs_on_after_disconnect(client, bench)


def test_a_malformed_message_gets_an_error_response_and_the_adapter_goes_on(
    bench: Bench, dap: Callable[[], DapClient]
) -> None:
    client = dap()

    def refused(data: bytes, seq: int = 0) -> str:
        client.send(data)
        answer = client.response(seq)
        assert answer["success"] is False, answer
        message: str = answer["message"]
        return message

    assert "no JSON" in refused(b"Content-Length: 5\r\n\r\nhello")
    assert "no JSON object" in refused(frame(b"[1, 2]"))
    assert "no Content-Length" in refused(b"Content-Type: text/plain\r\n\r\n")
    assert "is no number" in refused(b"Content-Length: many\r\n\r\n")
    assert "between 0 and" in refused(b"Content-Length: 999999999999\r\n\r\n")
    bad_arguments = {"seq": 7, "type": "request", "command": "next", "arguments": "x"}
    assert "`arguments` is no JSON object" in refused(frame(bad_arguments), 7)
    assert (
        "`threadId`: a number" in client.request("next", arguments={"threadId": "one"})["message"]
    )
    assert "not attached" in client.request("stackTrace", arguments={"threadId": 1})["message"]
    assert "does not support" in client.request("frobnicate")["message"]
    wrong = {"resource": "no such name!", "project": str(bench.project)}
    assert "resource:" in client.request("attach", arguments=wrong)["message"]
    nowhere = {"resource": RESOURCE, "project": str(bench.project / "missing")}
    assert "is no folder" in client.request("attach", arguments=nowhere)["message"]
    # and it still serves
    shown = attached(client, bench)
    assert shown["attach"]["success"], shown
    answer = client.request(
        "setBreakpoints",
        arguments={
            "source": {"path": str(bench.project.parent / "elsewhere.st")},
            "breakpoints": [{"line": 1}, {"line": 33, "hitCondition": "every 3rd"}],
        },
    )
    assert [b["verified"] for b in answer["body"]["breakpoints"]] == [False, False]
    assert "no file of the project" in answer["body"]["breakpoints"][0]["message"]
    mixed = client.ask(
        "setBreakpoints",
        source={"path": bench.source},
        breakpoints=[
            {"line": 33, "hitCondition": "== 3"},
            {"line": 33, "condition": "i >"},
            {"line": 33, "hitCondition": "> 4"},
        ],
    )["breakpoints"]
    assert "write N or >= N" in mixed[0]["message"]
    assert (mixed[1]["verified"], mixed[1]["message"]) == (False, "'i >': more expected")
    assert mixed[2]["verified"]
    armed = bench.client.ask(p.DebugGet()).debug.breakpoints
    assert [b.spec.hit_count for b in armed] == [None, 5]  # "> 4": from the fifth pass on
    runs_on_after_disconnect(client, bench)


def test_on_a_tcp_port_clients_come_one_after_the_other_and_a_viewer_may_not_debug(
    bench: Bench,
) -> None:
    port = free_port()
    process = padt_dap("--port", str(port), password=PASSWORDS["viewer"])
    try:
        for user in ("viewer", "viewer"):  # a second client once the first has gone
            with connected(port) as connection:
                reading, writing = connection.makefile("rb"), connection.makefile("wb")
                client = DapClient(reading, writing)
                answer = attached(client, bench, user)["attach"]
                assert not answer["success"]
                assert "refused (forbidden): viewer (read) may not" in answer["message"]
                client.ask("disconnect")
    finally:
        process.terminate()
    assert process.wait(WAIT_S) == 0


def test_on_a_tcp_port_sigterm_ends_it_and_the_client_s_program_runs_on(bench: Bench) -> None:
    """SIGTERM while a client's program stands at its breakpoint and the adapter waits for
    the client's next request: it ends with 0 and clears the client's breakpoints."""
    port = free_port()
    process = padt_dap("--port", str(port), password=PASSWORDS["engineer"])
    try:
        with connected(port) as connection:
            reading, writing = connection.makefile("rb"), connection.makefile("wb")
            client = DapClient(reading, writing)
            attached(client, bench)
            client.ask("setBreakpoints", source={"path": bench.source}, breakpoints=[{"line": 31}])
            client.ask("configurationDone")
            stopped_at(client)
            assert bench.program("Main").state == p.ProgramState.BKPT
            process.terminate()
            assert process.wait(WAIT_S) == 0
    finally:
        process.kill()
    wait_for(lambda: bench.program("Main").state == p.ProgramState.RUN, "Main runs again")
    assert bench.client.ask(p.DebugGet()).debug.breakpoints == []


def connected(port: int) -> socket.socket:
    """A connection to `padt dap --port`, once it listens."""
    deadline = time.monotonic() + WAIT_S
    while True:
        try:
            return socket.create_connection(("127.0.0.1", port))
        except ConnectionRefusedError:
            assert time.monotonic() < deadline, f"padt dap does not listen on {port}"
            time.sleep(0.1)


def test_the_client_is_told_when_the_resource_goes_away(
    tmp_path: Path, dap: Callable[[], DapClient]
) -> None:
    project = tmp_path / "project"
    project.mkdir()
    (project / "padt.toml").write_text(PADT_TOML.replace('"Bench"', '"Gone"'))
    (project / "prog.st").write_text(SOURCE)
    result = compile_project(load_project([project]))
    assert result.artifact is not None, result.diagnostics
    store_artifact(tmp_path / "state", result.artifact)
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    with running_resource("Gone", tmp_path / "state", endpoint, "--no-native-code") as (
        process,
        _,
    ):
        client = dap()
        client.ask("initialize", adapterID="padt")
        client.ask("attach", resource="Gone", zenoh=endpoint, project=str(project))
        client.event("initialized")
        process.terminate()  # the runtime stops: its liveliness token goes
        process.wait(WAIT_S)
        gone = client.event("output", lambda body: body["category"] == "important")
        assert gone["output"] == "resource Gone is gone\n"
        client.event("terminated")
        client.ask("disconnect")  # its breakpoints cannot be cleared: it still ends
        assert client.process is not None and client.process.wait(WAIT_S) == 0
